"""Loading URDF and MJCF models into a DART world with dartpy's own parsers.

A URDF is one skeleton (DartLoader; its root welded to the world or free). An MJCF is
one skeleton per top-level body plus one, named ``world``, for the world's own geoms
(MjcfParser); dartpy's parser reads ``<joint type="free"/>`` but welds the ``<freejoint/>``
shorthand, which is therefore rewritten as the former before parsing. Joint limits are
enforced, as gz-physics enforces every SDF axis limit (``dartsim/src/SDFFeatures.cc``).
"""

from __future__ import annotations

import os
import re
import tempfile
from dataclasses import dataclass, field
from typing import Any
from xml.etree import ElementTree

import dartpy as dart
import numpy as np

from galton.daemon.engines.mjcf_inertia import infer_inertials
from galton.protocol import (
    FeatureUnsupportedError,
    InvalidArgumentError,
)

MODEL_FORMATS = ("urdf", "mjcf")
MJCF_WORLD_BODIES = "__geom_skel__"
# DartLoader drops a URDF link named "world" (it welds the next link to the world): such a
# link is renamed before parsing, so it stays an entity named "world", as on other engines.
URDF_WORLD = re.compile(r'((?:link|name)\s*=\s*)(["\'])world\2')
WORLD_ALIAS = "world__galton"
FREEJOINT = re.compile(r"<freejoint\b")  # the skeleton dartpy makes of an MJCF's world geoms


@dataclass
class Model:
    """One loaded skeleton and how it was loaded (a snapshot loads it again so)."""

    root: str  # the root entity's name
    skeleton: Any
    fmt: str
    text: str
    prefix: str
    fixed_base: bool
    index: int  # which skeleton of the file
    loaded_positions: list[float] = field(default_factory=list)


def check_format(fmt: str) -> None:
    if fmt not in MODEL_FORMATS:
        raise FeatureUnsupportedError(f"the dart engine loads {', '.join(MODEL_FORMATS)} "
                                      f"models, not {fmt!r}")


def model_text(text: str | None, path: str | None) -> str:
    """The model's text, from ``text`` or read from ``path``."""
    if text is not None:
        return text
    try:
        with open(str(path), encoding="utf-8") as handle:
            return handle.read()
    except OSError as exc:
        raise InvalidArgumentError(f"cannot read model file {path!r}: {exc}") from None


def parse(fmt: str, text: str, fixed_base: bool) -> list[Any]:
    """The file's skeletons (InvalidArgumentError when it does not parse)."""
    if fmt == "urdf":
        loader = dart.utils.DartLoader()
        options = dart.utils.DartLoader.Options()
        options.mDefaultRootJointType = (dart.utils.DartLoader.RootJointType.FIXED
                                         if fixed_base else
                                         dart.utils.DartLoader.RootJointType.FLOATING)
        loader.setOptions(options)
        renamed = URDF_WORLD.sub(lambda m: f"{m.group(1)}{m.group(2)}{WORLD_ALIAS}{m.group(2)}",
                                 text)
        skeleton = loader.parseSkeletonString(renamed, dart.common.Uri("file:///model.urdf"))
        skeletons = [] if skeleton is None else [skeleton]
    else:
        skeletons = _parse_mjcf(text)
    if not skeletons:
        raise InvalidArgumentError(f"the {fmt} model does not parse (dartpy's parser "
                                   "refused it)")
    for skeleton in skeletons:
        for joint in skeleton.getJoints():
            if joint.getNumDofs() == 1 and limited(joint):
                joint.setLimitEnforcement(True)
    return skeletons


def _parse_mjcf(text: str) -> list[Any]:
    """MjcfParser reads files only: the text goes through a temporary file."""
    handle, path = tempfile.mkstemp(suffix=".xml")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as out:
            out.write(FREEJOINT.sub('<joint type="free"', text))
        world = dart.utils.MjcfParser.readWorld(dart.common.Uri(path))
    finally:
        os.unlink(path)
    if world is None:
        return []
    skeletons = [world.getSkeleton(k) for k in range(world.getNumSkeletons())]
    for skeleton in skeletons:
        world.removeSkeleton(skeleton)
    apply_inertials(skeletons, text)
    return skeletons


def apply_inertials(skeletons: list[Any], text: str) -> None:
    """Each body's ``<inertial>`` as the file gives it, or as MuJoCo infers it from the
    body's primitive geoms where it gives none: dartpy 6.20's MJCF parser leaves a body's
    inertia at the identity and drops the centre of mass of a body with no geom."""
    nodes = {str(node.getName()): node for skeleton in skeletons
             for node in skeleton.getBodyNodes()}
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as exc:
        raise InvalidArgumentError(f"the mjcf model does not parse: {exc}") from None
    infer_inertials(root)
    for body in root.iter("body"):
        inertial, node = body.find("inertial"), nodes.get(body.get("name", ""))
        if inertial is None or node is None:
            continue
        node.setMass(float(inertial.get("mass", "0")))
        node.setLocalCOM(_numbers(inertial.get("pos", "0 0 0")))
        moment = _moment(inertial)
        turn = _rotation(inertial.get("quat"))
        moment = turn @ moment @ turn.T
        node.setMomentOfInertia(moment[0, 0], moment[1, 1], moment[2, 2], moment[0, 1],
                                moment[0, 2], moment[1, 2])


def _numbers(text: str) -> np.ndarray:
    return np.array([float(v) for v in text.split()], dtype=float)


def _moment(inertial: Any) -> np.ndarray:
    full = inertial.get("fullinertia")
    if full is not None:
        xx, yy, zz, xy, xz, yz = _numbers(full)
        return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    return np.diag(_numbers(inertial.get("diaginertia", "0 0 0")))


def _rotation(quat: str | None) -> np.ndarray:
    """MJCF's quaternion (w x y z) as a rotation matrix (identity when absent)."""
    if quat is None:
        return np.eye(3)
    w, x, y, z = _numbers(quat) / np.linalg.norm(_numbers(quat))
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def limited(joint: Any) -> bool:
    """Whether a 1-DOF joint has limits (MJCF's unlimited joints read 0..0 in dartpy)."""
    return bool(joint.getPositionLowerLimit(0) < joint.getPositionUpperLimit(0))


def node_name(node: Any) -> str:
    name = str(node.getName())
    return "world" if name == WORLD_ALIAS else name


def root_name(skeleton: Any, prefix: str) -> str:
    """The root entity's name: prefix + the root body's name (``world`` for an MJCF's
    world geoms)."""
    if skeleton.getName() == MJCF_WORLD_BODIES:
        return prefix + "world"
    return prefix + node_name(skeleton.getRootBodyNode())


def link_names(skeleton: Any, prefix: str) -> list[str]:
    """Every body node's entity name, the root first."""
    root = root_name(skeleton, prefix)
    return [root] + [prefix + node_name(node) for node in skeleton.getBodyNodes()[1:]]
