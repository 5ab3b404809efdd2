"""The wire arguments of the joint and wrench operations, built from numpy arrays or scalars.

The ``Client`` methods (``galton.client.sdk.client``) send what these functions build: per-joint
values and rows go on the wire as packed float64 bins (docs/protocol.md, "set_joint_targets",
"apply_wrench"). A scalar stands for the same value on every name and a single row for the
same row on every body. Values that are no numbers, or rows of the wrong width, raise
``InvalidArgumentError`` here, before any request; everything else (counts, NaN, limits,
unknown names) the daemon judges, so its checks stay the one source of truth.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from galton.protocol import (
    POSE_WIDTH,
    TWIST_WIDTH,
    WRENCH_WIDTH,
    InvalidArgumentError,
    pack_f64,
)

POINT_WIDTH = 3  # x y z, world frame
SearchPath = str | os.PathLike[str] | Sequence[str | os.PathLike[str]]


def float_array(values: ArrayLike, where: str) -> np.ndarray:
    """``values`` as a float64 array, or InvalidArgumentError naming ``where``."""
    try:
        return np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidArgumentError(f"{where} must be numbers: {error}") from None


def joint_values(values: ArrayLike, count: int, where: str) -> bytes:
    """One value per joint, packed; a scalar is given to every joint."""
    array = float_array(values, where)
    if array.ndim == 0:
        array = np.full(count, float(array))
    return pack_f64(array.reshape(-1))


def body_rows(rows: ArrayLike, count: int, width: int, where: str) -> bytes:
    """One row of ``width`` numbers per body, packed; a single row is given to every body."""
    array = float_array(rows, where)
    if array.size % width or array.ndim > 2 or (array.ndim == 2 and array.shape[1] != width):
        raise InvalidArgumentError(f"{where} takes rows of {width} numbers, got an array of "
                                   f"shape {array.shape}")
    array = array.reshape(-1, width)
    if len(array) == 1 and count > 1:
        array = np.tile(array, (count, 1))
    return pack_f64(array)


def given(**values: Any) -> dict[str, Any]:
    """The arguments that were given: None means "leave it to the daemon's default"."""
    return {key: value for key, value in values.items() if value is not None}


def search_path_arg(search_path: SearchPath) -> str:
    """Folders joined by ':' as the wire wants; a str is taken as already joined."""
    if isinstance(search_path, str):
        return search_path
    if isinstance(search_path, os.PathLike):
        return os.fspath(search_path)
    return ":".join(str(Path(folder)) for folder in search_path)


def load_model_args(fmt: str, text: str | None, path: str | os.PathLike[str] | None,
                    prefix: str, fixed_base: bool | None,
                    search_path: SearchPath | None) -> dict[str, Any]:
    return {"format": fmt, "prefix": prefix, **given(
        text=text, path=None if path is None else os.fspath(path), fixed_base=fixed_base,
        search_path=None if search_path is None else search_path_arg(search_path))}


def joints_args(model: str | None, names: Sequence[str] | None) -> dict[str, Any]:
    return {**given(model=model), **names_arg(names)}


def names_arg(names: Sequence[str] | None) -> dict[str, Any]:
    """``{"names": [...]}``, or nothing (every joint, every wrench) when None."""
    return {} if names is None else {"names": list(names)}


def set_joint_states_args(names: Sequence[str], positions: ArrayLike,
                          velocities: ArrayLike | None) -> dict[str, Any]:
    count = len(names)
    args: dict[str, Any] = {"names": list(names),
                            "positions": joint_values(positions, count, "positions")}
    if velocities is not None:
        args["velocities"] = joint_values(velocities, count, "velocities")
    return args


def set_joint_targets_args(names: Sequence[str], mode: str, targets: ArrayLike | None = None,
                           kp: ArrayLike | None = None, kd: ArrayLike | None = None,
                           max_effort: ArrayLike | None = None) -> dict[str, Any]:
    """Absent gains are left to the daemon's defaults (kp, kd 0; max_effort infinite)."""
    count = len(names)
    args: dict[str, Any] = {"names": list(names), "mode": mode}
    given = {"targets": targets, "kp": kp, "kd": kd, "max_effort": max_effort}
    for key, values in given.items():
        if values is not None:
            args[key] = joint_values(values, count, key)
    return args


def set_states_args(names: Sequence[str], poses: ArrayLike | None = None,
                    twists: ArrayLike | None = None) -> dict[str, Any]:
    """A ``set_states`` request's arguments (rows of 7 and 6; one row for every body)."""
    count = len(names)
    args: dict[str, Any] = {"names": list(names)}
    if poses is not None:
        args["poses"] = body_rows(poses, count, POSE_WIDTH, "set_states.poses")
    if twists is not None:
        args["twists"] = body_rows(twists, count, TWIST_WIDTH, "set_states.twists")
    return args


def apply_wrench_args(names: Sequence[str], wrenches: ArrayLike,
                      points: ArrayLike | None = None,
                      duration: float | None = None) -> dict[str, Any]:
    """Wrenches are rows fx fy fz tx ty tz (N, N·m), points rows x y z: world frame."""
    count = len(names)
    args: dict[str, Any] = {"names": list(names),
                            "wrenches": body_rows(wrenches, count, WRENCH_WIDTH, "wrenches")}
    if points is not None:
        args["points"] = body_rows(points, count, POINT_WIDTH, "points")
    if duration is not None:
        args["duration"] = float(duration)
    return args


def step_args(count: int, names: Sequence[str] | None,
              joints: Sequence[str] | None) -> dict[str, Any]:
    """A ``step`` that reads bodies (``read``) and/or joints (``read_joints``) after it."""
    args: dict[str, Any] = {"count": count}
    if names is not None:
        args["read"] = list(names)
    if joints is not None:
        args["read_joints"] = list(joints)
    return args
