"""Loading URDF and MJCF models into a DART world with dartpy's own parsers.

A URDF is one skeleton (DartLoader; its root welded to the world or free). An MJCF is
one skeleton per top-level body plus one, named ``world``, for the world's own geoms
(MjcfParser); dartpy's parser reads ``<joint type="free"/>`` but not the ``<freejoint/>``
shorthand, which it welds. Joint limits are enforced, as gz-physics enforces every SDF
axis limit (``dartsim/src/SDFFeatures.cc``).
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field
from typing import Any

import dartpy as dart

from galton.protocol import (
    FeatureUnsupportedError,
    InvalidArgumentError,
)

MODEL_FORMATS = ("urdf", "mjcf")
MJCF_WORLD_BODIES = "__geom_skel__"  # the skeleton dartpy makes of an MJCF's world geoms


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
        skeleton = loader.parseSkeletonString(text, dart.common.Uri("file:///model.urdf"))
        skeletons = [] if skeleton is None else [skeleton]
    else:
        skeletons = _parse_mjcf(text)
    if not skeletons:
        raise InvalidArgumentError(f"the {fmt} model does not parse (dartpy's parser "
                                   "refused it)")
    for skeleton in skeletons:
        for joint in skeleton.getJoints():
            if joint.getNumDofs() == 1:
                joint.setLimitEnforcement(True)
    return skeletons


def _parse_mjcf(text: str) -> list[Any]:
    """MjcfParser reads files only: the text goes through a temporary file."""
    handle, path = tempfile.mkstemp(suffix=".xml")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as out:
            out.write(text)
        world = dart.utils.MjcfParser.readWorld(dart.common.Uri(path))
    finally:
        os.unlink(path)
    if world is None:
        return []
    skeletons = [world.getSkeleton(k) for k in range(world.getNumSkeletons())]
    for skeleton in skeletons:
        world.removeSkeleton(skeleton)
    return skeletons


def root_name(skeleton: Any, prefix: str) -> str:
    """The root entity's name: prefix + the root body's name (``world`` for an MJCF's
    world geoms)."""
    if skeleton.getName() == MJCF_WORLD_BODIES:
        return prefix + "world"
    return prefix + str(skeleton.getRootBodyNode().getName())


def link_names(skeleton: Any, prefix: str) -> list[str]:
    """Every body node's entity name, the root first."""
    root = root_name(skeleton, prefix)
    return [root] + [prefix + node.getName() for node in skeleton.getBodyNodes()[1:]]
