"""URDF robots into ODE bodies and joints (not yet: no model format is offered)."""

from __future__ import annotations

from typing import Any

from galton.daemon.engines.ode.joints import Robots
from galton.daemon.engines.ode.spawn import Body
from galton.protocol import EntityInfo, FeatureUnsupportedError

MODEL_FORMATS: tuple[str, ...] = ()


def load_urdf(world: int, space: int, robots: Robots, text: str | None, path: str | None,
              prefix: str, fixed_base: bool, values: dict[str, Any], taken: set[str]
              ) -> tuple[list[Body], list[EntityInfo]]:
    raise FeatureUnsupportedError("the ode engine loads no models yet")
