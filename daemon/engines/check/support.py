"""What the engine checks share: the context a check runs in, how a check fails or is
skipped, what it compares, and the small scenes it builds.

A check says what it expected and what it saw, so one failure reads as a bug report. It
knows no engine: it asks ``capabilities()`` what the engine under test can do.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from galton.daemon.engines.base import Engine
from galton.protocol import (
    POSE_WIDTH,
    TWIST_WIDTH,
    BodyGroup,
    GaltonError,
)
from galton.protocol.errors import brief
from galton.protocol.mesh import box_mesh

EngineFactory = Callable[[], Engine]
IDENTITY = (0.0, 0.0, 0.0, 1.0)
DENSITY = 1000.0  # kg/m³: the interface's mass for a body spawned with mass None
STANDARD_GRAVITY = 9.81  # m/s², for an engine with no "gravity" parameter
# Half sizes (metres) of each shape as the checks spawn it: none is a sphere in disguise.
SIZES: dict[str, tuple[float, ...]] = {
    "sphere": (0.05,), "box": (0.05, 0.1, 0.15), "cylinder": (0.05, 0.1),
    "capsule": (0.05, 0.1), "plane": (5.0, 5.0), "mesh": (0.05, 0.1, 0.15)}
# A turn of 0.8 rad about an axis off every coordinate axis: no component of it is special.
_AXIS = np.array([1.0, 2.0, 1.0]) / math.sqrt(6.0)
TURNED = (*(math.sin(0.4) * _AXIS).tolist(), math.cos(0.4))


class CheckFailedError(GaltonError):
    """One check found the engine breaking the interface: what was expected, what was seen."""

    def __init__(self, what: str, expected: str, seen: str) -> None:
        super().__init__(f"{what}: expected {expected}; saw {seen}")
        self.what, self.expected, self.seen = what, expected, seen


class CheckSkippedError(GaltonError):
    """The engine does not offer what a check tests (it says so in its capabilities)."""


@dataclass
class CheckContext:
    """What one check works on: a fresh engine, and a way to make more of them alike."""

    factory: EngineFactory
    params: Mapping[str, Any] = field(default_factory=dict)
    made: list[Engine] = field(default_factory=list)

    @property
    def engine(self) -> Engine:
        """The check's own engine, made on first use."""
        return self.made[0] if self.made else self.fresh()

    def fresh(self) -> Engine:
        """Another engine, as new as the first (the same parameters set), closed after."""
        engine = self.factory()
        self.made.append(engine)
        if self.params:
            engine.set_params(dict(self.params))
        return engine

    def close(self) -> None:
        for engine in self.made:
            engine.close()
        self.made.clear()


# -- expectations --------------------------------------------------------------------------
def expect(condition: bool, what: str, expected: str, seen: object) -> None:
    """Fail with ``what``, ``expected`` and a brief repr of ``seen`` unless ``condition``."""
    if not condition:
        raise CheckFailedError(what, expected, seen if isinstance(seen, str) else brief(seen))


