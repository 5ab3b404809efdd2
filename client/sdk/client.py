"""The Python SDK: one typed method per daemon operation.

>>> with Client("galton") as sim:
...     sim.spawn(spheres(["ball"], [[0, 0, 1]], radius=0.05))
...     sim.step(500)
...     states = sim.get_states(["ball"])

Each method builds its operation's declared request (``galton.protocol.requests``, one
msgspec Struct per operation) and sends it through ``Client._send``, which refuses a bad
value before it leaves, as the daemon would (``galton.client.sdk.sending``). Joints and
wrenches (issue 24) take numpy arrays or scalars; their requests are built in
``galton.client.sdk.joints``.

A Client holds no per-request state: each result is built from its own reply (stamps
included), so one Client may serve several threads. Timeouts come from the operation
registry (``galton.protocol.operations``) unless the caller names one.
"""

from __future__ import annotations

import builtins
import os
import uuid
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import zenoh
from numpy.typing import ArrayLike

from galton.client.sdk import joints as sdk_joints
from galton.client.sdk.control import ControlMethods
from galton.client.sdk.joints import SearchPath
from galton.client.sdk.perception import PerceptionMethods
from galton.client.sdk.sending import wire_args
from galton.client.sdk.streams import StateSample, StateStream, StreamMethods
from galton.client.sdk.telemetry import Subscription, TelemetryStream, subscribe_events
from galton.client.sdk.values import (
    FloatArray,
    JointStates,
    ShapeInfo,
    Stamp,
    States,
    shapes_of,
)
from galton.client.sdk.worlds import WorldMethods
from galton.client.transport.base import ZenohTransport, transport_for
from galton.client.transport.credentials import Credentials
from galton.client.transport.session import checked_timeout
from galton.protocol import (
    POSE_WIDTH,
    BodyGroup,
    BodyProperties,
    Capabilities,
    EntityInfo,
    JointInfo,
    Keys,
    Reply,
    SimStatus,
    Telemetry,
    pack_f64,
)
from galton.protocol import mesh as mesh_wire
from galton.protocol import requests as rq
from galton.protocol.arrays import unpack_f64
from galton.protocol.errors import ClientClosedError, InvalidArgumentError
from galton.protocol.operations import OPERATIONS, GetEntities
from galton.protocol.replies import (
    BoundsReply,
    EntitiesReply,
    JointsReply,
    NamesReply,
    ParamsReply,
    ShapesReply,
    StepReply,
    decode_result,
)
from galton.protocol.vocabulary import EngineName, EntityKind, ResetScope

if TYPE_CHECKING:  # pyzmq loads only for a zmq+ endpoint (transport_for)
    from galton.client.transport.zmq_keys import ZmqKeys

DEFAULT_TIMEOUT_S = 5.0

__all__ = ["DEFAULT_TIMEOUT_S", "Client", "JointStates", "Stamp", "StateSample", "StateStream",
           "States", "body_group", "boxes", "plane", "spheres"]


