"""Starting and stopping a ``galton-daemon`` subprocess on loopback, by its console command.

The client never imports the daemon: it runs the installed ``galton-daemon`` command and
waits for its readiness line and its liveliness token, never for a fixed time.
"""

from __future__ import annotations

import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
from pathlib import Path
from typing import IO

from galton.protocol import DaemonUnreachableError

READY_PREFIX = "galton-daemon ready:"
START_TIMEOUT_S = 60.0


def free_loopback_port() -> int:
    """A TCP port that was free on 127.0.0.1 a moment ago."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def daemon_command() -> list[str]:
    """The installed console command, next to this Python if it is not on PATH."""
    beside = Path(sys.executable).with_name("galton-daemon")
    found = shutil.which("galton-daemon") or (str(beside) if beside.exists() else None)
    if found is None:
        raise DaemonUnreachableError(
            "the galton-daemon command is not installed: run `pip install -e .` in the "
            "galton-bridge checkout")
    return [found]


class EmbeddedDaemon:
    """A daemon subprocess owned by this process; use as a context manager."""

    def __init__(self, engine: str = "mujoco", instance: str | None = None,
                 port: int | None = None, telemetry_rate: float = 10.0,
                 extra_args: list[str] | None = None, zmq: bool = False) -> None:
        self.engine = engine
        self.instance = instance or f"embedded-{engine}"
        self.port = port or free_loopback_port()
        self.endpoint = f"tcp/127.0.0.1:{self.port}"
        # With ``zmq``: a ZeroMQ ipc socket too, in a folder of its own (removed at stop).
        self._socket_dir = tempfile.mkdtemp(prefix="galton-") if zmq else None
        self.zmq_endpoint = (f"zmq+ipc://{self._socket_dir}/{self.instance}.sock"
                             if self._socket_dir else None)
        self.telemetry_rate = telemetry_rate
        self.extra_args = extra_args or []
        self.process: subprocess.Popen[str] | None = None
        self._ready = threading.Event()
        self._watcher: threading.Thread | None = None
        self._output: list[str] = []

    def start(self, timeout: float = START_TIMEOUT_S) -> EmbeddedDaemon:
        """Start the process and return once it says it is ready (or raise why not)."""
        command = [*daemon_command(), "--engine", self.engine, "--instance", self.instance,
                   "--listen", self.endpoint, "--telemetry-rate", str(self.telemetry_rate),
                   *self.extra_args]
        if self.zmq_endpoint is not None:
            command += ["--zmq", self.zmq_endpoint.removeprefix("zmq+")]
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, text=True, bufsize=1)
        self._watcher = threading.Thread(target=self._watch, args=(self.process.stdout,),
                                         daemon=True)
        self._watcher.start()
        if not self._ready.wait(timeout) or self.process.poll() is not None:
            self.stop()
            raise DaemonUnreachableError(
                f"galton-daemon ({self.engine}) did not become ready within {timeout:g} s:\n"
                + "".join(self._output[-20:]))
        return self

    def _watch(self, stream: IO[str] | None) -> None:
        """Read the daemon's output: signal readiness, or its death (EOF)."""
        if stream is None:
            return
        for line in stream:
            self._output.append(line)
            if line.startswith(READY_PREFIX):
                self._ready.set()
        self._ready.set()

    def stop(self, timeout: float = 15.0) -> int | None:
        """SIGTERM, then SIGKILL if it does not exit in time; returns the exit code."""
        if self.process is None:
            return None
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout)
        self._close_output()
        if self._socket_dir is not None:
            shutil.rmtree(self._socket_dir, ignore_errors=True)
        return self.process.returncode

    def _close_output(self) -> None:
        """The process has exited: let the reader reach EOF, then close the pipe."""
        if self._watcher is not None:
            self._watcher.join(5)
        if self.process is not None and self.process.stdout is not None:
            self.process.stdout.close()

    @property
    def output(self) -> str:
        return "".join(self._output)

    def __enter__(self) -> EmbeddedDaemon:
        return self.start() if self.process is None else self

    def __exit__(self, *exc: object) -> None:
        self.stop()
