"""The engines a daemon can host, imported only when asked for."""

from __future__ import annotations

import importlib

from galton.daemon.engines.base import Engine, native_output_silenced
from galton.protocol import FeatureUnsupportedError, InvalidArgumentError
from galton.protocol.errors import did_you_mean

ENGINE_CLASSES: dict[str, str] = {
    "mujoco": "galton.daemon.engines.mujoco.engine:MujocoEngine",
    "pybullet": "galton.daemon.engines.pybullet.engine:PybulletEngine",
    "ode": "galton.daemon.engines.ode.engine:OdeEngine",
    "dart": "galton.daemon.engines.dart.engine:DartEngine",
}


def create_engine(name: str) -> Engine:
    """A fresh, empty engine of that name."""
    target = ENGINE_CLASSES.get(name)
    if target is None:
        raise InvalidArgumentError(
            f"unknown engine {name!r}{did_you_mean(name, ENGINE_CLASSES)}; "
            f"available: {', '.join(ENGINE_CLASSES)}")
    module_name, class_name = target.split(":")
    try:
        with native_output_silenced():  # PyBullet prints its build time when imported
            module = importlib.import_module(module_name)
    except ImportError as exc:
        raise FeatureUnsupportedError(f"the {name} engine is not installed here: {exc}") from exc
    engine_class: type[Engine] = getattr(module, class_name)
    return engine_class()
