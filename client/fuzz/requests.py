"""Requests for the fuzz harness, generated from the operations' own argument declarations
(``galton.protocol.operations``): mostly well-formed ones over the world's own names, with
one thing wrong in many of them, and a share of broken envelopes.

Valid values are kept small (steps ≤ 200, groups ≤ 8 bodies), so a campaign explores many
requests rather than running a few long ones.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import msgpack
import numpy as np

from galton.protocol import PROTOCOL_VERSION, pack_f64
from galton.protocol.mesh import box_mesh, pack_faces, pack_vertices
from galton.protocol.operations import OPERATIONS, Arg, Operation

T = TypeVar("T")

MJCF = ('<mujoco><worldbody><body name="{name}" pos="0 0 1"><freejoint/>'
        '<geom size=".05"/></body></worldbody></mujoco>')
URDF = ('<robot name="{name}"><link name="base"><inertial><mass value="1"/>'
        '<inertia ixx=".01" iyy=".01" izz=".01" ixy="0" ixz="0" iyz="0"/></inertial>'
        '<collision><geometry><sphere radius=".05"/></geometry></collision></link></robot>')
SHAPES = {"sphere": 1, "box": 3, "cylinder": 2, "capsule": 2, "plane": 2}
PARAMS = {"timestep": (0.0005, 0.01), "gravity": None}
BAD_NUMBERS = (math.nan, math.inf, -math.inf, -1.0, 0.0, 1e308, -1e308, 2**63 - 1, True, "1",
               None, [1.0], {"x": 1})


class RequestMaker:
    """Makes one fuzz request at a time from a seeded generator and the world's names."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.names: list[str] = []  # the world's entities, as last listed
        self.sim_time = 0.0
        self.engine = "mujoco"  # the daemon's engine: load_world mostly keeps it
        self.last_count = 1  # names in the request being made
        self._counter = 0

    # -- choices -----------------------------------------------------------------------
    def chance(self, p: float) -> bool:
        return bool(self.rng.random() < p)

    def pick(self, items: Sequence[T]) -> T:
        return items[int(self.rng.integers(len(items)))]

    def fresh_name(self) -> str:
        self._counter += 1
        return f"fz{self._counter}"

    def some_names(self, new: bool = False) -> list[str]:
        count = int(self.rng.integers(1, 4))
        if new or not self.names or self.chance(0.1):
            return [self.fresh_name() for _ in range(count)]
        return [self.pick(self.names) for _ in range(count)]

    # -- one request -------------------------------------------------------------------
    def make(self) -> tuple[str, bytes]:
        """(operation key, payload): broken envelopes, and operations with their args."""
        if self.chance(0.05):
            return self.broken_envelope()
        op = self.pick(list(OPERATIONS.values()))
        args = self.args_for(op)
        if self.chance(0.3):
            self.spoil(args)
        body = {"v": PROTOCOL_VERSION, "op": op.name, "args": args}
        return op.name, msgpack.packb(body, use_bin_type=True)

    def broken_envelope(self) -> tuple[str, bytes]:
        op = self.pick(list(OPERATIONS))
        choices: list[Callable[[], bytes]] = [
            lambda: bytes(self.rng.integers(0, 256, int(self.rng.integers(0, 64)),
                                            dtype=np.uint8)),
            lambda: msgpack.packb([1, 2, 3]),
            lambda: msgpack.packb({"v": 99, "op": op, "args": {}}),
            lambda: msgpack.packb({"op": op, "args": {}}),
            lambda: msgpack.packb({"v": 1, "op": "spawn" if op != "spawn" else "list"}),
            lambda: msgpack.packb({"v": 1, "op": op, "args": [1]}),
            lambda: msgpack.packb({"v": 1, "op": op, "args": {}, "client": 7}),
            lambda: msgpack.packb({"v": 1, "op": op, "args": {"world": deep(40)}}),
        ]
        return op, self.pick(choices)()

    def args_for(self, op: Operation) -> dict[str, Any]:
        args: dict[str, Any] = {}
        for arg in op.args:
            if arg.required or self.chance(0.5):
                args[arg.name] = self.value_for(op, arg)
        if op.name == "load_model" and "text" in args and "path" in args:
            del args[self.pick(["text", "path"])]
        return args

    def value_for(self, op: Operation, arg: Arg) -> Any:
        special = SPECIAL.get((op.name, arg.name))
        if special is not None:
            return special(self)
        return KIND_VALUES[arg.kind](self, arg)

    def spoil(self, args: dict[str, Any]) -> None:
        """One thing wrong: a bad value, a missing or unknown argument, an unknown world."""
        how = self.pick(["value", "value", "drop", "unknown", "world", "long"])
        if how == "value" and args:
            args[self.pick(list(args))] = self.pick(BAD_NUMBERS)
        elif how == "drop" and args:
            del args[self.pick(list(args))]
        elif how == "unknown":
            args[self.pick(["junk", "nmaes", "count_", "Groups"])] = 1
        elif how == "world":
            args["world"] = self.pick(["other", 7, ""])
        elif how == "long":
            args[self.pick(list(args) or ["names"])] = "x" * int(self.rng.integers(5000, 9000))


