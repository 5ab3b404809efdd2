"""The daemon's Zenoh side: session, control queryable, publishers, liveliness token."""

from __future__ import annotations

import json
import logging
import os
import select
import signal
import threading
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import msgpack
import zenoh

from galton.daemon.access.users import User
from galton.daemon.access.zenoh_security import (
    TlsFiles,
    remove_private_files,
    security_settings,
    tls_settings,
)
from galton.daemon.access.zmq_auth import ZmqSecurity
from galton.daemon.core.calls import Call, Task
from galton.daemon.core.limits import DEFAULT_LIMITS, Limits
from galton.daemon.core.loop import SimLoop
from galton.daemon.engines import ENGINE_CLASSES, create_engine
from galton.daemon.engines.base import Engine
from galton.daemon.fronts.ros2.options import Ros2Options
from galton.daemon.fronts.zenoh_config import file_says, listen_endpoints, merge
from galton.daemon.fronts.zmq import PolledInbox, ZmqFront, parse_endpoint
from galton.daemon.world import checkpoint
from galton.daemon.world.scene import World
from galton.daemon.world.stream_sender import SampleSender
from galton.protocol import InvalidArgumentError, Keys, OperationFailedError, Telemetry
from galton.protocol.keys import (
    CLIENTS_PATTERN,
    client_from_token_key,
    client_token_key,
    op_from_control_key,
)
from galton.protocol.operations import OPERATIONS

log = logging.getLogger("galton.daemon")

# After SIGTERM the daemon answers what is pending and closes; if a request still holds the
# physics thread this long after the signal, the process exits without waiting for it.
SHUTDOWN_GRACE_S = 1.5
CLIENT_TOKEN_TIMEOUT_S = 1.0


@dataclass
class DaemonOptions:
    """How one daemon is started (the ``galton-daemon`` command line, as a value)."""

    engine: str = "mujoco"
    instance: str = "galton"
    # Empty: the --zenoh-config file's endpoints, else DEFAULT_LISTEN (fronts/zenoh_config.py)
    listen: list[str] = field(default_factory=list)
    connect: list[str] = field(default_factory=list)
    zenoh_config: Path | None = None
    multicast: bool = False
    telemetry_rate_hz: float = 10.0
    params: dict[str, Any] = field(default_factory=dict)
    limits: Limits = DEFAULT_LIMITS
    state_dir: Path | None = None  # checkpoints of the live world (daemon/world/checkpoint.py)
    checkpoint_period_s: float = checkpoint.DEFAULT_PERIOD_S
    zmq: list[str] = field(default_factory=list)  # ZeroMQ endpoints (daemon/fronts/zmq.py)
    users: Mapping[str, User] | None = None  # --users: authentication and roles (SECURITY.md)
    zmq_key: Path | None = None  # --zmq-key: the ZeroMQ front's CURVE key pair
    tls: TlsFiles | None = None  # --tls-cert/--tls-key/--tls-ca
    ros2: Ros2Options | None = None  # --ros2: the ROS 2 front (daemon/fronts/ros2, docs/ROS2.md)
    snapshot_key: bytes | None = None  # --snapshot-key: the secret that seals snapshot blobs


def zenoh_config(options: DaemonOptions) -> zenoh.Config:
    """The --zenoh-config file (or Zenoh's defaults) merged with the options by the rules of
    fronts/zenoh_config.py, with --users and --tls-* security (access/zenoh_security.py)."""
    return _merged_config(options, security_settings(options.users, options.tls,
                                                     options.instance))


def listening_on(options: DaemonOptions) -> list[str]:
    """The endpoints the daemon's Zenoh configuration listens on (its readiness line)."""
    tls = tls_settings(options.tls) if options.tls is not None else {}
    return listen_endpoints(_merged_config(options, tls))


