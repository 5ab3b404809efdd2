"""Loading URDF and MJCF models into a PyBullet world: what the engine's ``load_model`` checks,
names and registers.

Every body a load makes becomes an entity named ``prefix + its name`` (made unique among the
load's own), a multibody with damping set to zero like every dynamic body here.
"""

from __future__ import annotations

from collections.abc import Callable, Container
from typing import Any

from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet import props
from galton.daemon.engines.pybullet.bodies import read_text, unique_name
from galton.daemon.engines.pybullet.files import FileFacts
from galton.daemon.engines.pybullet.rebuild import Body, Model
from galton.protocol import (
    EntityInfo,
    FeatureUnsupportedError,
    InvalidArgumentError,
    NameNotUniqueError,
)

MODEL_FORMATS = ("urdf", "mjcf")


def model_text(fmt: str, text: str | None, path: str | None) -> str:
    """The model's text (the daemon passes it with its file names made absolute, and the
    path it came from for information), or read from its path when only that is given."""
    if fmt not in MODEL_FORMATS:
        raise FeatureUnsupportedError(
            f"PyBullet cannot load {fmt!r} models; it loads {', '.join(MODEL_FORMATS)}")
    if text is None and path is None:
        raise InvalidArgumentError("give a model as text or as a path")
    return text if text is not None else read_text(path or "")


def body_names(bc: BulletClient, fmt: str, ids: list[int], prefix: str,
               taken: Container[str]) -> list[str]:
    """The loaded bodies' entity names; refuse a load with no body or a name in use."""
    if not ids:
        raise InvalidArgumentError(f"the {fmt.upper()} model holds no bodies")
    names: list[str] = []
    for uid in ids:
        base = bc.getBodyInfo(uid)[0].decode("utf-8", "replace")
        names.append(unique_name(prefix + base, set(names)))
    # Checked here, not left to the World: registering a taken name would orphan the
    # body that holds it, and the World's undo (delete by name) would remove the wrong one.
    in_use = [n for n in names if n in taken]
    if in_use:
        raise NameNotUniqueError(
            f"the model's body {in_use[0]!r} has the name of an existing entity; load it "
            "with another prefix")
    return names


def link_names(bc: BulletClient, ids: list[int], roots: list[str], prefix: str,
               taken: Container[str], file: FileFacts) -> list[list[str | None]]:
    """Each loaded body's link entity names (``prefix`` + the file's link name), made
    unique among the load's own names, None for the links PyBullet's MJCF importer adds;
    refuse a name in use."""
    seen = set(roots)
    names: list[list[str | None]] = []
    for uid in ids:
        links: list[str | None] = []
        for j in range(bc.getNumJoints(uid)):
            own = bc.getJointInfo(uid, j)[12].decode("utf-8", "replace")
            links.append(None if file.hides_link(own) else unique_name(prefix + own, seen))
            seen.add(links[-1] or "")
        names.append(links)
    in_use = [n for links in names for n in links if n is not None and n in taken]
    if in_use:
        raise NameNotUniqueError(
            f"the model's link {in_use[0]!r} has the name of an existing entity; load it "
            "with another prefix")
    return names


def model_body(bc: BulletClient, change: Callable[..., Any], ccd_radius: float, uid: int,
               batch: int) -> Body:
    """A loaded body's records, with the settings every dynamic body gets."""
    static = bc.getDynamicsInfo(uid, -1)[0] <= 0
    # A multibody's damping (0.04 by default) slows its links too, welded base or not.
    change(uid, -1, linearDamping=0.0, angularDamping=0.0)
    if not static:
        change(uid, -1, ccdSweptSphereRadius=ccd_radius)
    return Body(uid, static, "model", (), None, batch, links=bc.getNumJoints(uid))


def entity_info(bc: BulletClient, name: str, body: Body, model: Model) -> EntityInfo:
    """A loaded entity as the World lists it: its mass is all its links'."""
    _, friction, restitution = props.properties(bc, body)
    return EntityInfo(name=name, shape="model", static=body.static,
                      mass=sum(m for m, _ in model.links), friction=friction,
                      restitution=restitution, source="model", model=name)


def link_info(bc: BulletClient, uid: int, link: int, name: str, root: str) -> EntityInfo:
    """A model's link as the World lists it (never static: it moves with its joint)."""
    info = bc.getDynamicsInfo(uid, link)
    return EntityInfo(name=name, shape="link", mass=float(info[0]), friction=float(info[1]),
                      restitution=float(info[5]), source="model", model=root)
