"""The Galton board as a typed, serialisable specification (``BoardSpec``) and its presets.

Every result should record the exact board that made it, so a board is plain data: nested
frozen dataclasses that go to and from dicts, JSON and TOML, checked on construction.
Units are SI (m, kg, s); z is up, x runs across the board, y is its depth (the front glass
is at -y, the back wall at +y). The defaults are the ``paper`` board.

Errors: ``BoardSpecError`` (an ``AnalysisError`` and a ``ValueError``) names the offending
field by its dotted path (``funnel.opening``), the value, and what would be right.

The layout derived from a spec (pin centres, dividers, funnel) and the checks live in
``board_layout``; primitives in ``board_geometry``; ball release and per-repetition
perturbation in ``board_release``; bins and ball outcomes in ``board_scoring``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, is_dataclass
from pathlib import Path
from types import UnionType
from typing import Any

from galton.analysis.board_layout import did_you_mean, spec_problems
from galton.analysis.errors import AnalysisError

PAPER_PINS_PER_ROW = (1, 8, 9, 10, 11, 10, 11, 10, 11, 10, 11)


class BoardSpecError(AnalysisError, ValueError):
    """A board specification field is missing, mistyped or out of range; ``field`` names it."""

    def __init__(self, field: str, problem: str) -> None:
        super().__init__(f"{field}: {problem}")
        self.field = field
        self.problem = problem


@dataclass(frozen=True)
class PinSpec:
    """The pin field: cylinders along y on a lattice whose alternate rows shift by pitch / 2.

    ``per_row`` counts pins from the top; None gives the classic triangle 1, 2, ..., rows.
    """

    radius: float = 0.10
    length: float = 0.55
    pitch: float = 0.50
    row_pitch: float = 0.20
    top_row_z: float = 4.104
    per_row: tuple[int, ...] | None = PAPER_PINS_PER_ROW


@dataclass(frozen=True)
class FunnelSpec:
    """Two slanted boxes; each is placed by its upper (ball-facing) surface.

    That surface runs from the inner tip (x = +-opening / 2, z = tip_z) up at ``angle_deg``
    to x = +-outer_x; the box hangs ``thickness`` below it, normal to the slope.
    """

    angle_deg: float = 20.0
    opening: float = 0.30
    tip_z: float = 4.615
    thickness: float = 0.30
    outer_x: float = 2.75


@dataclass(frozen=True)
class DividerSpec:
    """Bin dividers standing on the floor; None x positions put them under the lowest pins."""

    thickness: float = 0.10
    height: float = 2.0
    x_positions: tuple[float, ...] | None = None


@dataclass(frozen=True)
class WallSpec:
    """The two side walls; ``inner_x`` is the distance of their inner faces from x = 0."""

    inner_x: float = 2.75
    thickness: float = 0.10
    height: float = 7.0


@dataclass(frozen=True)
class CavitySpec:
    """The space between the front glass (at centre_y - depth / 2) and the back wall."""

    depth: float = 0.55
    centre_y: float = 0.0
    glass_thickness: float = 0.10
    back_thickness: float = 0.10


@dataclass(frozen=True)
class FloorSpec:
    """A box whose top face is at ``z``."""

    z: float = 0.0
    thickness: float = 0.10


@dataclass(frozen=True)
class BallSpec:
    """The balls: spheres of water density by default (0.045 m gives 0.3817 kg)."""

    radius: float = 0.045
    mass: float = 0.3817
    count: int = 100
    # A diagonal inertia (kg m², each axis) in place of a solid ball's 2/5 m r²: the
    # paper's Gazebo draft gave 0.1 (a copy error); None keeps the solid ball's.
    inertia: float | None = None

    @property
    def density(self) -> float:
        return self.mass / (4.0 / 3.0 * math.pi * self.radius**3)


@dataclass(frozen=True)
class ReleaseSpec:
    """How balls enter: "all-at-once" (a jittered cloud above the funnel) or "stream".

    ``interval`` (s of sim time) and ``stream_height`` (m above the funnel tip) apply to the
    stream; ``gap`` is the least free space between neighbours and walls at release.
    """

    mode: str = "all-at-once"
    interval: float = 0.2
    stream_height: float = 0.10
    gap: float = 0.005


@dataclass(frozen=True)
class PerturbationSpec:
    """Per-repetition changes, as the paper made: a board shift along x and ball jitter.

    The board shift is normal with ``board_shift_std`` (clipped to 3 std); each ball moves
    uniformly within +-``ball_jitter`` per axis.
    """

    board_shift_std: float = 0.002
    ball_jitter: float = 0.01


@dataclass(frozen=True)
class SurfaceSpec:
    """Contact properties of one body role in one engine; None keeps the engine default."""

    friction: float | None = None
    restitution: float | None = None


@dataclass(frozen=True)
class EngineContacts:
    """One engine's settings: daemon parameters (by their daemon names) and per-role surfaces."""

    params: dict[str, Any] = field(default_factory=dict)
    bodies: dict[str, SurfaceSpec] = field(default_factory=dict)