def _merged_config(options: DaemonOptions, security: dict[str, Any]) -> zenoh.Config:
    path = options.zenoh_config
    config = zenoh.Config.from_file(str(path)) if path is not None else zenoh.Config()
    inserts = merge(file_says(config), options.listen, options.connect, options.multicast,
                    security)
    for key, value in inserts.items():
        config.insert_json5(key, json.dumps(value))
    return config


class Daemon:
    """One daemon instance: a SimLoop on its own thread, served over one Zenoh session."""

    def __init__(self, options: DaemonOptions) -> None:
        self.options = options
        self.keys = Keys(options.instance)
        engine = create_engine(options.engine)
        if options.params:
            engine.set_params(options.params)
        try:
            self.session = zenoh.open(zenoh_config(options))
        finally:
            remove_private_files()  # the usrpwd dictionary: Zenoh has read it
        self._telemetry_pub = self.session.declare_publisher(
            self.keys.telemetry, congestion_control=zenoh.CongestionControl.DROP)
        self._events_pub = self.session.declare_publisher(self.keys.events)
        self.loop = SimLoop(self._first_world(engine), options.instance,
                            self._publish_telemetry, self._publish_event,
                            options.telemetry_rate_hz, create_engine, options.limits)
        self.loop.snapshot_key = options.snapshot_key
        self.front = _zmq_front(options, self.loop)
        # A state stream's samples: Zenoh's put off the physics thread, the ZeroMQ front's
        # send on it (its sockets are that thread's).
        self.loop.streams.sender = SampleSender(self._publish_states)
        self.loop.streams.publish = self.front.publish if self.front is not None else None
        self.loop.client_alive = self._client_alive
        self._thread: threading.Thread | None = None
        self._queryable: Any = None
        self._token: Any = None
        self._clients: Any = None
        self.ros2: Any = None  # the ROS 2 front, with --ros2
        self.finished = threading.Event()
        # Client ids whose liveliness token this daemon has seen come and not go (updated on
        # Zenoh's thread; a set's add and discard are atomic under the GIL).
        self._live_clients: set[str] = set()

    def _first_world(self, engine: Engine) -> World:
        """The checkpointed world when --state-dir holds one, else an empty world."""
        options = self.options
        if options.state_dir is not None:
            path = checkpoint.checkpoint_path(options.state_dir, options.instance)
            restored = checkpoint.load(path, create_engine, "default", options.limits,
                                       options.snapshot_key)
            if restored is not None:
                engine.close()
                log.warning("restored the world of %s: %d entities at step %d", path,
                            len(restored.entities), restored.step_index)
                return restored
        return World(engine, limits=options.limits)

    def save_checkpoint(self) -> None:
        """Save the live world to --state-dir (a faulted world is not saved)."""
        if self.options.state_dir is None or self.loop.world.faulted:
            return
        path = checkpoint.checkpoint_path(self.options.state_dir, self.options.instance)
        try:
            checkpoint.save(self.loop.world, path, self.options.snapshot_key)
        except Exception:
            log.exception("could not save a checkpoint to %s", path)

    def open(self) -> None:
        """Declare the control queryable and the liveliness token: clients can reach us.
        Watch the clients' tokens: a step job whose client vanishes ends (docs/protocol.md)."""
        self._clients = self.session.liveliness().declare_subscriber(
            CLIENTS_PATTERN, self._on_client_token, history=True)
        self._queryable = self.session.declare_queryable(self.keys.control_all, self._on_query)
        self._token = self.session.liveliness().declare_token(self.keys.alive)
        if self.options.ros2 is not None:
            from galton.daemon.fronts.ros2.front import (
                Ros2Front,  # [ros2] extra: imported here only
            )
            self.ros2 = Ros2Front(self.session, self.dispatch, self.options.instance,
                                  self.options.ros2)

    def _client_alive(self, client: str) -> bool:
        """Whether the client's liveliness token is there: seen by the subscriber (no wait),
        else asked once (a token declared a moment ago may not have reached us yet; the get
        holds the physics thread, under a millisecond on loopback)."""
        if client in self._live_clients:
            return True
        replies = self.session.liveliness().get(client_token_key(client),
                                                timeout=CLIENT_TOKEN_TIMEOUT_S)
        return any(reply.ok is not None for reply in replies)

    def _on_client_token(self, sample: zenoh.Sample) -> None:
        client = client_from_token_key(str(sample.key_expr))
        if client is None:
            return
        if sample.kind == zenoh.SampleKind.PUT:
            self._live_clients.add(client)
        else:
            self._live_clients.discard(client)
            self.loop.submit(Task(lambda: self.loop.client_gone(client)))

    def start(self) -> None:
        """Serve with the physics loop on a thread of its own (for embedding in a process
        that has other work on its main thread)."""
        self._thread = threading.Thread(target=self.loop.run, name="physics", daemon=True)
        self._thread.start()
        self.open()

    def withdraw(self) -> None:
        """Withdraw liveliness and stop the physics loop; it answers what is pending."""
        if self._token is not None:
            self._token.undeclare()
            self._token = None
        self.loop.stop()

    def close(self) -> None:
        """Withdraw liveliness first, answer what is pending, then close the session."""
        self.withdraw()
        if self._thread is not None:
            self._thread.join(timeout=10)
        if self._queryable is not None:
            self._queryable.undeclare()
        if self._clients is not None:
            self._clients.undeclare()
        if self.ros2 is not None:
            self.ros2.close()
        self.loop.streams.stop_sender()
        self.loop.world.engine.close()
        if self.front is not None:
            self.front.close()
        self.session.close()

    def _on_query(self, query: zenoh.Query) -> None:
        op = op_from_control_key(str(query.key_expr))
        payload = query.payload.to_bytes() if query.payload is not None else b""
        self.dispatch(Call(op, payload, _responder(query)))

    def dispatch(self, call: Call) -> None:
        """Hand a request to the physics thread, or answer a fast one on this thread: the
        one path of every Zenoh front (this one's queryable, the ROS 2 front's)."""
        declared = OPERATIONS.get(call.op)
        if declared is not None and declared.fast:
            self.loop.handle_readonly(call)
        else:
            self.loop.submit(call)

    def _publish_telemetry(self, sample: Telemetry) -> None:
        data = msgpack.packb(sample.to_wire())
        self._telemetry_pub.put(data)
        if self.front is not None:
            self.front.publish("telemetry", data)

    def _publish_states(self, topic: str, data: bytes) -> None:
        """A state stream's sample (daemon/world/state_streams.py), dropped rather than queued
        when the network is congested, as telemetry is; on the sender's thread."""
        self.session.put(f"{self.keys.prefix}/{topic}", data,
                         congestion_control=zenoh.CongestionControl.DROP)

    def _publish_event(self, event: dict[str, Any]) -> None:
        data = msgpack.packb({"instance": self.options.instance, **event})
        self._events_pub.put(data)
        if self.front is not None:
            self.front.publish("events", data)


