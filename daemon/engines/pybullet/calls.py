"""PyBullet's own failures (a lost connection, a refused call) as the Engine contract's
OperationFailedError."""

from __future__ import annotations

import functools
import typing
from collections.abc import Callable
from typing import TypeVar

import pybullet

from galton.protocol import OperationFailedError

_P = typing.ParamSpec("_P")
_R = TypeVar("_R")


def engine_call(method: Callable[_P, _R]) -> Callable[_P, _R]:
    """Wrap an engine method: pybullet.error becomes OperationFailedError."""
    @functools.wraps(method)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        try:
            return method(*args, **kwargs)
        except pybullet.error as exc:
            raise OperationFailedError(f"PyBullet {method.__name__} failed: {exc}") from exc
    return wrapper
