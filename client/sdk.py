"""The Python SDK: one typed method per daemon operation.

>>> with Client("galton") as sim:
...     sim.spawn(spheres(["ball"], [[0, 0, 1]], radius=0.05))
...     sim.step(500)
...     states = sim.get_states(["ball"])
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import zenoh

from galton.client.session import open_session, query
from galton.client.telemetry import Subscription, TelemetryStream, subscribe_events
from galton.protocol import (
    POSE_WIDTH,
    TWIST_WIDTH,
    BodyGroup,
    BodyProperties,
    Capabilities,
    EntityInfo,
    Keys,
    Reply,
    SimStatus,
    Telemetry,
    pack_f64,
    unpack_f64,
)
from galton.protocol.keys import client_token_key
from galton.protocol.operations import OPERATIONS

DEFAULT_TIMEOUT_S = 5.0
DEFAULT_STEP_TIMEOUT_S = 600.0


@dataclass
class States:
    """Poses (n, 7: x y z qx qy qz qw) and world twists (n, 6) of named bodies."""

    names: list[str]
    poses: np.ndarray
    twists: np.ndarray
    step: int
    sim_time: float

    @property
    def positions(self) -> np.ndarray:
        return self.poses[:, :3]

    @property
    def speeds(self) -> np.ndarray:
        return np.linalg.norm(self.twists[:, :3], axis=1)


@dataclass
class Stamp:
    """When a mutating request took effect."""

    step: int
    sim_time: float


class Client:
    """A connection to one daemon instance (the session may be shared with others)."""

    def __init__(self, instance: str = "galton", connect: str | Sequence[str] | None = None,
                 *, timeout: float = DEFAULT_TIMEOUT_S, session: zenoh.Session | None = None,
                 config_file: str | None = None) -> None:
        self.keys = Keys(instance)
        self.timeout = timeout
        self._own_session = session is None
        self.session = session if session is not None else open_session(connect, config_file)
        self.last_stamp = Stamp(0, 0.0)
        # This client's liveliness: a daemon ends a step request whose client has vanished.
        self.client_id = uuid.uuid4().hex
        self._token = self.session.liveliness().declare_token(client_token_key(self.client_id))

    @property
    def instance(self) -> str:
        return self.keys.instance

    def close(self) -> None:
        if self._token is not None:
            self._token.undeclare()
            self._token = None
        if self._own_session:
            self.session.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- plumbing -----------------------------------------------------------------------
    def call(self, op: str, args: dict[str, Any] | None = None,
             timeout: float | None = None) -> dict[str, Any]:
        """Send any operation; return its result map or raise the error its code means."""
        reply = self.request(op, args, timeout)
        reply.raise_for_code()
        return reply.result

    def request(self, op: str, args: dict[str, Any] | None = None,
                timeout: float | None = None) -> Reply:
        """Send any operation and return the raw reply, failures included."""
        steps = op in OPERATIONS and OPERATIONS[op].steps
        reply = query(self.session, self.keys.control(op), op, args,
                      self.timeout if timeout is None else timeout,
                      self.client_id if steps else None)
        self.last_stamp = Stamp(reply.step, reply.sim_time)
        return reply

    # -- discovery & clock --------------------------------------------------------------
    def capabilities(self) -> Capabilities:
        return Capabilities.from_wire(self.call("capabilities"))

    def status(self) -> SimStatus:
        return SimStatus.from_wire(self.call("status"))

    def play(self, rtf: float | None = None) -> SimStatus:
        """Run continuously at ``rtf`` × real time (0 = as fast as possible)."""
        return SimStatus.from_wire(self.call("play", {} if rtf is None else {"rtf": rtf}))

    def set_rtf(self, rtf: float) -> SimStatus:
        return SimStatus.from_wire(self.call("set_rtf", {"rtf": rtf}))

    def pause(self) -> SimStatus:
        return SimStatus.from_wire(self.call("pause"))

    def stop(self) -> SimStatus:
        """Pause and rewind: time to 0, every entity back to its created state."""
        return SimStatus.from_wire(self.call("stop"))

    def step(self, count: int = 1, timeout: float | None = None) -> Stamp:
        """Advance exactly ``count`` steps; returns when they are done."""
        self.call("step", {"count": count},
                  DEFAULT_STEP_TIMEOUT_S if timeout is None else timeout)
        return self.last_stamp

    def run_until(self, sim_time: float, timeout: float | None = None) -> Stamp:
        self.call("run_until", {"sim_time": sim_time},
                  DEFAULT_STEP_TIMEOUT_S if timeout is None else timeout)
        return self.last_stamp

    def step_and_read(self, count: int, names: Sequence[str],
                      timeout: float | None = None) -> States:
        """Advance ``count`` steps and return these bodies' states after the last one: one
        round trip, as a control loop wants (step, then observe)."""
        result = self.call("step", {"count": count, "read": list(names)},
                           DEFAULT_STEP_TIMEOUT_S if timeout is None else timeout)
        return self._states(result)

    def run_until_and_read(self, sim_time: float, names: Sequence[str],
                           timeout: float | None = None) -> States:
        """``run_until`` and ``get_states(names)`` in one round trip."""
        result = self.call("run_until", {"sim_time": sim_time, "read": list(names)},
                           DEFAULT_STEP_TIMEOUT_S if timeout is None else timeout)
        return self._states(result)

    def run_until_rest(self, sim_time: float, names: Sequence[str], speed: float,
                       every: float, timeout: float | None = None) -> tuple[States, bool]:
        """Run until every named body moves slower than ``speed`` m/s (looked at every
        ``every`` s of sim time) or until ``sim_time``; return their states and whether they
        came to rest. One round trip for a whole settling phase."""
        result = self.call("run_until", {"sim_time": sim_time, "read": list(names),
                                         "until_rest": {"speed": speed, "every": every}},
                           DEFAULT_STEP_TIMEOUT_S if timeout is None else timeout)
        return self._states(result), bool(result["at_rest"])

    def _states(self, result: dict[str, Any]) -> States:
        return States(result["names"], unpack_f64(result["poses"], POSE_WIDTH),
                      unpack_f64(result["twists"], TWIST_WIDTH), *_stamp(self.last_stamp))

    def reset(self, scope: str = "all") -> SimStatus:
        """Scopes: time, state (entities to their created state), spawned, all."""
        return SimStatus.from_wire(self.call("reset", {"scope": scope}))

    def load_world(self, engine: str, params: dict[str, Any] | None = None) -> SimStatus:
        """Replace the world with an empty one on another engine, without a restart."""
        args: dict[str, Any] = {"engine": engine}
        if params:
            args["params"] = params
        return SimStatus.from_wire(self.call("load_world", args, timeout=max(self.timeout, 30)))

    def get_params(self) -> dict[str, Any]:
        return self.call("get_params")["params"]

    def set_params(self, params: dict[str, Any]) -> dict[str, Any]:
        return self.call("set_params", {"params": params})["params"]

    # -- scene --------------------------------------------------------------------------
    def spawn(self, *groups: BodyGroup, timeout: float | None = None) -> list[str]:
        """Create every body of every group in one request (one engine rebuild)."""
        args = {"groups": [g.to_wire() for g in groups]}
        return self.call("spawn", args, timeout=timeout or max(self.timeout, 30))["names"]

    def load_model(self, fmt: str, *, text: str | None = None, path: str | None = None,
                   prefix: str = "") -> list[str]:
        args = {"format": fmt, "text": text, "path": path, "prefix": prefix}
        args = {k: v for k, v in args.items() if v is not None}
        return self.call("load_model", args, timeout=max(self.timeout, 30))["names"]

    def list(self, name: str | None = None, tag: str | None = None,
             kind: str | None = None) -> list[EntityInfo]:
        """Entities matching a name glob, a tag and/or a kind ("static"/"dynamic")."""
        args = {k: v for k, v in (("name", name), ("tag", tag), ("kind", kind)) if v is not None}
        return [EntityInfo.from_wire(e) for e in self.call("list", args)["entities"]]

    def get_states(self, names: Sequence[str] | None = None) -> States:
        """States of these bodies (all when None) in one request."""
        return self._states(
            self.call("get_states", {} if names is None else {"names": list(names)}))

    def set_states(self, names: Sequence[str], poses: np.ndarray | None = None,
                   twists: np.ndarray | None = None) -> Stamp:
        args: dict[str, Any] = {"names": list(names)}
        if poses is not None:
            args["poses"] = pack_f64(np.asarray(poses, dtype=float).reshape(-1, POSE_WIDTH))
        if twists is not None:
            args["twists"] = pack_f64(np.asarray(twists, dtype=float).reshape(-1, TWIST_WIDTH))
        self.call("set_states", args)
        return self.last_stamp

    def update(self, names: Sequence[str], **properties: Any) -> Stamp:
        """Change mass, friction, restitution, rgba or tags of these entities."""
        props = BodyProperties(**properties)
        self.call("update", {"names": list(names), "properties": props.to_wire()})
        return self.last_stamp

    def delete(self, names: Sequence[str]) -> Stamp:
        self.call("delete", {"names": list(names)}, timeout=max(self.timeout, 30))
        return self.last_stamp

    # -- streams ------------------------------------------------------------------------
    def telemetry(self, timeout: float | None = None) -> TelemetryStream:
        """An iterator of Telemetry samples (close it, or use it as a context manager)."""
        return TelemetryStream(self.session, self.keys.telemetry,
                               self.timeout if timeout is None else timeout)

    def on_telemetry(self, callback: Callable[[Telemetry], None]) -> Subscription:
        """Call ``callback`` on Zenoh's thread for every sample; keep it short."""
        return TelemetryStream.with_callback(self.session, self.keys.telemetry, callback)

    def on_event(self, callback: Callable[[dict[str, Any]], None]) -> Subscription:
        return subscribe_events(self.session, self.keys.events, callback)