class Client(WorldMethods, PerceptionMethods, ControlMethods, StreamMethods):
    """A connection to one daemon instance (the session may be shared with others).

    ``timeout``: seconds a quick operation waits for its reply; operations that rebuild a
    world wait at least their registry floor, stepping ones ``LONG_RUNNING_TIMEOUT_S``.
    Requests are for the daemon's live world; ``world(name)`` gives a view for another.
    """

    def __init__(self, instance: str = "galton", connect: str | Sequence[str] | None = None,
                 *, timeout: float = DEFAULT_TIMEOUT_S, session: zenoh.Session | None = None,
                 config_file: str | None = None,
                 credentials: Credentials | None = None,
                 zmq_keys: ZmqKeys | None = None, client_id: str | None = None) -> None:
        self.keys = Keys(instance)
        self.timeout = checked_timeout(timeout)
        self._closed = False
        self._world: str | None = None  # None: the live world (views name theirs)
        self._parent: WorldMethods | None = None
        # A daemon ends a step request whose client has vanished: this client's liveliness
        # token says so over Zenoh, the connection itself over ZeroMQ.
        # ``client_id``: one of the caller's choosing (galton-client view names a viewer's
        # VIEWER_ID_PREFIX + hex, the token a viewer may hold under --users).
        self.client_id = client_id or uuid.uuid4().hex
        self._own_transport = True
        self.transport = transport_for(self.keys, self.client_id, connect, session,
                                       config_file, credentials, zmq_keys)

    @property
    def session(self) -> zenoh.Session:
        """The Zenoh session (a client connected over ZeroMQ has none)."""
        if not isinstance(self.transport, ZenohTransport):
            raise InvalidArgumentError(
                f"this client speaks {self.transport.kind}, not Zenoh: it has no Zenoh session")
        return self.transport.session

    @property
    def instance(self) -> str:
        return self.keys.instance

    @property
    def closed(self) -> bool:
        """Closed itself, or a view of a client that was closed."""
        parent = self._parent
        return self._closed or (isinstance(parent, Client) and parent.closed)

    def close(self) -> None:
        """Withdraw this client's token and close its own connection; closing twice is
        fine (a view leaves its parent's open)."""
        if self._closed:
            return
        self._closed = True
        if self._own_transport:
            self.transport.close()

    def __enter__(self) -> Client:
        self._check_open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _check_open(self) -> None:
        if self.closed:
            raise ClientClosedError(
                f"this Client (instance {self.instance!r}) was closed; open a new one")

    # -- plumbing -----------------------------------------------------------------------
    def timeout_for(self, op: str, timeout: float | None = None) -> float:
        """The seconds a request for ``op`` waits: ``timeout`` if given (finite, above 0),
        else the registry's for the operation (unknown operations: this client's)."""
        if timeout is not None:
            return checked_timeout(timeout)
        known = OPERATIONS.get(op)
        return self.timeout if known is None else known.client_timeout(self.timeout)

    def request(self, op: str, args: dict[str, Any] | None = None,
                timeout: float | None = None) -> Reply:
        """Send any operation and return the raw reply, failures included; the reply holds
        the step and sim time the request took effect at."""
        self._check_open()
        wait = self.timeout_for(op, timeout)
        if self._world is not None:
            args = {"world": self._world, **(args or {})}
        # Every request names its client: a long step is tied to it, and so is control.
        return self.transport.request(op, args, wait, self.client_id)

    def call(self, op: str, args: dict[str, Any] | None = None,
             timeout: float | None = None) -> dict[str, Any]:
        """Send any operation as a raw ``args`` map (unchecked here: the daemon judges it);
        return its result map or raise the error its code means."""
        return self._ok(op, args, timeout).result

    def _send(self, op: str, request: rq.Args, timeout: float | None = None) -> Reply:
        """Send ``request``, ``op``'s declared request type, and return the reply it
        succeeded with; every SDK method sends through here. A bad value is refused before
        it leaves, as the daemon would refuse it (``galton.client.sdk.sending``)."""
        return self._ok(op, wire_args(op, request), timeout)

    def _ok(self, op: str, args: dict[str, Any] | None = None,
            timeout: float | None = None) -> Reply:
        """The reply to a request that succeeded (a failure raises its typed error)."""
        reply = self.request(op, args, timeout)
        reply.raise_for_code()
        return reply

    def _status(self, op: str, request: rq.Args | None = None) -> SimStatus:
        sent = rq.NoArgs() if request is None else request
        return SimStatus.from_wire(self._send(op, sent).result)

    # -- discovery & clock --------------------------------------------------------------
    def capabilities(self) -> Capabilities:
        return Capabilities.from_wire(self._send("capabilities", rq.NoArgs()).result)

    def status(self) -> SimStatus:
        return self._status("status")

    def play(self, rtf: float | None = None) -> SimStatus:
        """Run continuously at ``rtf`` × real time (0 = as fast as possible)."""
        return self._status("play", rq.Play(rtf=rtf))

    def set_rtf(self, rtf: float) -> SimStatus:
        return self._status("set_rtf", rq.SetRtf(rtf=rtf))

    def pause(self) -> SimStatus:
        return self._status("pause")

    def stop(self) -> SimStatus:
        """Pause and rewind: time to 0, every entity back to its created state."""
        return self._status("stop")

    def step(self, count: int = 1, timeout: float | None = None) -> Stamp:
        """Advance exactly ``count`` steps; returns when they are done."""
        return Stamp.of(self._send("step", rq.Step(count=count), timeout))

    def run_until(self, sim_time: float, timeout: float | None = None) -> Stamp:
        return Stamp.of(self._send("run_until", rq.RunUntil(sim_time=sim_time), timeout))

    def step_and_read(self, count: int, names: Sequence[str],
                      timeout: float | None = None) -> States:
        """Advance ``count`` steps and return these bodies' states after the last one: one
        round trip, as a control loop wants (step, then observe)."""
        return States.from_reply(
            self._send("step", sdk_joints.step_request(count, names, None), timeout))

    def step_and_read_joints(self, count: int, joints: Sequence[str],
                             timeout: float | None = None) -> JointStates:
        """Advance ``count`` steps and return these joints' states after the last one: with
        ``set_joint_targets`` before it, a lockstep control cycle."""
        return JointStates.from_step_reply(
            self._send("step", sdk_joints.step_request(count, None, joints), timeout))

    def step_and_read_both(self, count: int, names: Sequence[str], joints: Sequence[str],
                           timeout: float | None = None) -> tuple[States, JointStates]:
        """Advance ``count`` steps; return bodies' (or links') and joints' states after the
        last one, both from one reply (one round trip)."""
        reply = self._send("step", sdk_joints.step_request(count, names, joints), timeout)
        return States.from_reply(reply), JointStates.from_step_reply(reply)

    def run_until_and_read(self, sim_time: float, names: Sequence[str],
                           timeout: float | None = None) -> States:
        """``run_until`` and ``get_states(names)`` in one round trip."""
        return States.from_reply(self._send(
            "run_until", rq.RunUntil(sim_time=sim_time, read=list(names)), timeout))

    def run_until_and_read_joints(self, sim_time: float, joints: Sequence[str],
                                  timeout: float | None = None) -> JointStates:
        """``run_until`` and ``get_joint_states(joints)`` in one round trip."""
        return JointStates.from_step_reply(self._send(
            "run_until", rq.RunUntil(sim_time=sim_time, read_joints=list(joints)), timeout))

    def run_until_rest(self, sim_time: float, names: Sequence[str], speed: float,
                       every: float, timeout: float | None = None) -> tuple[States, bool]:
        """Run until every named body moves slower than ``speed`` m/s (looked at every
        ``every`` s of sim time) or until ``sim_time``; return their states and whether they
        came to rest. One round trip for a whole settling phase."""
        rest = rq.UntilRest(speed=speed, every=every)
        reply = self._send("run_until", rq.RunUntil(sim_time=sim_time, read=list(names),
                                                    until_rest=rest), timeout)
        return States.from_reply(reply), bool(decode_result(StepReply, reply.result).at_rest)

    def reset(self, scope: str = "all") -> SimStatus:
        """Scopes: time, state (entities to their created state), spawned, all."""
        return self._status("reset", rq.Reset(scope=cast(ResetScope, scope)))

    def load_world(self, engine: str, params: dict[str, Any] | None = None) -> SimStatus:
        """Replace the world with an empty one on another engine, without a restart."""
        return self._status("load_world", rq.LoadWorld(engine=cast(EngineName, engine),
                                                       params=params or None))

    def get_params(self) -> dict[str, Any]:
        return decode_result(ParamsReply, self._send("get_params", rq.NoArgs()).result).params

    def set_params(self, params: dict[str, Any]) -> dict[str, Any]:
        reply = self._send("set_params", rq.SetParams(params=params))
        return decode_result(ParamsReply, reply.result).params

    # -- scene --------------------------------------------------------------------------
    def spawn(self, *groups: BodyGroup, timeout: float | None = None) -> list[str]:
        """Create every body of every group in one request (one engine rebuild)."""
        request = rq.Spawn(groups=[g.to_wire() for g in groups])
        return decode_result(NamesReply, self._send("spawn", request, timeout).result).names

    def load_model(self, fmt: str, *, text: str | None = None,
                   path: str | os.PathLike[str] | None = None, prefix: str = "",
                   fixed_base: bool | None = None,
                   search_path: SearchPath | None = None) -> list[str]:
        """Load an MJCF or URDF model from ``text`` or a ``path`` on the daemon's machine;
        return its entities, each root before its links. ``fixed_base`` (URDF; daemon's
        default True) welds the root to the world; ``search_path``: folders (a list, or one
        str joined by ':') where the files the model names are looked for."""
        reply = self._send("load_model", sdk_joints.load_model_request(
            fmt, text, path, prefix, fixed_base, search_path))
        return decode_result(NamesReply, reply.result).names

    def list(self, name: str | None = None, tag: str | None = None,
             kind: str | None = None) -> list[EntityInfo]:
        """Entities matching a name glob, a tag and/or a kind ("static"/"dynamic")."""
        request = rq.List(name=name, tag=tag, kind=cast(EntityKind | None, kind))
        rows = decode_result(EntitiesReply, self._send("list", request).result).entities
        return [EntityInfo.from_wire(e) for e in rows]

    def get_states(self, names: Sequence[str] | None = None) -> States:
        """States of these bodies (all when None) in one request."""
        return States.from_reply(self._send("get_states", sdk_joints.names_or_all(names)))

    def get_bounds(self, names: Sequence[str] | None = None) -> dict[str, FloatArray]:
        """Each entity's world-frame axis-aligned bounds (all when None), as a row
        ``min_x min_y min_z max_x max_y max_z``."""
        reply = decode_result(BoundsReply, self._send(
            "get_bounds", sdk_joints.names_or_all(names)).result)
        rows = unpack_f64(reply.bounds, 6, "bounds")
        return dict(zip(reply.names, rows, strict=True))

    def get_entities(self, pattern: str | None = None,
                     region: ArrayLike | None = None) -> builtins.list[str]:
        """The entities passing every filter given (all when none): names the glob
        ``pattern`` matches (as ``list``'s); bounds touching ``region``, a box as two points
        ``[[min_x, min_y, min_z], [max_x, max_y, max_z]]``."""
        box = None if region is None else pack_f64(np.asarray(region, dtype=float).ravel())
        reply = self._send("get_entities", GetEntities(pattern=pattern, region=box))
        return decode_result(NamesReply, reply.result).names

    def get_shapes(self, names: Sequence[str] | None = None
                   ) -> dict[str, builtins.list[ShapeInfo]]:
        """Each entity's collision shapes (all entities when None), in its own frame; a
        mesh with its triangles where the daemon knows them (``ShapeInfo.boxed`` if not)."""
        reply = decode_result(ShapesReply, self._send(
            "get_shapes", sdk_joints.names_or_all(names)).result)
        return shapes_of(reply)

    def set_states(self, names: Sequence[str], poses: ArrayLike | None = None,
                   twists: ArrayLike | None = None) -> Stamp:
        """Poses (rows of 7) and/or twists (rows of 6); a single row is given to every body."""
        return Stamp.of(self._send("set_states",
                                   sdk_joints.set_states_request(names, poses, twists)))

    def update(self, names: Sequence[str], **properties: Any) -> Stamp:
        """Change mass, friction, restitution, rgba or tags of these entities."""
        props = rq.UpdateProperties(**BodyProperties(**properties).to_wire())
        return Stamp.of(self._send("update", rq.Update(names=list(names), properties=props)))

    def delete(self, names: Sequence[str]) -> Stamp:
        return Stamp.of(self._send("delete", rq.NamedOnly(names=list(names))))

    # -- joints and wrenches ------------------------------------------------------------
    def joints(self, model: str | None = None,
               names: Sequence[str] | None = None) -> builtins.list[JointInfo]:
        """Every joint of every loaded model, or of one ``model`` (its root entity), or
        these ``names``; in load order."""
        request = rq.Joints(model=model, names=None if names is None else list(names))
        result = self._send("joints", request).result
        return [JointInfo.from_wire(joint) for joint in decode_result(JointsReply, result).joints]

    def get_joint_states(self, names: Sequence[str] | None = None) -> JointStates:
        """Positions, velocities, efforts of these 1-DOF joints (all when None)."""
        return JointStates.from_reply(
            self._send("get_joint_states", sdk_joints.names_or_all(names)))

    def set_joint_states(self, names: Sequence[str], positions: ArrayLike,
                         velocities: ArrayLike | None = None) -> Stamp:
        """Teleport joints between steps (velocities None: each keeps its own)."""
        return Stamp.of(self._send("set_joint_states", sdk_joints.set_joint_states_request(
            names, positions, velocities)))

    def set_joint_states_and_read(self, names: Sequence[str], positions: ArrayLike,
                                  read: Sequence[str], velocities: ArrayLike | None = None
                                  ) -> States:
        """Teleport joints and return these bodies' or links' states where the joints now
        put them (no step): mirroring a robot is one round trip per cycle."""
        request = sdk_joints.set_joint_states_request(names, positions, velocities, read)
        return States.from_reply(self._send("set_joint_states", request))

    def set_joint_targets(self, names: Sequence[str], mode: str,
                          targets: ArrayLike | None = None, kp: ArrayLike | None = None,
                          kd: ArrayLike | None = None,
                          max_effort: ArrayLike | None = None) -> Stamp:
        """Hold a target (mode "position", "velocity", "effort" or "none") on these joints,
        applied every step by the engine until changed. Each of ``targets``, ``kp``, ``kd``
        and ``max_effort`` is one value per joint or a scalar for all."""
        return Stamp.of(self._send("set_joint_targets", sdk_joints.set_joint_targets_request(
            names, mode, targets, kp, kd, max_effort)))

    def apply_wrench(self, names: Sequence[str], wrenches: ArrayLike,
                     points: ArrayLike | None = None, duration: float | None = None) -> Stamp:
        """Hold a world-frame wrench (rows fx fy fz tx ty tz) on bodies or links, at
        ``points`` (rows x y z, world frame; None: each centre of mass), for ``duration``
        seconds or until cleared. One row alone acts on every body."""
        return Stamp.of(self._send("apply_wrench", sdk_joints.apply_wrench_request(
            names, wrenches, points, duration)))

    def clear_wrenches(self, names: Sequence[str] | None = None) -> Stamp:
        """Remove the wrenches of these bodies (every wrench when None)."""
        return Stamp.of(self._send("clear_wrenches", sdk_joints.names_or_all(names)))

    # -- streams ------------------------------------------------------------------------
    def telemetry(self, timeout: float | None = None) -> TelemetryStream:
        """An iterator of Telemetry samples (close it, or use it as a context manager)."""
        self._check_open()
        return TelemetryStream(self.transport, self.timeout if timeout is None else timeout)

    def on_telemetry(self, callback: Callable[[Telemetry], None]) -> Subscription:
        """Call ``callback`` on Zenoh's thread for every sample; keep it short."""
        self._check_open()
        return TelemetryStream.with_callback(self.transport, callback)

    def on_event(self, callback: Callable[[dict[str, Any]], None]) -> Subscription:
        self._check_open()
        return subscribe_events(self.transport, callback)


