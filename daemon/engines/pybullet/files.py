"""What a model file says that PyBullet's importers lose, read from its text.

- URDF: a continuous joint keeps the <limit> the file gives it (PyBullet reports it, the
  protocol says a continuous joint is unlimited); a joint's axis is in the child link's
  frame as written (PyBullet reports it turned into the child's inertial frame, in single
  precision).
- MJCF: the importer gives every joint a link of its own (``link<i>_<j>``, no mass) and
  welds the file's body to it (``jointfix_<i>_<j>``): the file's bodies and joints are
  the ones the protocol lists. And it takes a body's inertia from its geoms even where
  the file gives <inertial diaginertia=...>: that is set again after the load.
"""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass, field

from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet import mjcf

Axis = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class FileFacts:
    """A model file's own bodies (MJCF; None for URDF, where every link is one) and
    joints: name -> (URDF type or "", axis or None)."""

    bodies: frozenset[str] | None = None
    joints: dict[str, tuple[str, Axis | None]] = field(default_factory=dict)
    free: dict[str, str] = field(default_factory=dict)  # MJCF body -> its free joint's name
    damping: dict[str, float] = field(default_factory=dict)  # MJCF joint -> its damping

    def hides_link(self, name: str) -> bool:
        return self.bodies is not None and name not in self.bodies

    def hides_joint(self, name: str) -> bool:
        return self.bodies is not None and name not in self.joints


def facts(fmt: str, text: str) -> FileFacts:
    """Parse what ``FileFacts`` holds (the text is well-formed: load_bodies checked it)."""
    root = ElementTree.fromstring(text)
    if fmt == "urdf":
        urdf: dict[str, tuple[str, Axis | None]] = {
            joint.get("name", ""): (joint.get("type", ""), _axis(joint))
            for joint in root.iter("joint")}
        return FileFacts(None, urdf)
    bodies = frozenset(body.get("name", "") for body in root.iter("body"))
    joints: dict[str, tuple[str, Axis | None]] = {
        joint.get("name", ""): ("", None)
        for tag in ("joint", "freejoint") for joint in root.iter(tag)}
    free = {body.get("name", ""): joint.get("name", "")
            for body in root.iter("body") for joint in body
            if joint.get("name") and (joint.tag == "freejoint" or (
                joint.tag == "joint" and joint.get("type") == "free"))}
    return FileFacts(bodies, joints, free, mjcf.plan(text).damping)


def _axis(joint: ElementTree.Element) -> Axis:
    element = joint.find("axis")
    values = [float(v) for v in (element.get("xyz", "1 0 0") if element is not None
                                 else "1 0 0").split()]
    norm = sum(v * v for v in values) ** 0.5 or 1.0
    return (values[0] / norm, values[1] / norm, values[2] / norm)


def fix_mjcf_inertia(bc: BulletClient, ids: list[int], text: str) -> None:
    """Give each body the diagonal inertia its <inertial> states."""
    wanted: dict[str, list[float]] = {}
    for body in ElementTree.fromstring(text).iter("body"):
        inertial = body.find("inertial")
        if inertial is not None and inertial.get("diaginertia"):
            wanted[body.get("name", "")] = [float(v) for v in
                                            inertial.get("diaginertia", "").split()]
    if not wanted:
        return
    for uid in ids:
        links = {bc.getBodyInfo(uid)[0].decode("utf-8", "replace"): -1}
        links.update((bc.getJointInfo(uid, j)[12].decode("utf-8", "replace"), j)
                     for j in range(bc.getNumJoints(uid)))
        for name, link in links.items():
            diagonal = wanted.get(name)
            if diagonal is not None and len(diagonal) == 3 and bc.getDynamicsInfo(
                    uid, link)[0] > 0:
                bc.changeDynamics(uid, link, localInertiaDiagonal=diagonal)
