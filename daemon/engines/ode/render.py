"""No images from ODE: ODE has no renderer (Webots draws its worlds with its own, WREN), and
the daemon brings none for this engine. ``OdeEngine`` leaves ``render`` to the base Engine,
which refuses it with FEATURE_UNSUPPORTED, so capabilities() leaves "render" out
(engines/base.py derives it); a renderer would live here."""

from galton.daemon.engines.base import FEATURE_RENDER

ABSENT = FEATURE_RENDER  # the feature this module would hold, which the engine lacks
