"""The DART engine (``--engine dart``), configured as Gazebo Harmonic's gz-physics
``dartsim`` plugin configures DART: engine.py holds the class, the other modules its parts."""