def expect_array(value: object, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``value`` is a float64 ndarray of that shape."""
    expect(isinstance(value, np.ndarray), what, "a numpy array", type(value).__name__)
    array: np.ndarray = value  # type: ignore[assignment]
    expect(array.shape == shape and array.dtype == np.float64, what,
           f"float64 of shape {shape}", f"{array.dtype} of shape {array.shape}")
    return array


def expect_close(seen: np.ndarray, expected: np.ndarray, atol: float, what: str) -> None:
    """Equal within ``atol`` everywhere (NaN is never close); the failure names the worst
    entry."""
    gap = np.abs(np.asarray(seen, dtype=float) - np.asarray(expected, dtype=float))
    gap[np.isnan(gap)] = np.inf
    if gap.size and gap.max() > atol:
        at = tuple(int(i) for i in np.unravel_index(int(np.argmax(gap)), gap.shape))
        raise CheckFailedError(
            what, f"{float(np.asarray(expected)[at])!r} within {atol:g} at {list(at)}",
            f"{float(np.asarray(seen)[at])!r} (off by {float(gap[at]):.3g})")


def expect_identical(seen: np.ndarray, expected: np.ndarray, what: str) -> None:
    """Bit for bit the same numbers (NaN equal to NaN)."""
    if not np.array_equal(seen, expected, equal_nan=True):
        shapes = np.shape(seen) == np.shape(expected)
        gap = np.abs(np.asarray(seen) - np.asarray(expected)) if shapes else np.array(np.inf)
        raise CheckFailedError(what, "bit-identical arrays", f"arrays that differ by up to "
                               f"{float(np.max(np.nan_to_num(gap, nan=np.inf))):.3g}")


def expect_poses(seen: np.ndarray, expected: np.ndarray, atol: float, what: str) -> None:
    """Poses equal within ``atol``, a quaternion and its negative being one rotation."""
    seen = np.array(seen, dtype=float)
    flip = np.einsum("ij,ij->i", seen[:, 3:], np.asarray(expected)[:, 3:]) < 0
    seen[flip, 3:] *= -1.0
    expect_close(seen, expected, atol, what)


@contextmanager
def expect_raises(errors: type[Exception] | tuple[type[Exception], ...],
                  what: str) -> Iterator[None]:
    """The block raises one of ``errors``; anything else, or nothing, fails the check."""
    wanted = errors if isinstance(errors, tuple) else (errors,)
    names = " or ".join(e.__name__ for e in wanted)
    try:
        yield
    except wanted:
        return
    except Exception as exc:  # the wrong error is what the check reports
        raise CheckFailedError(what, names, f"{type(exc).__name__}: {exc}") from exc
    raise CheckFailedError(what, names, "no error")


def skip_unless(engine: Engine, feature: str) -> None:
    """Skip the check when the engine does not list ``feature`` in its capabilities."""
    if feature not in engine.capabilities().features:
        raise CheckSkippedError(f"the engine does not list the {feature!r} feature")


# -- what an engine holds --------------------------------------------------------------------
@dataclass
class Snapshot:
    """Everything a refused call must leave as it was, read through the interface."""

    names: list[str]
    poses: np.ndarray
    twists: np.ndarray
    properties: np.ndarray
    params: dict[str, Any]
    timestep: float

    @classmethod
    def of(cls, engine: Engine, names: Sequence[str]) -> Snapshot:
        poses, twists = engine.get_states(names)
        return cls(list(names), poses, twists, engine.properties(names), engine.get_params(),
                   engine.timestep)

    def expect_same(self, engine: Engine, what: str) -> None:
        """The engine still holds what this snapshot saw, bit for bit."""
        now = Snapshot.of(engine, self.names)
        expect_identical(now.poses, self.poses, f"{what}: poses")
        expect_identical(now.twists, self.twists, f"{what}: twists")
        expect_identical(now.properties, self.properties, f"{what}: properties")
        expect(now.params == self.params, f"{what}: parameters", brief(self.params),
               now.params)
        expect(now.timestep == self.timestep, f"{what}: timestep", repr(self.timestep),
               now.timestep)


# -- scenes ------------------------------------------------------------------------------------
def poses_at(positions: Any, quaternion: Sequence[float] = IDENTITY) -> np.ndarray:
    """(n, 7) poses at these positions, all turned by ``quaternion``."""
    rows = np.atleast_2d(np.asarray(positions, dtype=float))
    return np.column_stack([rows, np.tile(np.asarray(quaternion, dtype=float),
                                          (len(rows), 1))])


def group(shape: str, names: Sequence[str], positions: Any, **options: Any) -> BodyGroup:
    """Bodies of one shape at these positions, of the checks' size for it unless given."""
    size = tuple(options.pop("size", SIZES[shape]))
    quaternion = options.pop("quaternion", IDENTITY)
    twists = options.pop("twists", None)
    if twists is not None:
        twists = np.atleast_2d(np.asarray(twists, dtype=float)).reshape(-1, TWIST_WIDTH)
    if shape == "mesh":  # a box as a triangle mesh
        options["vertices"], options["faces"] = box_mesh((size[0], size[1], size[2]))
    return BodyGroup(shape, size, list(names), poses_at(positions, quaternion),
                     twists=twists, **options)


def ground(name: str = "ground") -> BodyGroup:
    return group("plane", [name], [0.0, 0.0, 0.0], static=True)


def volume(shape: str, size: Sequence[float]) -> float:
    """Volume (m³) of a solid shape from its half sizes (``SIZE_LAYOUT``)."""
    ball = 4.0 / 3.0 * math.pi * size[0] ** 3
    if shape == "sphere":
        return ball
    if shape in ("box", "mesh"):  # the checks' meshes are boxes
        return 8.0 * size[0] * size[1] * size[2]
    cylinder = math.pi * size[0] ** 2 * 2.0 * size[1]
    return cylinder + (ball if shape == "capsule" else 0.0)


def gravity(engine: Engine) -> np.ndarray:
    """The engine's gravity vector (m/s²): its "gravity" parameter, else standard, down."""
    value = engine.get_params().get("gravity", (0.0, 0.0, -STANDARD_GRAVITY))
    return np.asarray(value, dtype=float).reshape(3)


def states(engine: Engine, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """get_states, its shapes checked: (n, 7) poses and (n, 6) twists, float64."""
    poses, twists = engine.get_states(names)
    count = len(names)
    return (expect_array(poses, (count, POSE_WIDTH), f"get_states of {count}: poses"),
            expect_array(twists, (count, TWIST_WIDTH), f"get_states of {count}: twists"))
