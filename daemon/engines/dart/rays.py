"""No ray casts on DART: dartpy exposes no ray query on the ODE collision detector, which
this engine collides with as gz-physics' dartsim plugin does.
``DartEngine`` leaves ``raycast`` to the base Engine, which refuses it with
FEATURE_UNSUPPORTED, so capabilities() leaves "raycast" out (engines/base.py derives it);
ray casts would live here."""

from galton.daemon.engines.base import FEATURE_RAYCAST

ABSENT = FEATURE_RAYCAST  # the feature this module would hold, which the engine lacks
