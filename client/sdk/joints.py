"""The requests of the joint, wrench and state operations, built from numpy arrays or scalars
as their declared types (``galton.protocol.requests``).

The ``Client`` methods (``galton.client.sdk.client``) send what these functions build: per-joint
values and rows go on the wire as packed float64 bins (docs/protocol.md, "set_joint_targets",
"apply_wrench"). A scalar stands for the same value on every name and a single row for the
same row on every body. Values that are no numbers, or rows of the wrong width, raise
``InvalidArgumentError`` here; types and declared ranges are checked as the daemon checks
them when the request is sent (``Client._send``); everything else (counts, NaN, limits,
unknown names) the daemon judges, so its checks stay the one source of truth.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from galton.protocol import (
    POSE_WIDTH,
    TWIST_WIDTH,
    WRENCH_WIDTH,
    InvalidArgumentError,
    pack_f64,
)
from galton.protocol import requests as rq
from galton.protocol.vocabulary import TargetMode

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


def load_model_request(fmt: str, text: str | None, path: str | os.PathLike[str] | None,
                       prefix: str, fixed_base: bool | None,
                       search_path: SearchPath | None) -> rq.LoadModel:
    """``fixed_base`` None: the daemon's default (True)."""
    return rq.LoadModel(
        format=fmt, prefix=prefix, text=text, path=None if path is None else os.fspath(path),
        search_path=None if search_path is None else search_path_arg(search_path),
        **given(fixed_base=fixed_base))


def names_or_all(names: Sequence[str] | None) -> rq.NamesOrAll:
    """These names, or every one (every joint, every wrench) when None."""
    return rq.NamesOrAll(names=None if names is None else list(names))


def set_joint_states_request(names: Sequence[str], positions: ArrayLike,
                             velocities: ArrayLike | None,
                             read: Sequence[str] | None = None) -> rq.SetJointStates:
    count = len(names)
    return rq.SetJointStates(
        names=list(names), positions=joint_values(positions, count, "positions"),
        velocities=None if velocities is None else joint_values(velocities, count,
                                                                 "velocities"),
        read=None if read is None else list(read))


def set_joint_targets_request(names: Sequence[str], mode: str,
                              targets: ArrayLike | None = None, kp: ArrayLike | None = None,
                              kd: ArrayLike | None = None,
                              max_effort: ArrayLike | None = None) -> rq.SetJointTargets:
    """Absent gains are left to the daemon's defaults (kp, kd 0; max_effort infinite);
    ``mode`` is held to its choices when the request is sent (``Client._send``)."""
    count = len(names)

    def values(value: ArrayLike | None, key: str) -> bytes | None:
        return None if value is None else joint_values(value, count, key)
    return rq.SetJointTargets(names=list(names), mode=cast(TargetMode, mode),
                              targets=values(targets, "targets"), kp=values(kp, "kp"),
                              kd=values(kd, "kd"), max_effort=values(max_effort, "max_effort"))


def set_states_request(names: Sequence[str], poses: ArrayLike | None = None,
                       twists: ArrayLike | None = None) -> rq.SetStates:
    """A ``set_states`` request (rows of 7 and 6; one row for every body)."""
    count = len(names)
    return rq.SetStates(
        names=list(names),
        poses=None if poses is None else body_rows(poses, count, POSE_WIDTH,
                                                   "set_states.poses"),
        twists=None if twists is None else body_rows(twists, count, TWIST_WIDTH,
                                                     "set_states.twists"))


def apply_wrench_request(names: Sequence[str], wrenches: ArrayLike,
                         points: ArrayLike | None = None,
                         duration: float | None = None) -> rq.ApplyWrench:
    """Wrenches are rows fx fy fz tx ty tz (N, N·m), points rows x y z: world frame."""
    count = len(names)
    return rq.ApplyWrench(
        names=list(names), wrenches=body_rows(wrenches, count, WRENCH_WIDTH, "wrenches"),
        points=None if points is None else body_rows(points, count, POINT_WIDTH, "points"),
        duration=None if duration is None else float(duration))


def step_request(count: int, names: Sequence[str] | None,
                 joints: Sequence[str] | None) -> rq.Step:
    """A ``step`` that reads bodies (``read``) and/or joints (``read_joints``) after it."""
    return rq.Step(count=count, read=None if names is None else list(names),
                   read_joints=None if joints is None else list(joints))
