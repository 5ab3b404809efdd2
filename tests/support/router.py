"""A ``galton-client router`` process for tests: started by its console command on a free
loopback port, ready when it prints its ready line (never after a fixed time)."""

from __future__ import annotations

import subprocess
import threading
from typing import IO

from galton.client.cli.router import READY_PREFIX
from galton.client.sdk.embedded import free_loopback_port
from support.cli import CONSOLE_COMMAND

START_TIMEOUT_S = 30.0


class RouterProcess:
    """A Zenoh router subprocess on 127.0.0.1; a context manager."""

    def __init__(self) -> None:
        self.endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
        self.process: subprocess.Popen[str] | None = None
        self.output: list[str] = []
        self._ready = threading.Event()
        self._reader: threading.Thread | None = None

    def __enter__(self) -> RouterProcess:
        self.process = subprocess.Popen(
            [CONSOLE_COMMAND, "router", "--listen", self.endpoint], stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, text=True, bufsize=1)
        self._reader = threading.Thread(target=self._read, args=(self.process.stdout,),
                                        daemon=True)
        self._reader.start()
        if not self._ready.wait(START_TIMEOUT_S) or self.process.poll() is not None:
            self.__exit__()
            raise AssertionError("the router did not start:\n" + "".join(self.output))
        return self

    def _read(self, stream: IO[str] | None) -> None:
        if stream is None:
            return
        for line in stream:
            self.output.append(line)
            if line.startswith(READY_PREFIX):
                self._ready.set()
        self._ready.set()  # EOF: it died; the waiter checks poll()

    def __exit__(self, *exc: object) -> None:
        """SIGTERM; a router must then exit by itself, with code 0."""
        if self.process is None:
            return
        if self.process.poll() is None:
            self.process.terminate()
        code = self.process.wait(15)
        if self._reader is not None:
            self._reader.join(5)
        if self.process.stdout is not None:
            self.process.stdout.close()
        self.returncode = code