def _default_contacts() -> dict[str, EngineContacts]:
    return paper_materials()


MATERIALS = ("board", "engine")


@dataclass(frozen=True)
class BoardSpec:
    """A whole Galton board, its balls and how to run them; validated on construction."""

    name: str = "paper"
    rows: int = 11
    bins: int = 12
    seed: int = 0
    pins: PinSpec = field(default_factory=PinSpec)
    funnel: FunnelSpec = field(default_factory=FunnelSpec)
    dividers: DividerSpec = field(default_factory=DividerSpec)
    walls: WallSpec = field(default_factory=WallSpec)
    cavity: CavitySpec = field(default_factory=CavitySpec)
    floor: FloorSpec = field(default_factory=FloorSpec)
    ball: BallSpec = field(default_factory=BallSpec)
    release: ReleaseSpec = field(default_factory=ReleaseSpec)
    perturbation: PerturbationSpec = field(default_factory=PerturbationSpec)
    # Each engine's contact settings and per-role surfaces: the board's materials, which
    # travel with it. An engine named takes exactly what is given (nothing: the engine's
    # own defaults); an engine not named keeps the paper's (``paper_materials``).
    contacts: dict[str, EngineContacts] = field(default_factory=_default_contacts)
    # "board": the trials use ``contacts``; "engine": they ignore them, and the board runs
    # on each engine's own defaults (``galton-client bench --materials engine``).
    materials: str = "board"
    # How the board's solids are spawned: "primitives" (boxes and cylinders) or "mesh"
    # (each part a triangle mesh: a pin a prism of PIN_SIDES sides, a box a box).
    parts: str = "primitives"

    def __post_init__(self) -> None:
        problem = next(spec_problems(self), None)
        if problem is None and self.materials not in MATERIALS:
            problem = ("materials", f"must be one of {', '.join(MATERIALS)}, got "
                                    f"{self.materials!r}")
        if problem is not None:
            raise BoardSpecError(*problem)
        # An engine the contacts do not name keeps the paper's materials.
        object.__setattr__(self, "contacts", {**paper_materials(), **self.contacts})

    def engine_contacts(self, engine: str) -> EngineContacts:
        """What a trial on this engine sets: the board's materials there, or nothing (the
        engine's own defaults) when the board runs with ``materials = "engine"``."""
        if self.materials == "engine":
            return EngineContacts()
        return self.contacts.get(engine, EngineContacts())

    def to_dict(self) -> dict[str, Any]:
        """Plain data (dicts, lists, numbers, strings, None), ready for JSON."""
        plain: dict[str, Any] = _plain(self)
        return plain

    def to_json(self, indent: int | None = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> BoardSpec:
        """Build from plain data; missing fields take the defaults (the paper board)."""
        spec: BoardSpec = _build(cls, data, "")
        return spec

    @classmethod
    def from_json(cls, text: str) -> BoardSpec:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as err:
            raise BoardSpecError("board", f"is not valid JSON: {err}") from err
        return cls.from_dict(data)

    @classmethod
    def from_toml_string(cls, text: str) -> BoardSpec:
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as err:
            raise BoardSpecError("board", f"is not valid TOML: {err}") from err
        return cls.from_dict(data)

    @classmethod
    def from_toml(cls, path: str | Path) -> BoardSpec:
        return cls.from_toml_string(_read(Path(path)))

    @classmethod
    def load(cls, source: str | Path) -> BoardSpec:
        """A preset by name ("paper", "small") or a ``.toml`` / ``.json`` file by path."""
        if isinstance(source, str) and source in PRESETS:
            return PRESETS[source]()
        path = Path(source)
        if path.suffix in (".toml", ".json") or path.exists():
            text = _read(path)
            return cls.from_json(text) if path.suffix == ".json" else cls.from_toml_string(text)
        raise BoardSpecError("board", f"{str(source)!r} is neither a preset nor a file"
                             f"{did_you_mean(str(source), PRESETS)}; presets: "
                             f"{', '.join(PRESETS)}")

    def replace(self, **changes: Any) -> BoardSpec:
        """A copy with some top-level fields changed, validated again."""
        return dataclasses.replace(self, **changes)


# --- presets -------------------------------------------------------------------------------


def paper_board() -> BoardSpec:
    """The board of the paper's public model (msegoferre/galton_board, galton.dae).

    Read off the model: 11 rows of r = 0.10 m pins, 0.55 m long, at z = 2.104 .. 4.104;
    1, 8, 9, 10, 11, 10, 11, ... pins a row on a 0.5 m lattice; 11 dividers 0.1 x 2.0 m under
    the lowest row; side walls' inner faces at +-2.75 m, 7 m tall; funnel walls 0.30 m
    thick at 20 deg whose inner tips leave 0.30 m (the model's inner faces are at
    x = +-0.152). See ``board_layout`` for how the rows meet the bins.

    Two deliberate changes: the board is centred on y = 0 (the model's pins are centred at
    y = 0.209), and each funnel wall runs on to the side wall, where the model's stops
    0.11 m short and leaves a pocket that would hold balls.
    """
    return BoardSpec()


# --- the board's materials -------------------------------------------------------------------
# The paper board's contacts, calibrated per engine on it (docs/PHYSICS.md, "The board's
# materials"): a hard ball on hard wood. Each engine's world starts with that engine's own
# defaults; the board brings these, on every body it spawns.
SCENERY_ROLES = ("pin", "funnel", "divider", "wall", "glass", "floor")
# MuJoCo: the scenery's bounce 0.61 (measured e 0.70) and the balls' 0.3 (two balls meet at
# e 0.37), friction 0.5 on both; a stiffer impedance floor (dmin 0.8), torsional friction
# (condim 4) and the elliptic cone, with which piles sleep.
MUJOCO_SCENERY = SurfaceSpec(friction=0.5, restitution=0.61)
MUJOCO_BALL = SurfaceSpec(friction=0.5, restitution=0.3)
MUJOCO_SETTINGS: dict[str, Any] = {"mujoco.solimp": [0.8, 0.95, 0.001, 0.5, 2.0],
                                   "mujoco.condim": 4, "mujoco.cone": "elliptic"}
# PyBullet multiplies two bodies' values: 0.8275 on every body is e 0.685 (measured 0.70-0.72)
# and friction 0.5 is mu 0.25; contacts from 0.01 m keep a slow ball's bounce; pyramid
# friction is cheaper and changes nothing on the board.
PYBULLET_SURFACE = SurfaceSpec(friction=0.5, restitution=0.8275)
PYBULLET_SETTINGS: dict[str, Any] = {"pybullet.contact_breaking_threshold": 0.01,
                                     "pybullet.enable_cone_friction": False}
# ODE and DART run the board as Webots and Gazebo would: their own contact (Webots' friction 1
# and bounce 0.5; SDF's friction 1 and restitution 0), stated on the board all the same.
ODE_SURFACE = SurfaceSpec(friction=1.0, restitution=0.5)
DART_SURFACE = SurfaceSpec(friction=1.0, restitution=0.0)


def surfaces(scenery: SurfaceSpec, ball: SurfaceSpec) -> dict[str, SurfaceSpec]:
    """Every body role's surface: the scenery's on each static part, the ball's on balls."""
    return {"ball": ball, **{role: scenery for role in SCENERY_ROLES}}


def paper_materials() -> dict[str, EngineContacts]:
    """The paper board's materials on every engine."""
    return {
        "mujoco": EngineContacts(dict(MUJOCO_SETTINGS), surfaces(MUJOCO_SCENERY, MUJOCO_BALL)),
        "pybullet": EngineContacts(dict(PYBULLET_SETTINGS),
                                   surfaces(PYBULLET_SURFACE, PYBULLET_SURFACE)),
        "ode": EngineContacts({}, surfaces(ODE_SURFACE, ODE_SURFACE)),
        "dart": EngineContacts({}, surfaces(DART_SURFACE, DART_SURFACE)),
    }


def material_of(engine: str, surface: SurfaceSpec,
                params: Mapping[str, Any] | None = None) -> EngineContacts:
    """The paper's contact settings on this engine with one surface on every body (and
    these parameters added): a board whose balls and scenery share one material."""
    settings = paper_materials()[engine].params
    return EngineContacts({**settings, **(params or {})}, surfaces(surface, surface))


def small_board() -> BoardSpec:
    """A quick board for tests: 5 rows, 6 bins, 1-m dividers, 30 balls, same pins and balls.

    It keeps the paper's lattice, pin and ball sizes and cavity depth (so it is 3-D in the
    same way), and the paper's funnel-to-pin spacing, only with fewer rows and lower walls.
    """
    return BoardSpec(
        name="small", rows=5, bins=6,
        pins=PinSpec(top_row_z=1.904, per_row=(1, 4, 5, 4, 5)),
        funnel=FunnelSpec(tip_z=2.415, outer_x=1.25),
        dividers=DividerSpec(height=1.0),
        walls=WallSpec(inner_x=1.25, height=3.5),
        ball=BallSpec(count=30),
    )


def paper_webots_board() -> BoardSpec:
    """The paper's own set-up, for comparison: the paper board, all balls released at once,
    and a Webots-like contact (Webots' default bounce 0.5, Coulomb friction 1).

    Engines combine two bodies' coefficients differently, so the same physical contact
    needs different raw values: MuJoCo maps a body's restitution to its contact damping (a
    ball on a static body feels the static body's surface; 0.5 gives a bounce of about 0.5);
    PyBullet multiplies them (0.707 on every body: 0.707² ≈ 0.5). Friction 1 on every body
    is 1 on MuJoCo and 1 × 1 on PyBullet. Moving and static bodies both get these values.
    MuJoCo's and PyBullet's timesteps stay at their defaults (Webots' 32 ms step would tunnel
    there); ODE, Webots' own engine, runs Webots' 32 ms, which is the question this preset
    asks of it.
    """
    return BoardSpec(name="paper-webots", contacts={
        "mujoco": material_of("mujoco", webots_surface(0.5)),
        "pybullet": material_of("pybullet", webots_surface(0.707)),
        "ode": material_of("ode", webots_surface(0.5), {"timestep": WEBOTS_TIMESTEP}),
        "dart": material_of("dart", webots_surface(0.707)),
    })


WEBOTS_TIMESTEP = 0.032  # s: Webots' default basicTimeStep, which ODE runs here as Webots does


def paper_gazebo_board() -> BoardSpec:
    """The paper's Gazebo scene (msegoferre/pruebas_Gz_Wbt): the paper board, all balls at
    once, balls of r 0.045 m and 1 kg, restitution 0 and friction 1 (SDF's defaults), a
    1 ms step on every engine. DART (``--engine dart``) runs it as Gazebo Harmonic does;
    DART takes a pair's smaller friction and the product of restitutions, so 0 and 1 on
    every body are 0 and 1 for every pair, as on MuJoCo and PyBullet. The draft's ball
    inertia 0.1 kg m² (a copy error: a solid ball has 0.00081) is an option, ``[ball]
    inertia = 0.1`` in a board file (every engine sets it).
    """
    return BoardSpec(name="paper-gazebo", ball=BallSpec(mass=1.0), contacts={
        engine: material_of(engine, webots_surface(0.0), {"timestep": 0.001})
        for engine in ("mujoco", "pybullet", "dart")})


def paper_mesh_board() -> BoardSpec:
    """The paper board with every part a static triangle mesh, as the paper imported its
    board into each simulator: what mesh collisions cost each engine in lost balls and χ²
    beside the primitives of ``paper``, with the same materials."""
    return BoardSpec(name="paper-mesh", parts="mesh")


def webots_surface(restitution: float) -> SurfaceSpec:
    """Webots' default contact (friction 1; bounce 0.5 as this engine's raw value), on moving
    and static bodies alike."""
    return SurfaceSpec(friction=1.0, restitution=restitution)


PRESETS: dict[str, Callable[[], BoardSpec]] = {
    "paper": paper_board, "paper-webots": paper_webots_board,
    "paper-gazebo": paper_gazebo_board, "paper-mesh": paper_mesh_board, "small": small_board}


# --- (de)serialisation ---------------------------------------------------------------------


def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except OSError as err:
        raise BoardSpecError("board", f"cannot read {str(path)!r}: {err.strerror}") from err


def _plain(value: Any) -> Any:
    if is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in fields(value)}
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    return value


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


