"""A real browser for the view's tests: Debian's headless Chromium (software WebGL),
driven over the DevTools protocol, so that one page stays open and is photographed as often
as a test asks (a ``--screenshot`` run opens a new page each time and guesses when the
page is drawn)."""

from __future__ import annotations

import base64
import contextlib
import io
import json
import os
import re
import shutil
import signal
import subprocess
import tempfile
import time
import urllib.request
from collections.abc import Callable
from typing import Any

import numpy as np
from websockets.sync.client import ClientConnection, connect

CHROMIUM = shutil.which("chromium-headless-shell")
FLAGS = ("--no-sandbox", "--enable-unsafe-swiftshader", "--use-gl=angle",
         "--use-angle=swiftshader", "--remote-debugging-port=0")
TEST_SCALE = 0.5  # a quarter of the pixels: software GL is slow
START_TIMEOUT_S = 60.0
CALL_TIMEOUT_S = 150.0  # a screenshot waits for a frame: seconds on a loaded machine
DEVTOOLS_LINE = re.compile(r"DevTools listening on (ws://\S+)")


class Browser:
    """One headless Chromium showing one page; ``close`` ends it."""

    def __init__(self, url: str, width: int, height: int, scale: float = TEST_SCALE) -> None:
        assert CHROMIUM is not None, "chromium-headless-shell is not installed"
        self._profile = tempfile.TemporaryDirectory(prefix="galton-chromium-")
        self._process = subprocess.Popen(
            [CHROMIUM, *FLAGS, f"--window-size={width},{height}",
             f"--force-device-scale-factor={scale}",
             f"--user-data-dir={self._profile.name}", url],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
            start_new_session=True)  # its GPU and renderer processes end with its group
        self._page = connect(self._page_socket(), max_size=None)
        self._ids = 0

    def _page_socket(self) -> str:
        """The DevTools address of the page, from the line Chromium prints when it starts."""
        assert self._process.stderr is not None
        for line in self._process.stderr:
            found = DEVTOOLS_LINE.search(line)
            if found:
                port = found.group(1).split(":")[2].split("/")[0]
                break
        else:
            raise RuntimeError("chromium-headless-shell ended without serving DevTools")
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as r:
            pages = [t for t in json.load(r) if t.get("type") == "page"]
        return str(pages[0]["webSocketDebuggerUrl"])

    def _call(self, socket: ClientConnection, method: str, **params: Any) -> dict[str, Any]:
        self._ids += 1
        socket.send(json.dumps({"id": self._ids, "method": method, "params": params}))
        while True:
            message = json.loads(socket.recv(timeout=CALL_TIMEOUT_S))
            if message.get("id") == self._ids:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return dict(message.get("result", {}))

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression in the page (JSON-able values only)."""
        result = self._call(self._page, "Runtime.evaluate", expression=expression,
                            returnByValue=True)
        return result.get("result", {}).get("value")

    def reload(self, timeout: float = START_TIMEOUT_S) -> None:
        """Load the page again, as a user pressing F5 (a new document, a new connection),
        returning once the old document is gone (what is read next is the new one's)."""
        self.evaluate("window.__galtonOldPage = true")
        self._call(self._page, "Page.reload", ignoreCache=True)
        deadline = time.monotonic() + timeout
        while self.evaluate("window.__galtonOldPage === true"):
            assert time.monotonic() < deadline, f"the page did not reload in {timeout} s"
            time.sleep(0.05)  # the old document until the new one replaces it

    def text_until(self, drawn: Callable[[str], bool], timeout: float) -> str:
        """The page's text, read until ``drawn`` says it shows what is awaited;
        AssertionError with the last text after ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        while True:
            text = str(self.evaluate("document.body ? document.body.innerText : ''") or "")
            if drawn(text):
                return text
            assert time.monotonic() < deadline, (
                f"the page did not show what was awaited in {timeout} s; it shows {text!r}")
            time.sleep(0.2)  # polling a page's DOM: nothing to wait on from here

    def screenshot(self) -> np.ndarray:
        """The page as drawn now: RGB, height x width x 3."""
        from PIL import Image
        result = self._call(self._page, "Page.captureScreenshot", format="png")
        image = Image.open(io.BytesIO(base64.b64decode(result["data"])))
        return np.asarray(image.convert("RGB")).astype(int)

    def wait_for(self, drawn: Callable[[np.ndarray], bool], timeout: float) -> np.ndarray:
        """Screenshots until one satisfies ``drawn`` (the page has drawn what is awaited);
        AssertionError with the last one's look after ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        while True:
            image = self.screenshot()
            if drawn(image) or time.monotonic() > deadline:
                assert drawn(image), f"the page did not draw what was awaited in {timeout} s"
                return image

    def close(self) -> None:
        """End the browser and every process it started (a GPU process left behind kept
        a core busy after the test)."""
        self._page.close()
        group = os.getpgid(self._process.pid)
        os.killpg(group, signal.SIGTERM)
        try:
            self._process.wait(30)
        finally:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(group, signal.SIGKILL)
        assert self._process.stderr is not None
        self._process.stderr.close()
        self._profile.cleanup()

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