def deep(depth: int) -> Any:
    value: Any = 0
    for _ in range(depth):
        value = [value]
    return value


# Numbers at the ends of float64: a horizon of 5e-324 s or 1e308 s once raised Python's own
# errors inside the daemon (issue 35).
EXTREME_NUMBERS = (5e-324, 1e-300, 1e308, -1e308)


def _number(maker: RequestMaker, arg: Arg) -> Any:
    if maker.chance(0.05):
        return maker.pick(EXTREME_NUMBERS)
    return float(maker.rng.uniform(0, 3))


def _count(maker: RequestMaker, arg: Arg) -> Any:
    return int(maker.rng.integers(1, 200))


def _string(maker: RequestMaker, arg: Arg) -> Any:
    return maker.pick(["", "fz*", "ball", "a\x00b", "tag"])


def _choice(maker: RequestMaker, arg: Arg) -> Any:
    if maker.chance(0.1):
        return "bogus"
    return maker.pick(list(arg.choices))


def _names(maker: RequestMaker, arg: Arg) -> Any:
    names = maker.some_names()
    maker.last_count = len(names)  # the rows that follow mostly match
    return names


def _map(maker: RequestMaker, arg: Arg) -> Any:
    return {}


def _rows(width: int) -> Callable[[RequestMaker, Arg], Any]:
    def make(maker: RequestMaker, arg: Arg) -> Any:
        count = maker.last_count if maker.chance(0.8) else int(maker.rng.integers(1, 4))
        rows = maker.rng.normal(0, 1, (count, width))
        if width == 7:
            rows[:, 2] = np.abs(rows[:, 2]) + 0.5
        if maker.chance(0.1):
            return pack_f64(rows)[:-3]
        if maker.chance(0.03):  # absurd but finite: the next step must fault the world
            rows *= 1e200
        return pack_f64(rows)
    return make


def _groups(maker: RequestMaker, arg: Arg) -> Any:
    return [_group(maker) for _ in range(int(maker.rng.integers(1, 3)))]


def _group(maker: RequestMaker) -> dict[str, Any]:
    if maker.chance(0.1):
        return _mesh_group(maker)
    shape = maker.pick(list(SHAPES))
    count = int(maker.rng.integers(1, 9))
    poses = np.zeros((count, 7))
    poses[:, :2] = maker.rng.uniform(-2, 2, (count, 2))
    poses[:, 2] = maker.rng.uniform(0.2, 2, count)
    poses[:, 6] = 1.0
    group: dict[str, Any] = {
        "shape": shape, "size": [float(maker.rng.uniform(0.02, 0.2))] * SHAPES[shape],
        "names": _group_names(maker, count), "poses": pack_f64(poses),
        "static": shape == "plane" or maker.chance(0.3)}
    for key, low, high in (("mass", 0.01, 5.0), ("friction", 0.0, 1.0),
                           ("restitution", 0.0, 1.0)):
        if maker.chance(0.2) and not (key == "mass" and group["static"]):
            group[key] = float(maker.rng.uniform(low, high))
    if maker.chance(0.15):
        group[maker.pick(["mass", "size", "names", "poses", "shape", "colour"])] = \
            maker.pick(BAD_NUMBERS)
    return group