def _build(cls: type, data: Any, path: str) -> Any:
    """Instantiate dataclass ``cls`` from a mapping, converting nested fields by their hints."""
    if not isinstance(data, Mapping):
        raise BoardSpecError(path or "board",
                             f"must be a table of fields, got {type(data).__name__} {data!r}")
    names = [f.name for f in fields(cls)]
    for key in data:
        if key not in names:
            raise BoardSpecError(_join(path, str(key)),
                                 f"is not a field{did_you_mean(str(key), names)}; "
                                 f"known: {', '.join(names)}")
    hints = typing.get_type_hints(cls)
    return cls(**{k: _convert(hints[k], v, _join(path, k)) for k, v in data.items()})


def _convert(hint: Any, value: Any, path: str) -> Any:
    """Turn plain data into the hinted type: nested dataclasses, tuples, dicts, floats."""
    origin = typing.get_origin(hint)
    if isinstance(hint, type) and is_dataclass(hint):
        return _build(hint, value, path)
    if origin in (UnionType, typing.Union):
        if value is None:
            return None
        inner = [a for a in typing.get_args(hint) if a is not type(None)]
        return _convert(inner[0], value, path)
    if origin is tuple:
        if not isinstance(value, list | tuple):
            raise BoardSpecError(path, f"must be a list, got {type(value).__name__} {value!r}")
        item = typing.get_args(hint)[0]
        return tuple(_convert(item, v, f"{path}[{i}]") for i, v in enumerate(value))
    if origin is dict:
        if not isinstance(value, Mapping):
            raise BoardSpecError(path, f"must be a table, got {type(value).__name__} {value!r}")
        item = typing.get_args(hint)[1]
        return {str(k): _convert(item, v, _join(path, str(k))) for k, v in value.items()}
    if hint is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value
