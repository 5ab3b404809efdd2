"""The fuzzer's extreme-number cases (issue 46): every number a client can send that reaches
an engine, sent at the ends of float64 (1e308, a quaternion with a 1e155 component, a mass
of 1e-300), each in its own request on a world with a ball and a jointed arm.

Each must be refused with one typed reply and change nothing, the world must then step,
and the daemon must still serve: an accepted one is a finding too (a value past the
protocol's bounds, docs/protocol.md "Bounds", must never reach an engine).
``run_extremes`` runs them; tests/conformance/test_extremes.py runs them on every engine.
The extreme poses and twists (``extreme_poses``, ``extreme_twists``) are sent through the ROS
2 front too, as SpawnEntity's initial_pose and SetEntityState's state, on every engine
(tests/daemon/fronts/test_ros2_extremes.py).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import msgpack
import numpy as np

from galton.client.fuzz.campaign import look, send
from galton.client.sdk.client import Client
from galton.protocol import (
    PROTOCOL_VERSION,
    DaemonUnreachableError,
    GaltonError,
    ResultCode,
    decode_reply,
    pack_f64,
)

# A two-link arm with one revolute and one prismatic joint: every engine loads URDF.
ARM = ('<robot name="xarm"><link name="base"><inertial><mass value="1"/>'
       '<inertia ixx=".01" iyy=".01" izz=".01" ixy="0" ixz="0" iyz="0"/></inertial></link>'
       '<link name="upper"><inertial><mass value="0.5"/><inertia ixx=".001" iyy=".001" '
       'izz=".001" ixy="0" ixz="0" iyz="0"/></inertial></link>'
       '<link name="slide"><inertial><mass value="0.2"/><inertia ixx=".001" iyy=".001" '
       'izz=".001" ixy="0" ixz="0" iyz="0"/></inertial></link>'
       '<joint name="hinge" type="revolute"><parent link="base"/><child link="upper"/>'
       '<axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="100" velocity="10"/></joint>'
       '<joint name="rail" type="prismatic"><parent link="upper"/><child link="slide"/>'
       '<origin xyz="0 0 0.3"/><axis xyz="1 0 0"/>'
       '<limit lower="-1" upper="1" effort="100" velocity="10"/></joint></robot>')
HUGE = (1e308, -1e308, 1e200, 1e155)
TINY = (5e-324, 1e-300)
# Quaternions (qx qy qz qw) no engine may be handed: huge, zero, tiny.
Vector = tuple[float, float, float]
Quaternion = tuple[float, float, float, float]
BAD_QUATERNIONS: tuple[Quaternion, ...] = (
    (0.0, 1e308, 0.0, 1.0), (1e155, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0),
    (1e-200, 0.0, 0.0, 0.0), (0.0, 0.0, 1e20, 1.0))


@dataclass
class ExtremesReport:
    """What the extreme cases found; ``ok`` when nothing."""

    cases: int = 0
    codes: dict[str, int] = field(default_factory=dict)
    exits: int = 0  # cases after which the daemon no longer answered
    untyped: list[str] = field(default_factory=list)
    accepted: list[str] = field(default_factory=list)  # answered OK: reached an engine
    applied_after_refusal: list[str] = field(default_factory=list)
    broken_after: list[str] = field(default_factory=list)  # the world no longer steps

    @property
    def ok(self) -> bool:
        return not (self.exits or self.untyped or self.accepted
                    or self.applied_after_refusal or self.broken_after)

    def to_dict(self) -> dict[str, Any]:
        return {"cases": self.cases, "codes": self.codes, "exits": self.exits,
                "untyped": self.untyped[:10], "accepted": self.accepted[:10],
                "applied_after_refusal": self.applied_after_refusal[:10],
                "broken_after": self.broken_after[:10], "ok": self.ok}


def _pose(position: tuple[float, float, float] = (0.0, 0.0, 1.0),
          quaternion: tuple[float, ...] = (0.0, 0.0, 0.0, 1.0)) -> bytes:
    return pack_f64(np.array([[*position, *quaternion]]))


def _row(*values: float) -> bytes:
    return pack_f64(np.array([values], dtype=float))


def _sphere(**changes: Any) -> dict[str, Any]:
    group: dict[str, Any] = {"shape": "sphere", "size": [0.05], "names": ["xnew"],
                             "poses": _pose()}
    group.update(changes)
    return {"groups": [group]}


def extreme_poses() -> Iterator[tuple[Vector, Quaternion]]:
    """(position, quaternion qx qy qz qw) pairs no engine may be handed: each bad
    quaternion at a plain position, each huge position with the identity."""
    for quaternion in BAD_QUATERNIONS:
        yield (0.0, 0.0, 1.0), quaternion
    for huge in HUGE:
        yield (huge, 0.0, 1.0), (0.0, 0.0, 0.0, 1.0)


def extreme_twists() -> Iterator[tuple[float, float, float, float, float, float]]:
    """Twists (vx vy vz wx wy wz) past every bound: each huge value, linear and angular."""
    for huge in HUGE:
        yield huge, 0.0, 0.0, 0.0, 0.0, 0.0
        yield 0.0, 0.0, 0.0, 0.0, 0.0, huge


def pose_cases(op: str, base: dict[str, Any], key: str) -> Iterator[tuple[str, dict[str, Any]]]:
    """``base`` with its pose ``key`` at each extreme pose."""
    for position, quaternion in extreme_poses():
        yield op, {**base, key: _pose(position, quaternion)}


def cases(ball: str, joints: list[str]) -> Iterator[tuple[str, dict[str, Any]]]:
    """Every extreme case, as (operation, args): ``ball`` a free body, ``joints`` the arm's
    scalar joints."""
    for position, quaternion in extreme_poses():
        yield "spawn", _sphere(poses=_pose(position, quaternion))
    for huge in HUGE:
        yield "spawn", _sphere(twists=_row(huge, 0, 0, 0, 0, 0))
        yield "spawn", _sphere(twists=_row(0, 0, 0, 0, huge, 0))
        yield "spawn", _sphere(mass=huge)
        yield "spawn", _sphere(size=[huge])
    for tiny in TINY:
        yield "spawn", _sphere(mass=tiny)
        yield "spawn", _sphere(mass=1.0, inertia=[tiny, tiny, tiny])
    yield from pose_cases("set_states", {"names": [ball]}, "poses")
    yield from pose_cases("compare", {"names": [ball]}, "poses")
    for twist in extreme_twists():
        yield "set_states", {"names": [ball], "twists": _row(*twist)}
    for huge in HUGE:
        yield "apply_wrench", {"names": [ball], "wrenches": _row(huge, 0, 0, 0, 0, 0)}
        yield "apply_wrench", {"names": [ball], "wrenches": _row(0, 0, 0, 0, huge, 0)}
        yield "apply_wrench", {"names": [ball], "wrenches": _row(1, 0, 0, 0, 0, 0),
                               "points": _row(huge, 0, 0)}
        yield "raycast", {"origins": _row(huge, 0, 0), "directions": _row(0, 0, -1)}
        yield "update", {"names": [ball], "properties": {"mass": huge}}
        yield "set_joint_states", {"names": joints, "positions": huge}
        yield "set_joint_states", {"names": joints, "positions": 0.0, "velocities": huge}
        for mode in ("position", "velocity", "effort"):
            yield "set_joint_targets", {"names": joints, "mode": mode, "targets": huge}
        yield "set_joint_targets", {"names": joints, "mode": "position", "targets": 0.5,
                                    "kp": huge, "kd": 1.0}
        yield "set_joint_targets", {"names": joints, "mode": "position", "targets": 0.5,
                                    "kp": 10.0, "kd": huge}
        yield "set_joint_targets", {"names": joints, "mode": "effort", "targets": 1.0,
                                    "max_effort": huge}
        yield "predict", {"horizon": 0.01, "set_states": {
            "names": [ball], "poses": _pose(quaternion=(huge, 0.0, 0.0, 1.0))}}
        yield "predict", {"horizon": 0.01, "joint_targets": {
            "names": joints, "mode": "effort", "targets": huge}}
        yield "predict", {"horizon": 0.01, "wrenches": {
            "names": [ball], "wrenches": _row(0, 0, 0, huge, 0, 0)}}
    for tiny in TINY:
        yield "update", {"names": [ball], "properties": {"mass": tiny}}


def setup(client: Client) -> tuple[str, list[str]]:
    """A paused world with a ground, a ball and the arm; its ball and scalar joints."""
    client.call("reset", {"scope": "all"})
    client.call("pause")
    client.call("spawn", {"groups": [
        {"shape": "plane", "size": [5.0, 5.0], "names": ["xground"], "poses": _pose(
            position=(0.0, 0.0, 0.0)), "static": True},
        {"shape": "sphere", "size": [0.05], "names": ["xball"], "poses": _pose()}]})
    client.call("load_model", {"format": "urdf", "text": ARM, "prefix": "xarm_"})
    joints = [j["name"] for j in client.call("joints")["joints"]
              if j["type"] in ("revolute", "prismatic")]
    return "xball", joints


def run_extremes(client: Client, timeout: float = 30.0) -> ExtremesReport:
    """Send every case (``cases``) and check each as the module docstring says."""
    report = ExtremesReport()
    ball, joints = setup(client)
    for op, args in cases(ball, joints):
        report.cases += 1
        try:
            _one(client, report, op, args, timeout)
        except DaemonUnreachableError:  # it no longer answers: it exited (or hangs)
            report.exits += 1
            return report
    try:
        client.call("status")
    except DaemonUnreachableError:
        report.exits += 1
    return report


def _one(client: Client, report: ExtremesReport, op: str, args: dict[str, Any],
         timeout: float) -> None:
    label = f"{op} {_brief(args)}"
    before = look(client).digest
    payload = msgpack.packb({"v": PROTOCOL_VERSION, "op": op, "args": args},
                            use_bin_type=True)
    replies = send(client, op, payload, timeout)
    if len(replies) != 1:
        report.untyped.append(f"{label}: {len(replies)} replies")
        return
    try:
        code = decode_reply(replies[0]).code
    except GaltonError as error:
        report.untyped.append(f"{label}: {error}")
        return
    report.codes[code.name] = report.codes.get(code.name, 0) + 1
    if code == ResultCode.OK:
        report.accepted.append(label)
        setup(client)
    elif look(client).digest != before:
        report.applied_after_refusal.append(f"{label} ({code.name})")
        setup(client)
    elif not _steps(client):
        report.broken_after.append(label)
        setup(client)


def _steps(client: Client) -> bool:
    """The world still steps after a refusal (a step left over from the case is its own)."""
    try:
        client.call("step", {"count": 2})
        client.call("get_states", {"names": ["xball"]})
    except DaemonUnreachableError:
        raise
    except GaltonError:
        return False
    return True


def _brief(args: dict[str, Any]) -> str:
    def short(value: Any) -> Any:
        if isinstance(value, bytes):
            return np.frombuffer(value, dtype="<f8").tolist()
        if isinstance(value, dict):
            return {k: short(v) for k, v in value.items()}
        if isinstance(value, list):
            return [short(v) for v in value]
        return value
    return str(short(args))[:160]