def _mesh_group(maker: RequestMaker) -> dict[str, Any]:
    """A mesh box (shape ``mesh``), now and then with one of its parts broken: an index
    out of range, a flat or non-finite vertex list, a ragged byte count."""
    half = maker.rng.uniform(0.02, 0.2, 3)
    vertices, faces = box_mesh((float(half[0]), float(half[1]), float(half[2])))
    count = int(maker.rng.integers(1, 4))
    poses = np.tile([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], (count, 1))
    poses[:, :2] = maker.rng.uniform(-2, 2, (count, 2))
    group: dict[str, Any] = {"shape": "mesh", "names": _group_names(maker, count),
                             "poses": pack_f64(poses), "static": maker.chance(0.5),
                             "vertices": pack_vertices(vertices), "faces": pack_faces(faces)}
    if maker.chance(0.3):
        broken = maker.pick([("faces", pack_faces(faces + 8)),
                             ("vertices", pack_vertices(vertices * [1.0, 1.0, 0.0])),
                             ("vertices", pack_vertices(vertices * math.nan)),
                             ("faces", pack_faces(faces)[:-3]), ("size", [0.1])])
        group[broken[0]] = broken[1]
    return group


def _group_names(maker: RequestMaker, count: int) -> list[str]:
    """New names, but now and then one already taken."""
    names = [maker.fresh_name() for _ in range(count)]
    if maker.names and maker.chance(0.1):
        names[0] = maker.pick(maker.names)
    return names


def _properties(maker: RequestMaker) -> dict[str, Any]:
    key = maker.pick(["mass", "friction", "restitution", "rgba", "tags"])
    value = {"mass": float(maker.rng.uniform(0.01, 5)), "friction": 0.5, "restitution": 0.5,
             "rgba": [1, 0, 0, 1], "tags": ["t"]}[key]
    if maker.chance(0.2):
        value = maker.pick([1e-300, 1e300, -1.0, math.nan, "x"])
    return {key: value}


def _params(maker: RequestMaker) -> dict[str, Any]:
    return maker.pick([{"timestep": float(maker.rng.uniform(0.0005, 0.005))},
                       {"gravity": [0.0, 0.0, -9.81]}, {"timestep": 0.0},
                       {"timestpe": 0.002}, {"mujoco.iterations": 5},
                       {"pybullet.solver_iterations": 5}])


def _sim_time(maker: RequestMaker) -> Any:
    return maker.sim_time + float(maker.rng.uniform(0.001, 0.3))


def _until_rest(maker: RequestMaker) -> Any:
    return maker.pick([{"speed": 0.01, "every": 0.05}, {"speed": -1}, {"speed": 1, "wat": 2}])


def _plans(maker: RequestMaker, arg: Arg) -> Any:
    """A plan or two of timed wrenches on the known bodies, now and then one thing wrong."""
    step: dict[str, Any] = {"at": float(maker.rng.uniform(0, 0.05)), "wrenches": {
        "names": maker.some_names()[:1] or ["x"], "wrenches": pack_f64(np.ones((1, 6)))}}
    if maker.chance(0.3):
        step[maker.pick(["at", "wrenches", "junk"])] = maker.pick([-1.0, 1e308, "x", {}])
    return [[step] for _ in range(int(maker.rng.integers(1, 3)))]


def _perturb(maker: RequestMaker) -> Any:
    return maker.pick([{"position": 0.001}, {"orientation": 0.1, "velocity": 0.01},
                       {"position": -1.0}, {"bodies": {"nobody": {"position": 0.1}}},
                       {"position": math.nan}, {"wat": 1}])