def _stamp(stamp: Stamp) -> tuple[int, float]:
    return stamp.step, stamp.sim_time


def spheres(names: Sequence[str], positions: Sequence[Sequence[float]] | np.ndarray,
            radius: float, **options: Any) -> BodyGroup:
    """A group of spheres at these positions (identity orientation)."""
    return body_group("sphere", (radius,), names, positions, **options)


def boxes(names: Sequence[str], positions: Sequence[Sequence[float]] | np.ndarray,
          half_extents: Sequence[float], **options: Any) -> BodyGroup:
    return body_group("box", tuple(half_extents), names, positions, **options)


def plane(name: str = "ground", height: float = 0.0, **options: Any) -> BodyGroup:
    return body_group("plane", (50.0, 50.0), [name], [[0.0, 0.0, height]], static=True, **options)


def body_group(shape: str, size: tuple[float, ...], names: Sequence[str],
           positions: Sequence[Sequence[float]] | np.ndarray, **options: Any) -> BodyGroup:
    xyz = np.asarray(positions, dtype=float).reshape(-1, 3)
    poses = np.zeros((len(xyz), POSE_WIDTH))
    poses[:, :3] = xyz
    poses[:, 6] = 1.0
    return BodyGroup(shape=shape, size=size, names=list(names), poses=poses, **options)
