"""Readying a parsed model (MJCF or URDF) for the world: names, a base, one actuator per joint.

Before a model is attached, every body and joint gets a name (the World addresses links and
joints by name), a URDF root gets a free joint when its base floats, the file's own
actuators go (nothing could drive them, and a servo among them would hold a joint the
contract calls free), and every 1-DOF joint gets one general actuator: gain fixed, bias
affine, all zero until a target is set (``joints.write_targets``). A joint's own
actuator force limit is lifted into the joint's description (``effort_limit``): only a
target's ``max_effort`` clips its effort.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco

BODY = mujoco.mjtObj.mjOBJ_BODY
SCALAR_JOINTS = (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)
# A URDF's joint limits are meant hard; MuJoCo's are soft, their default time constant
# (0.02 s) letting a driven kuka_iiwa joint pass its limit by 0.02 rad under 50 N·m. URDF
# joints get this stiffer one: twice the default timestep (MuJoCo itself never goes below
# twice the timestep in use, so a larger timestep stays stable).
URDF_LIMIT_SOLREF = (0.004, 1.0)
_FALSE = mujoco.mjtLimited.mjLIMITED_FALSE
# A URDF link named "world" (MuJoCo's name for its world body) goes by this name in MuJoCo:
# until attached, and for good when attached without a prefix (see ``entity_name``).
WORLD_LINK = "world"
STAND_IN = "galton.urdf.world"
_TRUE = mujoco.mjtLimited.mjLIMITED_TRUE


@dataclass
class Facts:
    """What the compiled model does not tell about a model, by unprefixed name: joints'
    effort and velocity limits, fixed joints' names by their child link, and the links
    that go by a stand-in name until attached (a URDF's ``world``)."""

    effort: dict[str, float] = field(default_factory=dict)
    velocity: dict[str, float] = field(default_factory=dict)
    fixed: dict[str, str] = field(default_factory=dict)
    renamed: dict[str, str] = field(default_factory=dict)  # stand-in body -> link name

    def link_name(self, body: str) -> str:
        """A body's link name (the stand-in's real one), unprefixed."""
        return self.renamed.get(body, body)


def rename_attached(spec: mujoco.MjSpec, prefix: str, facts: Facts) -> None:
    """Give the bodies that went by stand-in names their link names, once attached (but a
    link attached as "world" keeps its stand-in: the world body has that name)."""
    for stand_in, name in facts.renamed.items():
        if prefix + name != WORLD_LINK:
            spec.body(prefix + stand_in).name = prefix + name


def entity_name(body: str) -> str:
    """The entity a MuJoCo body of a model is: its name, but for a link named "world"."""
    return WORLD_LINK if body == STAND_IN else body


def body_name(entity: str) -> str:
    """The MuJoCo body of a model's entity (``entity_name`` reversed)."""
    return STAND_IN if entity == WORLD_LINK else entity


def free_joint_name(body: str) -> str:
    """The name of a floating base's joint when the file names none."""
    return f"{body}:free"


def fixed_joint_name(body: str) -> str:
    """The name of a jointless link's weld to its parent when the file names none."""
    return f"{body}:fixed"


def ready_model(child: mujoco.MjSpec, facts: Facts, *, float_base: bool, urdf: bool) -> None:
    """Name, float (URDF's ``fixed_base=False``) and actuate a parsed model, in place;
    a URDF's joint limits made stiff."""
    name_bodies(child)
    if float_base:
        for top in child.worldbody.bodies:
            if not top.joints:
                top.add_freejoint(name=free_joint_name(top.name))
    name_joints(child)
    for actuator in list(child.actuators):
        child.delete(actuator)
    for joint in child.joints:
        keep_effort_limit(joint, facts)
        if urdf:
            joint.solref_limit = URDF_LIMIT_SOLREF
        if joint.type in SCALAR_JOINTS:
            add_actuator(child, joint.name)


def name_bodies(child: mujoco.MjSpec) -> None:
    """Give every unnamed body a name unique in the model: ``body<i>``."""
    taken = {b.name for b in child.bodies}
    counter = 0
    for body in [*child.worldbody.bodies, *child.worldbody.find_all(BODY)]:
        while not body.name:
            candidate = f"body{counter}"
            counter += 1
            if candidate not in taken:
                body.name = candidate
                taken.add(candidate)


def name_joints(child: mujoco.MjSpec) -> None:
    """Give every unnamed joint a name: ``<body>:free`` for a free one, else
    ``<body>:joint<k>`` (k its place among the body's joints)."""
    for body in child.worldbody.find_all(BODY):
        for k, joint in enumerate(body.joints):
            if not joint.name:
                free = joint.type == mujoco.mjtJoint.mjJNT_FREE
                joint.name = free_joint_name(body.name) if free else f"{body.name}:joint{k}"


def keep_effort_limit(joint: mujoco.MjsJoint, facts: Facts) -> None:
    """Record the joint's actuator force range as its effort limit, then lift it."""
    lo, hi = (float(v) for v in joint.actfrcrange)
    limited = joint.actfrclimited == _TRUE or (joint.actfrclimited != _FALSE and lo < hi)
    if limited and joint.name not in facts.effort:
        facts.effort[joint.name] = max(abs(lo), abs(hi))
    joint.actfrclimited = _FALSE


def add_actuator(child: mujoco.MjSpec, joint: str) -> None:
    """A general actuator on this joint, named like it, exerting nothing until set."""
    actuator = child.add_actuator(name=joint, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT,
                                  gaintype=mujoco.mjtGain.mjGAIN_FIXED,
                                  biastype=mujoco.mjtBias.mjBIAS_AFFINE)
    actuator.gainprm[0] = 0.0
    actuator.ctrllimited = _FALSE
    actuator.forcelimited = _FALSE
    actuator.actlimited = _FALSE