def _zmq_front(options: DaemonOptions, loop: SimLoop) -> ZmqFront | None:
    """With --zmq: the ZeroMQ sockets, polled by the physics thread through its inbox, and
    advertised by ``capabilities``."""
    if not options.zmq:
        return None
    if options.users is not None and options.zmq_key is None:
        raise InvalidArgumentError(
            "--users with --zmq needs --zmq-key: an unauthenticated ZeroMQ front would let "
            "anyone on it past the users file (make a key pair with `galton-client zmq-keys "
            "DIR`)")
    security = (ZmqSecurity.load(options.zmq_key, options.users)
                if options.zmq_key is not None else None)
    front = ZmqFront([parse_endpoint(endpoint) for endpoint in options.zmq], options.instance,
                     security)
    loop.inbox = PolledInbox(front, lambda peer: Task(lambda: loop.client_gone(peer)))
    loop.advertised = {"zmq": front.advertised()}
    return front


def _responder(query: zenoh.Query) -> Callable[[bytes], None]:
    def respond(data: bytes) -> None:
        try:
            query.reply(query.key_expr, data)
        finally:
            query.drop()
    return respond


def signal_wakeup_pipe() -> int:
    """Route SIGINT and SIGTERM to a pipe and return its read end: a thread blocked reading
    it wakes on either signal, and the handlers themselves run no Python code that matters."""
    wake_read, wake_write = os.pipe()
    os.set_blocking(wake_write, False)
    signal.set_wakeup_fd(wake_write)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: None)
    return wake_read


