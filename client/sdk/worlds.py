"""The SDK's worlds, snapshots, predictions and comparisons (issue 25), mixed into Client.

A daemon holds one live world and side worlds; ``Client.world(name)`` is a view of the same
connection whose every request names that world:

>>> ahead = sim.fork_world("ahead")          # a copy of the live world
>>> side = sim.world("ahead")                # requests for it
>>> side.step(500)                           # the live world is not disturbed
>>> saved = sim.snapshot("before")           # kept in the daemon
>>> sim.restore("before")                    # the same steps give the same states again

``lockstep`` keeps a world at an external clock's time stamps (a robot's).
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Self, cast

import numpy as np
from numpy.typing import ArrayLike

from galton.client.sdk import joints as sdk_joints
from galton.client.sdk.calibration import (
    CalibrationResult,
    calibrate_args,
    trigger_calibration,
)
from galton.client.sdk.sending import wire_args
from galton.client.sdk.values import Comparison, Prediction, SnapshotInfo, Stamp, WorldInfo
from galton.protocol import POSE_WIDTH, TWIST_WIDTH, InvalidArgumentError, Reply, pack_f64
from galton.protocol import requests as rq
from galton.protocol.operations import Calibrate
from galton.protocol.replies import SnapshotsReply, WorldsReply, decode_result
from galton.protocol.vocabulary import EngineName

if TYPE_CHECKING:
    from galton.client.sdk.client import Client

# run_until takes no step when the target is within this fraction of a step (the daemon's
# own rounding), so a stamp that close is already reached.
_STEP_TOLERANCE = 1e-9


class WorldMethods:
    """Client methods for worlds, snapshots, prediction and comparison."""

    _world: str | None
    _parent: WorldMethods | None
    _closed: bool
    _own_transport: bool

    if TYPE_CHECKING:
        def _send(self, op: str, request: rq.Args, timeout: float | None = None
                  ) -> Reply: ...

        def _check_open(self) -> None: ...

    # -- addressing a world ---------------------------------------------------------------
    @property
    def world_name(self) -> str | None:
        """The world this client's requests name (None: the daemon's live world)."""
        return self._world

    def world(self, name: str) -> Self:
        """A view of this client whose every request is for world ``name`` (its session,
        liveliness and timeouts shared; closing the view leaves this client open, closing
        this client closes the view)."""
        self._check_open()
        if not isinstance(name, str) or not name:
            raise InvalidArgumentError(f"a world name is a non-empty str, got {name!r}")
        view = copy.copy(self)
        view._world, view._parent = name, self
        view._own_transport, view._closed = False, False
        return view

    # -- worlds ---------------------------------------------------------------------------
    def list_worlds(self) -> list[WorldInfo]:
        """Every world of the daemon, the live one first."""
        rows = decode_result(WorldsReply, self._send("list_worlds", rq.NoArgs()).result).worlds
        return [WorldInfo.of(row) for row in rows]

    def create_world(self, name: str, engine: str | None = None,
                     params: dict[str, Any] | None = None) -> WorldInfo:
        """An empty side world (engine default: the live world's); it moves only when
        stepped."""
        request = rq.CreateWorld(name=name, engine=cast(EngineName | None, engine),
                                 params=params or None)
        return WorldInfo.from_wire(self._send("create_world", request).result)

    def fork_world(self, name: str, source: str | None = None) -> WorldInfo:
        """A copy of world ``source`` (default the live one): scene, state, parameters,
        targets, wrenches and clock. The source is not disturbed."""
        request = rq.ForkWorld(name=name, source=source)
        return WorldInfo.from_wire(self._send("fork_world", request).result)

    def delete_world(self, name: str) -> None:
        """Delete a side world (the live one cannot be)."""
        self._send("delete_world", rq.Named(name=name))

    # -- snapshots ------------------------------------------------------------------------
    def snapshot(self, slot: str | None = None, blob: bool = False) -> SnapshotInfo:
        """The complete world, kept in the daemon under ``slot`` and/or returned as bytes
        (``.blob``) that any daemon with the same engine restores."""
        reply = self._send("snapshot", rq.Snapshot(slot=slot, blob=blob))
        return SnapshotInfo.from_wire(reply.result, self._world or "")

    def restore(self, slot: str | None = None, blob: bytes | None = None) -> WorldInfo:
        """Replace the world by a snapshot: exactly one of a ``slot`` or a ``blob``. The
        same steps after it give the same states, bit for bit."""
        if (slot is None) == (blob is None):
            raise InvalidArgumentError("restore takes exactly one of slot or blob")
        request = rq.Restore(slot=slot, blob=None if blob is None else bytes(blob))
        return WorldInfo.from_wire(self._send("restore", request).result)

    def snapshots(self) -> list[SnapshotInfo]:
        """The snapshot slots the daemon keeps."""
        rows = decode_result(SnapshotsReply, self._send("snapshots", rq.NoArgs()).result).slots
        return [SnapshotInfo(row.slot, row.world, row.engine, row.bytes, row.step, row.sim_time,
                             row.entity_count) for row in rows]

    def delete_snapshot(self, slot: str) -> None:
        self._send("delete_snapshot", rq.Slot(slot=slot))

    # -- ahead of reality -----------------------------------------------------------------
    def predict(self, horizon: float, every: float | None = None,
                read: Sequence[str] | None = None, read_joints: Sequence[str] | None = None,
                slot: str | None = None, set_states: Mapping[str, Any] | None = None,
                joint_targets: Mapping[str, Any] | None = None,
                wrenches: Mapping[str, Any] | None = None,
                futures: int | None = None, perturb: Mapping[str, Any] | None = None,
                seed: int | None = None, plans: Sequence[Sequence[Mapping[str, Any]]] | None
                = None, score: Mapping[str, Any] | None = None,
                timeout: float | None = None, first_future: int | None = None
                ) -> Prediction:
        """Run a copy of the world (or of snapshot ``slot``) ``horizon`` seconds ahead,
        sampling ``read`` bodies and ``read_joints`` joints every ``every`` seconds, and
        discard it: the world is never changed. The copy may first be changed, each as its
        request's keyword arguments: ``set_states`` (names, poses, twists),
        ``joint_targets`` (names, mode, targets, kp, kd, max_effort) and ``wrenches``
        (names, wrenches, points, duration).

        Many futures at once: ``futures`` N, each started with seeded noise ``perturb``
        ({"position": m, "orientation": rad, "velocity": m/s, "bodies": {name: {...}}}),
        and/or ``plans``, one per future, each a list of {"at": s, "joint_targets":
        {...}, "wrenches": {...}}; ``score`` {"body": name, "target": [x, y, z]} gives
        each future's distance to the target at the horizon (docs/protocol.md).
        ``first_future`` K: these are futures K.. of ``seed``'s ensemble (a batch of a
        larger one, as ``galton.client.bench.futures`` spreads over daemons)."""
        request = rq.Predict(
            horizon=horizon, every=every, read=_listed(read), read_joints=_listed(read_joints),
            slot=slot, futures=futures, seed=seed, **sdk_joints.given(first_future=first_future),
            perturb=None if perturb is None else rq.decode_field(
                "predict", rq.Predict, "perturb", dict(perturb)),
            plans=None if plans is None else [[_plan_step(item) for item in plan]
                                              for plan in plans],
            score=None if score is None else rq.Score(
                body=score["body"], target=[float(v) for v in score["target"]]),
            set_states=_as_map("set_states", sdk_joints.set_states_request, set_states),
            joint_targets=_as_map("set_joint_targets", sdk_joints.set_joint_targets_request,
                                  joint_targets),
            wrenches=_as_map("apply_wrench", sdk_joints.apply_wrench_request, wrenches))
        return Prediction.from_reply(self._send("predict", request, timeout))

    def compare(self, names: Sequence[str], poses: ArrayLike, twists: ArrayLike | None = None,
                sigma_position: float | None = None, sigma_angle: float | None = None,
                sigma_speed: float | None = None, correct: bool = False,
                spread: ArrayLike | float | None = None,
                trigger: tuple[float, int] | None = None,
                calibrate: Mapping[str, Any] | None = None) -> Comparison:
        """Observed poses (rows of 7, and optionally twists) of these bodies against the
        world's at its present time: per-body errors and one anomaly score (about 1 at the
        sigmas' noise, 3 a surprise). ``correct`` sets the bodies to the observation.
        ``spread`` (m, per body or one for all): the spread of position an ensemble
        prediction expected (``Prediction.spread_of(names)``), combined with
        ``sigma_position`` as independent noise: the score then says how surprising the
        observation is given what was imagined. ``trigger`` (threshold, window): count this
        comparison toward the world's surprise streak; the one that makes it ``window``
        long is ``suggested`` and publishes a ``calibration_suggested`` event.
        ``calibrate`` (with ``trigger``: ``{"fit": {...}, "apply": ..., "max_predictions":
        ..., "population": ..., "seed": ...}``, calibrate's own fields): that comparison
        also starts the calibration itself, over the streak's observations (``calibrating``;
        ``calibration_started`` and ``calibration_finished`` events)."""
        count = len(names)
        if trigger is None and calibrate is not None:
            raise InvalidArgumentError("compare: calibrate is started by a trigger; give "
                                       "trigger=(threshold, window) with it")
        request = rq.Compare(
            names=list(names), correct=correct,
            poses=sdk_joints.body_rows(poses, count, POSE_WIDTH, "compare.poses"),
            twists=None if twists is None else sdk_joints.body_rows(
                twists, count, TWIST_WIDTH, "compare.twists"),
            spread=None if spread is None else spread_arg(spread, count),
            trigger=None if trigger is None else _trigger(trigger, calibrate),
            **sdk_joints.given(sigma_position=sigma_position, sigma_angle=sigma_angle,
                               sigma_speed=sigma_speed))
        return Comparison.from_reply(self._send("compare", request), list(names))

    def calibrate(self, fit: Mapping[str, Sequence[float]], names: Sequence[str],
                  times: ArrayLike, poses: ArrayLike, *, twists: ArrayLike | None = None,
                  slot: str | None = None, apply: bool = False,
                  max_predictions: int | None = None, population: int | None = None,
                  seed: int | None = None, timeout: float | None = None
                  ) -> CalibrationResult:
        """Fit ``fit``'s parameters ({"box.friction": (low, high), "gravity": ...}) so that
        a prediction from the first sample (or snapshot ``slot``) lands where ``names`` were
        seen at ``times`` (``poses``: samples x bodies rows of 7, NaN: not seen). The
        first sample's twists are ``twists``, or estimated from the first samples. With
        ``apply`` the fitted values are set in this world; otherwise it is not changed.
        ``observed_in(recording)`` (galton.client) gives names, times and poses."""
        args = calibrate_args(fit, names, times, poses, twists, {
            "slot": slot, "apply": apply, "max_predictions": max_predictions,
            "population": population, "seed": seed})
        return CalibrationResult.from_reply(self._send("calibrate", Calibrate(**args), timeout))


def spread_arg(spread: ArrayLike | float, count: int) -> float | bytes:
    """One spread for all bodies, or packed float64, one per body."""
    if isinstance(spread, int | float):
        return float(spread)
    values = np.asarray(spread, dtype=float).reshape(-1)
    if len(values) != count:
        raise InvalidArgumentError(f"compare.spread has {len(values)} values for {count} "
                                   "bodies: give one per body, or one for all")
    return pack_f64(values)


def _trigger(trigger: tuple[float, int], calibrate: Mapping[str, Any] | None) -> rq.Trigger:
    """compare's trigger, and the calibration it starts (as calibrate's own fields): typed
    from the caller's map, refused as the daemon would refuse it."""
    wire: dict[str, Any] = {"threshold": float(trigger[0]), "window": int(trigger[1])}
    if calibrate is not None:
        wire["calibrate"] = trigger_calibration(calibrate)
    typed: rq.Trigger = rq.decode_field("compare", rq.Compare, "trigger", wire)
    return typed


