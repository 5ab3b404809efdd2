"""The joints of a world's loaded models: what the engine reports, the target mode each
holds, and the checks every joint request passes before the engine sees it.

Joint states and targets address joints with one degree of freedom (revolute,
prismatic); a spherical or free joint's state is its child link's pose (get_states), and a
fixed joint has none. Every check runs before anything is applied, so a rejected request
changes nothing.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from galton.daemon.engines.base import (
    FEATURE_TARGET_EFFORT,
    FEATURE_TARGET_POSITION,
    FEATURE_TARGET_VELOCITY,
    Engine,
)
from galton.protocol import (
    FeatureUnsupportedError,
    InvalidArgumentError,
    JointInfo,
)
from galton.protocol.errors import unknown_names
from galton.protocol.vocabulary import MAX_GAIN

MODE_FEATURES = {"position": FEATURE_TARGET_POSITION, "velocity": FEATURE_TARGET_VELOCITY,
                 "effort": FEATURE_TARGET_EFFORT}
LIMIT_SLACK = 1e-9  # a position at a limit, give or take rounding, is within it


class JointTable:
    """Joints by name, refreshed from the engine whenever models come or go."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self.by_name: dict[str, JointInfo] = {}

    def refresh(self) -> None:
        """Read the engine's joints again, keeping the modes this table knows of."""
        modes = {name: info.mode for name, info in self.by_name.items()}
        self.by_name = {j.name: dataclasses.replace(j, mode=modes.get(j.name, j.mode))
                        for j in self.engine.joints()}

    def select(self, model: str | None = None,
               names: Sequence[str] | None = None) -> list[JointInfo]:
        """These joints (all when None), of one model when ``model`` is given."""
        infos = self.require(names) if names is not None else list(self.by_name.values())
        return [j for j in infos if model is None or j.model == model]

    def require(self, names: Sequence[str]) -> list[JointInfo]:
        """The joints of these names, or NotFound naming the first unknown one."""
        missing = [n for n in names if n not in self.by_name]
        if missing:
            raise unknown_names("joint", missing, self.by_name)
        return [self.by_name[n] for n in names]

    def require_scalar(self, names: Sequence[str], where: str) -> list[JointInfo]:
        """Known joints with one degree of freedom (what states and targets address)."""
        infos = self.require(names)
        for info in infos:
            if not info.scalar:
                raise InvalidArgumentError(
                    f"{where}: joint {info.name!r} is {info.type}: " + _why_not_scalar(info))
        return infos

    def scalar_names(self) -> list[str]:
        return [name for name, info in self.by_name.items() if info.scalar]

    def check_limits(self, infos: Sequence[JointInfo], positions: np.ndarray,
                     where: str) -> None:
        """Refuse a position outside a joint's limits (the engines would push it back)."""
        for info, value in zip(infos, positions.tolist(), strict=True):
            low = -np.inf if info.lower is None else info.lower - LIMIT_SLACK
            high = np.inf if info.upper is None else info.upper + LIMIT_SLACK
            if not low <= value <= high:
                raise InvalidArgumentError(
                    f"{where}: {value:g} is outside joint {info.name!r}'s limits "
                    f"[{_bound(info.lower, '-inf')}, {_bound(info.upper, 'inf')}]",
                    {"joint": info.name, "lower": info.lower, "upper": info.upper})

    def set_targets(self, names: Sequence[str], mode: str, targets: np.ndarray,
                    kp: np.ndarray, kd: np.ndarray, max_effort: np.ndarray) -> None:
        """Check a target request whole, then hand it to the engine and note the mode."""
        infos = self.require_scalar(names, "set_joint_targets")
        feature = MODE_FEATURES.get(mode)
        if feature is not None and feature not in self.engine.capabilities().features:
            raise FeatureUnsupportedError(
                f"the {self.engine.name} engine cannot hold {mode} targets")
        _check_gains(mode, kp, kd, max_effort)
        if mode == "position":
            self.check_limits(infos, targets, "set_joint_targets.targets")
        self.engine.set_joint_targets(names, mode, targets, kp, kd, max_effort)
        for name in names:
            self.by_name[name] = dataclasses.replace(self.by_name[name], mode=mode)

    def set_damping(self, names: Sequence[str], damping: np.ndarray, where: str) -> None:
        """Check whole (known 1-DOF joints, 0 <= damping <= MAX_GAIN), then have the engine
        set each joint's own damping and read the joints again."""
        self.require_scalar(names, where)
        if not np.all((damping >= 0) & (damping <= MAX_GAIN)):
            bad = float(damping[np.argmax(~((damping >= 0) & (damping <= MAX_GAIN)))])
            raise InvalidArgumentError(f"{where}: a joint's damping must be within "
                                       f"[0, {MAX_GAIN:g}], got {bad:g}")
        self.engine.set_joint_damping(names, damping)
        self.refresh()

    def release_all(self) -> None:
        """Every joint's mode back to none (the engine has restored its joints)."""
        self.by_name = {n: dataclasses.replace(j, mode="none") for n, j in self.by_name.items()}


def _bound(value: float | None, none: str) -> str:
    return none if value is None else f"{value:g}"


def _why_not_scalar(info: JointInfo) -> str:
    if info.type == "fixed":
        return "it has no degree of freedom to read or drive"
    return (f"joint states and targets address one-degree-of-freedom joints; read or set "
            f"its child link {info.child!r} with get_states / set_states")


def _check_gains(mode: str, kp: np.ndarray, kd: np.ndarray, max_effort: np.ndarray) -> None:
    for name, values in (("kp", kp), ("kd", kd)):
        if (values < 0).any():
            raise InvalidArgumentError(f"set_joint_targets.{name} must be >= 0, got "
                                       f"{float(values[np.argmax(values < 0)]):g}")
    if (max_effort <= 0).any():
        raise InvalidArgumentError("set_joint_targets.max_effort must be > 0 (inf: no limit), "
                                   f"got {float(max_effort[np.argmax(max_effort <= 0)]):g}")
    if mode == "position" and (kp <= 0).any():
        raise InvalidArgumentError("a position target needs kp > 0 (N·m/rad or N/m)")
    if mode == "velocity" and (kd <= 0).any():
        raise InvalidArgumentError("a velocity target needs kd > 0 (N·m·s/rad or N·s/m)")
