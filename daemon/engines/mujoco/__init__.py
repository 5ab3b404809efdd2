"""The MuJoCo engine (``--engine mujoco``): a world built with ``mujoco.MjSpec`` (engine.py)."""