def _score(maker: RequestMaker) -> Any:
    body = (maker.some_names() or ["x"])[0]
    return maker.pick([{"body": body, "target": [0.0, 0.0, 0.0]}, {"body": body},
                       {"body": "nobody", "target": [1, 2, 3]},
                       {"body": body, "target": [math.inf, 0, 0]}])


def _model_text(maker: RequestMaker) -> Any:
    name = maker.fresh_name()
    return maker.pick([MJCF.format(name=name), URDF.format(name=name), "<mujoco>", "not xml"])


def _model_path(maker: RequestMaker) -> Any:
    return maker.pick(["/dev/zero", "/dev/stdin", "/tmp", "/no/such/file.xml", ""])


def _prefix(maker: RequestMaker) -> Any:
    return maker.pick(["", "p_", "\x00", "x" * 70, maker.fresh_name() + "_"])


def _world(maker: RequestMaker) -> Any:
    return maker.pick(["default", "other"])


def _values(maker: RequestMaker, arg: Arg) -> Any:
    """One number per joint: a number, or packed float64 (sometimes of the wrong length)."""
    if maker.chance(0.4):
        return float(maker.rng.uniform(-2, 2))
    count = maker.last_count if maker.chance(0.8) else int(maker.rng.integers(1, 4))
    return pack_f64(maker.rng.normal(0, 1, count))


def _blob(maker: RequestMaker, arg: Arg) -> Any:
    """Not a snapshot: random bytes, msgpack of something else, or a wrong format."""
    return maker.pick([bytes(maker.rng.integers(0, 256, 64, dtype=np.uint8)),
                       msgpack.packb({"format": 99}), msgpack.packb([1, 2]), b""])


def _cameras(maker: RequestMaker, arg: Arg) -> Any:
    """Small cameras, with now and then one thing wrong."""
    camera: dict[str, Any] = {"eye": [2.0, 0.0, 1.0], "target": [0.0, 0.0, 0.5],
                              "width": int(maker.rng.integers(1, 24)),
                              "height": int(maker.rng.integers(1, 24)),
                              "outputs": maker.pick([["rgb"], ["depth", "segmentation"]])}
    if maker.chance(0.3):
        camera[maker.pick(["width", "fov", "eye", "near", "outputs"])] = maker.pick(
            [0, 100000, math.nan, [1, 2], ["x"], -1.0])
    return [camera]


KIND_VALUES: dict[str, Callable[[RequestMaker, Arg], Any]] = {
    "number": _number, "count": _count, "string": _string, "bool": lambda m, a: m.chance(0.5),
    "names": _names, "map": _map, "groups": _groups, "poses": _rows(7), "twists": _rows(6),
    "choice": _choice, "values": _values, "wrenches": _rows(6), "points": _rows(3),
    "blob": _blob, "cameras": _cameras, "plans": _plans,
}
SPECIAL: dict[tuple[str, str], Callable[[RequestMaker], Any]] = {
    ("update", "properties"): _properties,
    ("set_params", "params"): _params,
    ("load_world", "params"): lambda m: m.pick([{}, {"timestep": 0.002}, {"bogus": 1}]),
    ("run_until", "sim_time"): _sim_time,
    ("run_until", "until_rest"): _until_rest,
    ("predict", "perturb"): _perturb,
    ("predict", "score"): _score,
    ("predict", "futures"): lambda m: int(m.rng.integers(1, 5)),
    ("load_model", "text"): _model_text,
    ("load_model", "path"): _model_path,
    ("load_model", "prefix"): _prefix,
    ("play", "rtf"): lambda m: m.pick([0.0, 1.0, 5.0, -1.0]),
    ("load_world", "engine"): lambda m: m.engine if m.chance(0.9) else m.pick(
        ["mujoco", "pybullet", "ode", "dart", "bullet"]),
}
