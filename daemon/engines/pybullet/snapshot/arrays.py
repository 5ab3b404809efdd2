"""Plain data for PyBullet snapshots: arrays as little-endian bytes with their shape beside
them, and the checked reading of a snapshot that came from anywhere (a client, a file).

A snapshot is untrusted input: every reader here checks a value's type, length, shape and
range, and raises InvalidArgumentError naming the field (``where``) and what was wrong.
Nothing is ever unpickled or evaluated.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from galton.protocol import InvalidArgumentError
from galton.protocol.errors import brief
from galton.protocol.model import check_name, check_type, finite_number

F64 = np.dtype("<f8")
DTYPES = {"f8": F64}  # the dtypes a snapshot's arrays may have, by their tag


def pack(values: Any) -> dict[str, Any]:
    """An array of numbers as {"dtype", "shape", "data"}: little-endian float64 bytes."""
    array = np.ascontiguousarray(values, dtype=F64)
    return {"dtype": "f8", "shape": list(array.shape), "data": array.tobytes()}


def unpack(value: Any, shape: Sequence[int], where: str, *, finite: bool = True,
           allow_inf: bool = False) -> np.ndarray:
    """The array packed in ``value``, checked to have exactly ``shape``; NaN and infinity
    refused with ``finite`` (infinity allowed again with ``allow_inf``)."""
    fields(value, ("dtype", "shape", "data"), where)
    if not isinstance(value["dtype"], str) or value["dtype"] not in DTYPES:
        raise InvalidArgumentError(f"{where}.dtype must be one of {', '.join(DTYPES)}, "
                                   f"got {brief(value['dtype'])}")
    got = check_type(value["shape"], list, f"{where}.shape")
    if got != list(shape) or any(isinstance(n, bool) for n in got):
        raise InvalidArgumentError(f"{where} has shape {brief(got)}; expected {list(shape)}")
    data = check_type(value["data"], (bytes, bytearray), f"{where}.data")
    dtype = DTYPES[value["dtype"]]
    if len(data) != math.prod(shape) * dtype.itemsize:
        raise InvalidArgumentError(f"{where}.data holds {len(data)} bytes; shape {list(shape)} "
                                   f"of {value['dtype']} takes {math.prod(shape) * dtype.itemsize}")
    array = np.frombuffer(data, dtype=dtype).reshape(shape).astype(np.float64)
    if finite:
        bad = np.isnan(array) if allow_inf else ~np.isfinite(array)
        if bad.any():
            raise InvalidArgumentError(f"{where} holds NaN or infinity")
    return array


def fields(value: Any, keys: Sequence[str], where: str) -> dict[str, Any]:
    """``value`` as a dict holding exactly ``keys`` (no more, no fewer)."""
    record: dict[str, Any] = check_type(value, dict, where)
    missing = [key for key in keys if key not in record]
    if missing:
        raise InvalidArgumentError(f"{where}: missing field {missing[0]!r}")
    extra = [key for key in record if key not in keys]
    if extra:
        raise InvalidArgumentError(f"{where} has an unknown field {brief(extra[0])}; "
                                   f"it holds: {', '.join(keys)}")
    return record


def flag(value: Any, where: str) -> bool:
    result: bool = check_type(value, bool, where)
    return result


def text(value: Any, where: str) -> str:
    result: str = check_type(value, str, where)
    return result


def count(value: Any, where: str, *, high: int) -> int:
    """A whole number in [0, high]."""
    number: int = check_type(value, int, where)
    if not 0 <= number <= high:
        raise InvalidArgumentError(f"{where} must be a whole number in [0, {high}], "
                                   f"got {brief(number)}")
    return number


def number(value: Any, where: str, *, low: float = -math.inf,
           high: float = math.inf) -> float:
    return finite_number(value, where, low=low, high=high)


def optional(value: Any, where: str, **bounds: float) -> float | None:
    return None if value is None else number(value, where, **bounds)


def numbers(value: Any, length: int, where: str, **bounds: float) -> tuple[float, ...]:
    """A list of exactly ``length`` finite numbers."""
    check_type(value, list, where)
    if len(value) != length:
        raise InvalidArgumentError(f"{where} must hold {length} numbers, got {len(value)}")
    return tuple(number(v, f"{where}[{i}]", **bounds) for i, v in enumerate(value))


def flags(value: Any, length: int, where: str) -> list[bool]:
    """A list of exactly ``length`` booleans."""
    check_type(value, list, where)
    if len(value) != length or not all(isinstance(v, bool) for v in value):
        raise InvalidArgumentError(f"{where} must be a list of {length} booleans")
    return list(value)


def names(value: Any, where: str, *, length: int | None = None,
          hidden: bool = False) -> list[Any]:
    """A list of valid entity names (None allowed with ``hidden``), all different."""
    check_type(value, list, where)
    if length is not None and len(value) != length:
        raise InvalidArgumentError(f"{where} must hold {length} names, got {len(value)}")
    out = [None if hidden and name is None else check_name(name, f"{where}[{i}]")
           for i, name in enumerate(value)]
    shown = [name for name in out if name is not None]
    if len(set(shown)) != len(shown):
        raise InvalidArgumentError(f"{where} names an entity more than once")
    return out


def unique(seen: set[str], new: Sequence[str | None], where: str) -> None:
    """Refuse a name already used elsewhere in the snapshot; add the new ones."""
    for name in new:
        if name is not None:
            if name in seen:
                raise InvalidArgumentError(f"{where}: the name {name!r} is used twice")
            seen.add(name)
