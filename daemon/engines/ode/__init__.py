"""The ODE engine (Open Dynamics Engine, Debian's libode8 through ctypes), configured as
Webots configures its own fork of ODE. ``engine.OdeEngine`` is the engine; the other modules
are its parts."""
