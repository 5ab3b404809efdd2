"""A body's mass, centre of mass and inertia as MuJoCo computes them from its primitive geoms
(spheres, boxes, capsules, cylinders, ellipsoids), for engines whose MJCF importers do not:
PyBullet's puts a body's centre of mass at its origin, takes every geom's inertia as its
bounding box's and gives every geom a density of 1000 (pybullet/mjcf.py); dartpy's leaves
every inertia at the identity (dart/models.py). Pure computation on the file's text, shared
by the engine packages like the base."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ElementTree
from collections.abc import Sequence

import numpy as np

from galton.daemon.engines.geometry import volume as primitive_volume

DEFAULT_DENSITY = 1000.0  # kg/m³, MuJoCo's
Attrs = dict[str, str]
Classes = dict[str, dict[str, Attrs]]  # default class -> tag -> attributes


class Angles:
    """The file's <compiler angle= eulerseq=>: how it writes orientations."""

    def __init__(self, angle: str = "degree", eulerseq: str = "xyz") -> None:
        self.scale = math.pi / 180 if angle != "radian" else 1.0
        self.eulerseq = eulerseq


def volume(geom: Attrs) -> float | None:
    """A primitive geom's volume; None for any other."""
    kind, size = _shape(geom)
    if kind is None:
        return None
    if kind == "ellipsoid":
        return 4 / 3 * math.pi * size[0] * size[1] * size[2]
    widths = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3}
    return primitive_volume(kind, tuple(size[:widths[kind]]))


def inertial(geoms: Sequence[Attrs], angles: Angles) -> Attrs | None:
    """The ``<inertial>`` attributes MuJoCo would infer from these geoms; None when one is
    no primitive (or they weigh nothing)."""
    parts = [_part(g, angles) for g in geoms]
    if not parts or any(p is None for p in parts):
        return None
    masses = np.array([p[0] for p in parts if p is not None])
    total = float(masses.sum())
    if total <= 0:
        return None
    centres = np.array([p[1] for p in parts if p is not None])
    com = masses @ centres / total
    tensor = np.zeros((3, 3))
    for (mass, centre, turn, diagonal) in (p for p in parts if p is not None):
        d = centre - com
        tensor += turn @ np.diag(diagonal) @ turn.T + mass * (d @ d * np.eye(3) - np.outer(d, d))
    values, axes = np.linalg.eigh(tensor)
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return {"pos": _text(com), "quat": _text(_quaternion(axes)), "mass": f"{total!r}",
            "diaginertia": _text(np.maximum(values, 0.0))}


def _part(geom: Attrs, angles: Angles
          ) -> tuple[float, np.ndarray, np.ndarray, np.ndarray] | None:
    """(mass, centre, rotation, principal inertia) of one primitive geom."""
    kind, size = _shape(geom)
    space = volume(geom)
    if kind is None or space is None:
        return None
    mass = float(geom["mass"]) if "mass" in geom else float(
        geom.get("density", DEFAULT_DENSITY)) * space
    centre, turn = _frame(geom, angles)
    return mass, centre, turn, _diagonal(kind, size, mass, space)


def _diagonal(kind: str, size: list[float], mass: float, space: float) -> np.ndarray:
    r = size[0]
    if kind == "sphere":
        return np.full(3, 0.4 * mass * r**2)
    if kind in ("box", "ellipsoid"):
        a, b, c = (s * s for s in size[:3])
        k = 1 / 3 if kind == "box" else 1 / 5
        return mass * k * np.array([b + c, a + c, a + b])
    h = size[1]
    if kind == "cylinder":
        return np.array([mass * (3 * r**2 + 4 * h**2) / 12] * 2 + [mass * r**2 / 2])
    # A capsule: a cylinder and two hemispheres, split by volume.
    density = mass / space
    tube, ball = density * math.pi * r**2 * 2 * h, density * 4 / 3 * math.pi * r**3
    side = tube * (3 * r**2 + 4 * h**2) / 12 + ball * (0.4 * r**2 + h**2 + 0.75 * h * r)
    return np.array([side, side, tube * r**2 / 2 + ball * 0.4 * r**2])


def _shape(geom: Attrs) -> tuple[str | None, list[float]]:
    kind = geom.get("type", "sphere")
    size = [float(v) for v in geom.get("size", "").split()]
    if "fromto" in geom and kind in ("capsule", "cylinder", "box", "ellipsoid") and size:
        ends = [float(v) for v in geom["fromto"].split()]
        half = math.dist(ends[:3], ends[3:]) / 2
        size = [size[0], half] if kind in ("capsule", "cylinder") else [
            size[0], size[1] if len(size) > 1 else size[0], half]
    wanted = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3}
    if kind not in wanted or len(size) < wanted[kind]:
        return None, size
    return kind, size


def _frame(geom: Attrs, angles: Angles) -> tuple[np.ndarray, np.ndarray]:
    """A geom's centre and rotation in its body's frame."""
    if "fromto" in geom:
        ends = np.array([float(v) for v in geom["fromto"].split()])
        return (ends[:3] + ends[3:]) / 2, _z_to(ends[3:] - ends[:3])
    centre = np.array([float(v) for v in geom.get("pos", "0 0 0").split()])
    return centre, _rotation(geom, angles)


