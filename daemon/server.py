"""The composition root: options, engine, core, fronts and signal handling, wired here and
nowhere else. The fronts themselves live in daemon/fronts/ (Zenoh, ZeroMQ, ROS 2)."""

from __future__ import annotations

import dataclasses
import logging
import os
import select
import signal
import threading
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import zenoh

from galton.daemon.access.users import User
from galton.daemon.access.zenoh_security import TlsFiles, security_settings
from galton.daemon.access.zmq_auth import ZmqSecurity
from galton.daemon.core.limits import DEFAULT_LIMITS, Limits
from galton.daemon.core.loop import SimLoop
from galton.daemon.core.wiring import Checkpoints, LoopWiring
from galton.daemon.engines import ENGINE_CLASSES, create_engine
from galton.daemon.engines.base import Engine
from galton.daemon.fronts.base import Front, Fronts
from galton.daemon.fronts.ros2.options import Ros2Options
from galton.daemon.fronts.zenoh import ZenohFront, merged_config
from galton.daemon.fronts.zmq import ZmqFront, parse_endpoint
from galton.daemon.world import checkpoint
from galton.daemon.world.world import World
from galton.protocol import InvalidArgumentError, OperationFailedError

if TYPE_CHECKING:
    from galton.daemon.fronts.ros2.front import Ros2Front  # the [ros2] extra's

log = logging.getLogger("galton.daemon")

# After SIGTERM the daemon answers what is pending and closes; if a request still holds the
# physics thread this long after the signal, the process exits without waiting for it.
SHUTDOWN_GRACE_S = 1.5


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


def _merged_config(options: DaemonOptions, security: dict[str, Any]) -> zenoh.Config:
    path = options.zenoh_config
    config = zenoh.Config.from_file(str(path)) if path is not None else zenoh.Config()
    return merged_config(config, options.listen, options.connect, options.multicast, security)


class Daemon:
    """One daemon instance: a SimLoop (the core) served by its fronts -- Zenoh always,
    ZeroMQ with --zmq, ROS 2 with --ros2 -- opened, published to and closed as one list.

    ``signals``: the daemon is the process (``run_daemon``): SIGTERM ends a scene-changing
    request at once, and --state-dir checkpoints the live world periodically."""

    def __init__(self, options: DaemonOptions, signals: StopSignals | None = None) -> None:
        self.options = options
        engine = create_engine(options.engine)
        if options.params:
            engine.set_params(options.params)
        self.fronts = _fronts(options)
        self.loop = SimLoop(self._first_world(engine), self._wiring(signals))
        self._thread: threading.Thread | None = None
        self.finished = threading.Event()

    def ready_line(self) -> str:
        """What ``run_daemon`` prints once it serves: users and tests parse it."""
        options = self.options
        return (f"galton-daemon ready: instance={options.instance} engine={options.engine} "
                f"{self.fronts.ready_words()} engines={','.join(ENGINE_CLASSES)}")

    def _wiring(self, signals: StopSignals | None) -> LoopWiring:
        """Everything the loop is given, once: publishing to every front, the front it
        polls, what it advertises, and with ``signals`` the process's own hooks."""
        options = self.options
        checkpoints = (Checkpoints(self.save_checkpoint, options.checkpoint_period_s)
                       if signals is not None and options.state_dir is not None else None)
        return LoopWiring(
            options.instance, publish=self.fronts.publish,
            telemetry_rate_hz=options.telemetry_rate_hz, engine_factory=create_engine,
            limits=options.limits, polled=self.fronts.polled(), snapshot_key=options.snapshot_key,
            advertised=self.fronts.advertised, client_alive=self.fronts.client_alive,
            work_guard=((lambda: sigterm_ends_at_once(signals)) if signals is not None
                        else nullcontext),
            checkpoints=checkpoints)

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
        """Open every front on the core's call interface: clients can reach us."""
        self.fronts.open(self.loop.intake)

    def start(self) -> None:
        """Serve with the physics loop on a thread of its own (for embedding in a process
        that has other work on its main thread)."""
        self._thread = threading.Thread(target=self.loop.run, name="physics", daemon=True)
        self._thread.start()
        self.open()

    def withdraw(self) -> None:
        """Withdraw from every front and stop the physics loop; it answers what is pending."""
        self.fronts.withdraw()
        self.loop.stop()

    def close(self) -> None:
        """Withdraw first, answer what is pending, then close the fronts (last opened
        first) and the engine."""
        self.withdraw()
        if self._thread is not None:
            self._thread.join(timeout=10)
        self.loop.world.engine.close()
        self.loop.slots.close()
        self.fronts.close()


def _fronts(options: DaemonOptions) -> Fronts:
    """Every front the options ask for, in the order they open (Zenoh first: ROS 2 rides on
    its session); what was built is closed again if a later one fails. A new front is one
    factory here (its options in, the front out) and one line in this list."""
    zmq_front = _zmq_front(options)  # first: a bad endpoint fails before Zenoh opens
    built: list[Front] = [zmq_front] if zmq_front is not None else []
    try:
        zenoh_front = ZenohFront(zenoh_config(options), options.instance)
        built.insert(0, zenoh_front)
        ros2_front = _ros2_front(options, zenoh_front)
        if ros2_front is not None:
            built.append(ros2_front)
    except BaseException:
        for front in built:
            front.close()
        raise
    return Fronts(built)


def _zmq_front(options: DaemonOptions) -> ZmqFront | None:
    """With --zmq: the ZeroMQ sockets, polled by the physics thread (the core's
    ``PolledInbox``), and advertised by ``capabilities``."""
    if not options.zmq:
        return None
    if options.users is not None and options.zmq_key is None:
        raise InvalidArgumentError(
            "--users with --zmq needs --zmq-key: an unauthenticated ZeroMQ front would let "
            "anyone on it past the users file (make a key pair with `galton-client zmq-keys "
            "DIR`)")
    security = (ZmqSecurity.load(options.zmq_key, options.users)
                if options.zmq_key is not None else None)
    return ZmqFront([parse_endpoint(endpoint) for endpoint in options.zmq], options.instance,
                    security, silence_s=options.limits.zmq_silence_s)


def _ros2_front(options: DaemonOptions, zenoh_front: ZenohFront) -> Ros2Front | None:
    """With --ros2: the ROS 2 node, on the Zenoh front's session (its [ros2] extra is
    imported only here), refusing requests over the daemon's max_request_bytes."""
    if options.ros2 is None:
        return None
    from galton.daemon.fronts.ros2.front import Ros2Front  # [ros2] extra: imported here only
    return Ros2Front(zenoh_front.session, options.instance, dataclasses.replace(
        options.ros2, max_request_bytes=options.limits.max_request_bytes))


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
    if options.state_dir is not None:
        options.state_dir.mkdir(parents=True, exist_ok=True)
    daemon = Daemon(options, signals)
    daemon.open()

    def stop_on_signal() -> None:
        signals.wait()
        daemon.withdraw()
        if not daemon.finished.wait(SHUTDOWN_GRACE_S):
            log.warning("a request still held the physics thread %.1f s after the signal: "
                        "exiting without it", SHUTDOWN_GRACE_S)
            os._exit(0)
    threading.Thread(target=stop_on_signal, name="signals", daemon=True).start()
    announce(daemon.ready_line())
    try:
        daemon.loop.run()
        daemon.save_checkpoint()  # on SIGTERM or SIGINT, after the last request
        daemon.finished.set()
    finally:
        daemon.close()
    return 0
