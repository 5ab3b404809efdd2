"""An MJCF file as MuJoCo reads it, given to PyBullet's importer, which reads it otherwise.

What the importer does differently, and what is done about it (docs/protocol.md, "load_model"):

- A top-level body with no joint: MuJoCo welds it to the world; the importer makes it free.
  It is given ``<inertial mass="0">`` before the load (Bullet fixes a base without mass).
- A body without ``<inertial>``: the importer gives every geom a density of 1000 (no
  ``mass=``, no ``density=``), puts the centre of mass at the body's origin and takes each
  geom's inertia as its bounding box's. A body of primitive geoms is given the
  ``<inertial>`` MuJoCo infers (mjcf_inertia.py). A body with a mesh is given the
  mass MuJoCo gives it after the load, its inertia scaled alike: exact for one geom, or
  geoms of one density; one whose geoms' densities differ is refused, naming it.
- ``<joint damping=...>``: the importer drops it; it is set after the load.
- ``<joint type="ball">``: the importer drops the joint and its body; refused, naming it.
- A ``<joint>`` without ``type`` (MuJoCo: a hinge, or its default class's): the importer
  drops it and its body; the type is written in.

Default classes (``<default>``, ``class``, ``childclass``) are resolved as MuJoCo does for
the attributes read here.
"""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass, field

from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines import mjcf_inertia as inertia
from galton.protocol import FeatureUnsupportedError

DEFAULT_DENSITY = inertia.DEFAULT_DENSITY  # kg/m³, MuJoCo's and the importer's
Attrs = dict[str, str]


@dataclass(slots=True)
class MjcfPlan:
    """The text PyBullet loads, and what is set after the load."""

    text: str
    masses: dict[str, float] = field(default_factory=dict)  # body -> its one geom's mass
    mass_factors: dict[str, float] = field(default_factory=dict)  # body -> density / 1000
    damping: dict[str, float] = field(default_factory=dict)  # joint -> damping
    edited: bool = False  # the text differs from the file's


def plan(text: str) -> MjcfPlan:
    """Read the file (well-formed: checked before), refuse what PyBullet cannot load as
    MuJoCo does, and weld the top-level bodies MuJoCo welds."""
    root = ElementTree.fromstring(text)
    compiler = root.find("compiler")
    angles = inertia.Angles() if compiler is None else inertia.Angles(
        compiler.get("angle", "degree"), compiler.get("eulerseq", "xyz"))
    classes = inertia.default_classes(root)
    result = MjcfPlan(text)
    for world in root.iter("worldbody"):
        for body in world.findall("body"):
            _read_body(body, body.get("childclass", "main"), classes, angles, result)
            if not any(c.tag in ("joint", "freejoint") for c in body):
                _weld(body)
                result.edited = True
    if result.edited:
        result.text = ElementTree.tostring(root, encoding="unicode")
    return result


def apply(bc: BulletClient, ids: list[int], wanted: MjcfPlan) -> None:
    """Set what the importer dropped: masses (inertia scaled alike), joint damping."""
    for uid in ids:
        for link in range(-1, bc.getNumJoints(uid)):
            info = bc.getJointInfo(uid, link) if link >= 0 else None
            body = (info[12] if info else bc.getBodyInfo(uid)[0]).decode("utf-8", "replace")
            mass, _, inertia = bc.getDynamicsInfo(uid, link)[:3]
            factor = wanted.mass_factors.get(body)
            if body in wanted.masses and mass > 0:
                factor = wanted.masses[body] / mass
            if factor is not None and factor != 1.0 and mass > 0:
                bc.changeDynamics(uid, link, mass=mass * factor,
                                  localInertiaDiagonal=[i * factor for i in inertia])
            joint = info[1].decode("utf-8", "replace") if info else ""
            if joint in wanted.damping:
                bc.changeDynamics(uid, link, jointDamping=wanted.damping[joint])


def _read_body(body: ElementTree.Element, childclass: str,
               classes: inertia.Classes, angles: inertia.Angles,
               result: MjcfPlan) -> None:
    name = body.get("name", "")
    geoms: list[Attrs] = []
    for child in body:
        if child.tag == "body":
            _read_body(child, child.get("childclass", childclass), classes, angles, result)
        elif child.tag == "geom":
            geoms.append(inertia.resolved(child, childclass, classes))
        elif child.tag == "joint":
            joint = inertia.resolved(child, childclass, classes)
            _read_joint(joint, name, result)
            if "type" not in child.attrib:  # the importer drops a joint without one
                child.set("type", joint.get("type", "hinge"))
                result.edited = True
    if body.find("inertial") is None and geoms:
        found = inertia.inertial(geoms, angles)
        if found is not None:  # primitives: MuJoCo's inertial, written in
            body.insert(0, ElementTree.Element("inertial", found))
            result.edited = True
            return
        if len(geoms) == 1 and "mass" in geoms[0]:
            result.masses[name] = float(geoms[0]["mass"])
        factor = _mass_factor(name, geoms)
        if factor is not None:
            result.mass_factors[name] = factor


def _read_joint(joint: Attrs, body: str, result: MjcfPlan) -> None:
    kind = joint.get("type", "hinge")
    label = joint.get("name", "")
    if kind == "ball":
        raise FeatureUnsupportedError(
            f'PyBullet\'s MJCF importer cannot load a ball joint (<joint name="{label}" '
            f'type="ball"> in body {body!r}): it drops the joint and its body; load this '
            "model on MuJoCo")
    damping = float(joint.get("damping", "0") or 0.0)
    if damping and kind in ("hinge", "slide"):
        result.damping[label] = damping


def _mass_factor(body: str, geoms: list[Attrs]) -> float | None:
    """The factor from the importer's mass of the body (density 1000) to MuJoCo's; None
    when they agree or a lone geom states its mass. Refused when the geoms' densities
    differ (no scale makes both the mass and the inertia right)."""
    if not any("mass" in g or "density" in g for g in geoms) or (
            len(geoms) == 1 and "mass" in geoms[0]):
        return None
    densities = []
    for number, geom in enumerate(geoms):
        density = _density(geom)
        if density is None:
            raise FeatureUnsupportedError(
                f"PyBullet cannot give body {body!r} the masses its geoms state (geom "
                f"{geom.get('name', number)!r} has a mass and no volume this daemon "
                "computes); give the body an <inertial>, or load this model on MuJoCo")
        densities.append(density)
    if max(densities) - min(densities) > 1e-9 * max(densities):
        raise FeatureUnsupportedError(
            f"PyBullet cannot give body {body!r} geoms of different densities "
            f"({', '.join(f'{d:g}' for d in densities)} kg/m³): its importer gives a body "
            "one; give the body an <inertial>, or load this model on MuJoCo")
    return densities[0] / DEFAULT_DENSITY


def _density(geom: Attrs) -> float | None:
    if "mass" not in geom:
        return float(geom.get("density", DEFAULT_DENSITY))
    volume = inertia.volume(geom)
    return None if volume is None else float(geom["mass"]) / volume


def _weld(body: ElementTree.Element) -> None:
    """Give a jointless top-level body no mass: PyBullet then fixes it, as MuJoCo welds it."""
    for inertial in body.findall("inertial"):
        body.remove(inertial)
    body.insert(0, ElementTree.Element(
        "inertial", {"pos": "0 0 0", "mass": "0", "diaginertia": "0 0 0"}))
