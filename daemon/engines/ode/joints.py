"""Loaded robots' joints: ODE hinge and slider joints, the targets held on them, and the
rewind to the as-loaded state."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from galton.daemon.engines.ode.spawn import Body
from galton.protocol import FeatureUnsupportedError, JointInfo


@dataclass
class Robots:
    """Every loaded model's links and joints (none until URDF loading lands)."""

    models: dict[str, list[str]] = field(default_factory=dict)  # root -> its links
    links: set[str] = field(default_factory=set)

    def busy(self) -> bool:
        return False

    def actuate(self) -> None:
        """Apply every held target for the coming step."""

    def infos(self) -> list[JointInfo]:
        return []

    def links_of(self, root: str, bodies: dict[str, Body]) -> list[Body]:
        return [bodies[n] for n in self.models.get(root, []) if n in bodies]

    def model_mass(self, root: str, bodies: dict[str, Body]) -> float:
        return float(sum(b.mass for b in self.links_of(root, bodies)))

    def forget(self, root: str) -> None:
        for name in self.models.pop(root, []):
            self.links.discard(name)

    def destroy(self) -> None:
        self.models.clear()
        self.links.clear()

    def states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        raise FeatureUnsupportedError("the ode engine holds no joints")

    def teleport(self, names: Sequence[str], positions: np.ndarray,
                 velocities: np.ndarray | None, bodies: dict[str, Body]) -> None:
        raise FeatureUnsupportedError("the ode engine holds no joints")

    def hold(self, names: Sequence[str], mode: str, targets: np.ndarray, kp: np.ndarray,
             kd: np.ndarray, max_effort: np.ndarray, bodies: dict[str, Body]) -> None:
        raise FeatureUnsupportedError("the ode engine holds no joints")

    def rewind(self, bodies: dict[str, Body]) -> None:
        """Nothing to rewind without joints."""