def _plan_step(item: Mapping[str, Any]) -> rq.PlanStep:
    """A plan's timed action: its joint targets and wrenches as their requests' maps."""
    return rq.PlanStep(
        at=float(item["at"]),
        joint_targets=_as_map("set_joint_targets", sdk_joints.set_joint_targets_request,
                              item.get("joint_targets")),
        wrenches=_as_map("apply_wrench", sdk_joints.apply_wrench_request, item.get("wrenches")))


def _as_map(op: str, build: Callable[..., rq.Args], kwargs: Mapping[str, Any] | None
            ) -> dict[str, Any] | None:
    """A request predict carries inside it (its set_states, joint_targets, wrenches, each
    as keyword arguments of that request's SDK method), built as ``op``'s declared type
    and sent as its map, checked as the daemon checks it (``wire_args``)."""
    return None if kwargs is None else wire_args(op, build(**kwargs))


def _listed(names: Sequence[str] | None) -> list[str] | None:
    return None if names is None else list(names)


def lockstep(sim: Client, stamps: Iterable[float]) -> Iterator[Stamp]:
    """Keep ``sim``'s world at an external clock: for each time stamp (increasing, in
    seconds of the world's sim time), step until the world's sim time reaches it and yield
    where it got to. Stamps that are whole multiples of the timestep are met exactly
    (drift 0); others are passed by less than one step, and a stamp already reached takes
    no step. The caller sets targets or reads states between stamps, as a robot's
    controller does between its cycles."""
    status = sim.status()
    dt = status.timestep
    reached = Stamp(status.step, status.sim_time)
    for stamp in stamps:
        if (stamp - reached.sim_time) / dt > _STEP_TOLERANCE:
            reached = sim.run_until(stamp)
        yield reached
