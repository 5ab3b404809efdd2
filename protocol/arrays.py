"""Bulk numbers travel as packed little-endian float64 rows, never as a map per body."""

from __future__ import annotations

import numpy as np

from galton.protocol.errors import InvalidArgumentError

_WIRE_DTYPE = np.dtype("<f8")


def pack_f64(rows: np.ndarray) -> bytes:
    """Pack an array of numbers as little-endian float64, row-major."""
    return np.ascontiguousarray(rows, dtype=_WIRE_DTYPE).tobytes()


def unpack_f64(data: object, width: int, field: str = "array") -> np.ndarray:
    """Unpack bytes into an (n, width) float64 array, checking the length fits."""
    if not isinstance(data, bytes | bytearray | memoryview):
        raise InvalidArgumentError(
            f"{field} must be msgpack bin of little-endian float64, got {type(data).__name__}"
        )
    size = len(data)
    row_bytes = width * _WIRE_DTYPE.itemsize
    if size % row_bytes:
        raise InvalidArgumentError(
            f"{field} holds {size} bytes, not a whole number of {width}-float64 rows "
            f"({row_bytes} bytes each)"
        )
    return np.frombuffer(data, dtype=_WIRE_DTYPE).reshape(-1, width).astype(np.float64)