def spheres(names: Sequence[str], positions: Sequence[Sequence[float]] | np.ndarray,
            radius: float, **options: Any) -> BodyGroup:
    """A group of spheres at these positions (identity orientation)."""
    return body_group("sphere", (radius,), names, positions, **options)


def boxes(names: Sequence[str], positions: Sequence[Sequence[float]] | np.ndarray,
          half_extents: Sequence[float], **options: Any) -> BodyGroup:
    return body_group("box", tuple(half_extents), names, positions, **options)


def meshes(names: Sequence[str], positions: Sequence[Sequence[float]] | np.ndarray,
           vertices: Sequence[Sequence[float]] | np.ndarray,
           faces: Sequence[Sequence[int]] | np.ndarray, **options: Any) -> BodyGroup:
    """A group of bodies of one triangle mesh (vertices in the body's frame, faces as
    vertex-index triples wound outward) at these positions; how each engine collides it
    (convex hull or triangles) is in docs/ENGINES.md."""
    points = np.asarray(vertices, dtype=float).reshape(-1, 3)
    return body_group("mesh", mesh_wire.half_extents(points), names, positions,
                      vertices=points, faces=np.asarray(faces, dtype=np.int64).reshape(-1, 3),
                      **options)


def plane(name: str = "ground", height: float = 0.0, **options: Any) -> BodyGroup:
    return body_group("plane", (50.0, 50.0), [name], [[0.0, 0.0, height]], static=True, **options)


def body_group(shape: str, size: tuple[float, ...], names: Sequence[str],
               positions: Sequence[Sequence[float]] | np.ndarray, **options: Any) -> BodyGroup:
    """A group of bodies of one shape at these positions (identity orientation)."""
    xyz = np.asarray(positions, dtype=float).reshape(-1, 3)
    poses = np.zeros((len(xyz), POSE_WIDTH))
    poses[:, :3] = xyz
    poses[:, 6] = 1.0
    return BodyGroup(shape=shape, size=size, names=list(names), poses=poses, **options)