class StopSignals:
    """SIGINT and SIGTERM as the wakeup pipe delivers them: a watcher thread ``wait``s for
    one, and a request about to hold the interpreter for seconds asks first whether one
    came (``received``: also one still in the pipe, which the watcher has not read yet)."""

    def __init__(self) -> None:
        self._read = signal_wakeup_pipe()
        self._received = threading.Event()

    def wait(self) -> None:
        os.read(self._read, 1)
        self._received.set()

    def received(self) -> bool:
        return self._received.is_set() or bool(select.select([self._read], [], [], 0)[0])


@contextmanager
def sigterm_ends_at_once(signals: StopSignals) -> Iterator[None]:
    """Inside a scene-changing request, SIGTERM takes its default action: the process ends
    at once. An engine call (a 100,000-body spawn, a compile) may hold the GIL for seconds,
    so no Python handler or watcher could run until it returns; outside such requests the
    stop is graceful. A request that comes to its work after a stop signal (one that landed
    while its payload was decoded) is refused, not begun: begun, it would hold the GIL past
    SHUTDOWN_GRACE_S (5.8 s for a 100,000-body PyBullet spawn). Costs two signal() calls
    and a poll of the pipe, about 5 µs."""
    previous = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        if signals.received():
            raise OperationFailedError("the daemon is shutting down (SIGTERM or SIGINT); "
                                       "the request was not begun")
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def run_daemon(options: DaemonOptions, announce: Callable[[str], None] = print) -> int:
    """Serve until SIGINT or SIGTERM; return the exit code (0 on a clean stop).

    The physics loop runs on the main thread, which has nothing else to do: on the
    long-lived thread it had before, the same MuJoCo trial cost about 4 % more CPU, for
    reasons not found (docs/PERFORMANCE.md, "Bridge overhead"). The signal handlers do
    nothing themselves: Python's C-level handler writes each signal to a wakeup pipe,
    whichever thread the kernel chose, and a watcher thread waiting on that pipe stops the
    loop. No Python code runs inside a lock, so a second signal cannot deadlock shutdown.
    """
    signals = StopSignals()
    daemon = Daemon(options)
    daemon.loop.work_guard = lambda: sigterm_ends_at_once(signals)
    if options.state_dir is not None:
        options.state_dir.mkdir(parents=True, exist_ok=True)
        daemon.loop.schedule_checkpoints(daemon.save_checkpoint, options.checkpoint_period_s)
    daemon.open()

    def stop_on_signal() -> None:
        signals.wait()
        daemon.withdraw()
        if not daemon.finished.wait(SHUTDOWN_GRACE_S):
            log.warning("a request still held the physics thread %.1f s after the signal: "
                        "exiting without it", SHUTDOWN_GRACE_S)
            os._exit(0)
    threading.Thread(target=stop_on_signal, name="signals", daemon=True).start()
    zmq = f" zmq={','.join(daemon.front.control)}" if daemon.front is not None else ""
    announce(f"galton-daemon ready: instance={options.instance} engine={options.engine} "
             f"listen={','.join(listening_on(options))}{zmq} engines={','.join(ENGINE_CLASSES)}")
    try:
        daemon.loop.run()
        daemon.save_checkpoint()  # on SIGTERM or SIGINT, after the last request
        daemon.finished.set()
    finally:
        daemon.close()
    return 0