def _rotation(geom: Attrs, angles: Angles) -> np.ndarray:
    if "quat" in geom:
        w, x, y, z = (float(v) for v in geom["quat"].split())
        return _matrix(np.array([w, x, y, z]))
    if "axisangle" in geom:
        *axis, angle = (float(v) for v in geom["axisangle"].split())
        return _about(np.array(axis), angle * angles.scale)
    if "zaxis" in geom:
        return _z_to(np.array([float(v) for v in geom["zaxis"].split()]))
    if "xyaxes" in geom:
        values = np.array([float(v) for v in geom["xyaxes"].split()])
        x = values[:3] / np.linalg.norm(values[:3])
        y = values[3:] - (values[3:] @ x) * x
        y /= np.linalg.norm(y)
        return np.column_stack([x, y, np.cross(x, y)])
    if "euler" in geom:
        turn = np.eye(3)
        for letter, value in zip(angles.eulerseq, geom["euler"].split(), strict=False):
            axis = np.eye(3)["xyz".index(letter.lower())]
            step = _about(axis, float(value) * angles.scale)
            turn = turn @ step if letter.islower() else step @ turn
        return turn
    return np.eye(3)


def _about(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    half = angle / 2
    return _matrix(np.array([math.cos(half), *(math.sin(half) * axis)]))


def _z_to(direction: np.ndarray) -> np.ndarray:
    """The shortest rotation taking +z to ``direction`` (as MuJoCo's fromto and zaxis)."""
    z = direction / np.linalg.norm(direction)
    axis = np.cross([0.0, 0.0, 1.0], z)
    sine = float(np.linalg.norm(axis))
    if sine < 1e-12:
        return np.eye(3) if z[2] > 0 else np.diag([1.0, -1.0, -1.0])
    return _about(axis, math.atan2(sine, float(z[2])))


def _matrix(quat: np.ndarray) -> np.ndarray:
    w, x, y, z = quat / np.linalg.norm(quat)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _quaternion(turn: np.ndarray) -> np.ndarray:
    """A rotation matrix as MuJoCo's (w, x, y, z)."""
    trace = float(np.trace(turn))
    if trace > 0:
        s = 2 * math.sqrt(trace + 1)
        return np.array([s / 4, (turn[2, 1] - turn[1, 2]) / s, (turn[0, 2] - turn[2, 0]) / s,
                         (turn[1, 0] - turn[0, 1]) / s])
    i = int(np.argmax(np.diag(turn)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2 * math.sqrt(1 + turn[i, i] - turn[j, j] - turn[k, k])
    quat = np.zeros(4)
    quat[0] = (turn[k, j] - turn[j, k]) / s
    quat[1 + i] = s / 4
    quat[1 + j] = (turn[j, i] + turn[i, j]) / s
    quat[1 + k] = (turn[k, i] + turn[i, k]) / s
    return quat


def _text(values: np.ndarray) -> str:
    return " ".join(f"{float(v)!r}" for v in values)


def default_classes(root: ElementTree.Element) -> Classes:
    """Each default class's attributes per element tag, inherited from its parents."""
    classes: dict[str, dict[str, Attrs]] = {}

    def walk(default: ElementTree.Element, inherited: dict[str, Attrs], name: str) -> None:
        own = {tag: dict(attrs) for tag, attrs in inherited.items()}
        for child in default:
            if child.tag != "default":
                own.setdefault(child.tag, {}).update(child.attrib)
        classes[name] = own
        for child in default.findall("default"):
            walk(child, own, child.get("class", ""))

    for top in root.findall("default"):
        walk(top, {}, top.get("class", "main"))
    return classes


def resolved(element: ElementTree.Element, childclass: str, classes: Classes) -> Attrs:
    """An element's attributes with its default class's filled in."""
    cls = element.get("class", childclass)
    return {**classes.get(cls, {}).get(element.tag, {}), **element.attrib}


def infer_inertials(root: ElementTree.Element) -> None:
    """Write into each body of the file that has no ``<inertial>`` and whose geoms are all
    primitives the one MuJoCo infers (its inertiafromgeom="auto")."""
    compiler = root.find("compiler")
    angles = Angles() if compiler is None else Angles(
        compiler.get("angle", "degree"), compiler.get("eulerseq", "xyz"))
    classes = default_classes(root)
    for world in root.iter("worldbody"):
        for body in world.findall("body"):
            _infer(body, body.get("childclass", "main"), classes, angles)


def _infer(body: ElementTree.Element, childclass: str, classes: Classes, angles: Angles) -> None:
    geoms = [resolved(g, childclass, classes) for g in body.findall("geom")]
    if body.find("inertial") is None and geoms:
        found = inertial(geoms, angles)
        if found is not None:
            body.insert(0, ElementTree.Element("inertial", found))
    for child in body.findall("body"):
        _infer(child, child.get("childclass", childclass), classes, angles)
