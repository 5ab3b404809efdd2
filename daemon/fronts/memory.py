"""Memory a big request leaves behind: Zenoh frees its buffers into glibc's heap, which
keeps the pages (issue 46: one 50 MB payload, refused or not, left the daemon's RSS about
45 MiB up for good). After such a request, once its query is dropped, the heap's free pages
are handed back (glibc's ``malloc_trim``; elsewhere nothing is done)."""

from __future__ import annotations

import ctypes
import ctypes.util
import threading
from typing import Any

BIG_PAYLOAD_BYTES = 1 << 20  # a request this big is followed by a trim
TRIM_AFTER_S = 0.5  # by then its query, and Zenoh's buffers for it, are freed


def _libc() -> Any:
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.malloc_trim.argtypes, libc.malloc_trim.restype = [ctypes.c_size_t], ctypes.c_int
        return libc
    except (OSError, AttributeError):  # not glibc: nothing to trim
        return None


_LIBC = _libc()
_lock = threading.Lock()
_pending: list[threading.Timer] = []


def after_request_of(size: int) -> None:
    """Called for each request's payload size, from any thread: a big one schedules one
    trim (several big ones in a row share it)."""
    if size < BIG_PAYLOAD_BYTES or _LIBC is None:
        return
    with _lock:
        if _pending:
            return
        timer = threading.Timer(TRIM_AFTER_S, _trim)
        timer.daemon = True
        _pending.append(timer)
    timer.start()


def _trim() -> None:
    with _lock:
        _pending.clear()
    _LIBC.malloc_trim(0)
