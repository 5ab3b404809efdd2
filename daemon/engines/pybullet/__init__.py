"""The PyBullet engine (``--engine pybullet``): a headless Bullet world (engine.py)."""
