"""Engine checks for articulated models: links as entities, joints, joint states, the
target law, wrenches and the rewind of joints (each skipped when the engine does not list
the feature it tests). The rig is a URDF written here: a fixed base, an arm on a hinge
about y, a carriage sliding along the arm, and a tip mounted on it by a fixed joint."""

from __future__ import annotations

import numpy as np

from galton.daemon.engines.base import (
    FEATURE_JOINT_TARGETS,
    FEATURE_JOINTS,
    FEATURE_TARGET_EFFORT,
    FEATURE_TARGET_POSITION,
    FEATURE_WRENCH,
    Engine,
)
from galton.daemon.engines.check.support import (
    CheckContext,
    CheckSkippedError,
    expect,
    expect_close,
    group,
    skip_unless,
    states,
)

LINK = ('<link name="{name}"><inertial><mass value="{mass}"/><inertia ixx="0.01" ixy="0" '
        'ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial><collision><geometry><box '
        'size="0.1 0.1 0.1"/></geometry></collision></link>')
RIG = ("<robot name='rig'>" + "".join(LINK.format(name=n, mass=m) for n, m in (
    ("base", 2.0), ("arm", 1.0), ("carriage", 0.5), ("tip", 0.1))) + """
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 1"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" effort="50" velocity="5"/></joint>
  <joint name="slider" type="prismatic"><parent link="arm"/><child link="carriage"/>
    <axis xyz="1 0 0"/><limit lower="-0.2" upper="0.4" effort="20" velocity="1"/></joint>
  <joint name="mount" type="fixed"><parent link="carriage"/><child link="tip"/>
    <origin xyz="0 0 -0.1"/></joint>
</robot>""")
DRIVEN = ["r_hinge", "r_slider"]


def load_rig(engine: Engine) -> None:
    """The rig under the prefix ``r_``, with a fixed base (skipped without URDF or joints)."""
    skip_unless(engine, FEATURE_JOINTS)
    if "urdf" not in engine.capabilities().model_formats:
        raise CheckSkippedError("the engine loads no URDF")
    engine.load_model("urdf", RIG, None, "r_", fixed_base=True)


def check_model_links_and_joints(ctx: CheckContext) -> None:
    """A URDF loads as a root entity (shape "model") and one entity per other link (shape
    "link"), all naming the root as their model; joints() lists the file's joints with
    their types, links, unit axis in the child's frame and limits, each free of targets."""
    engine = ctx.engine
    skip_unless(engine, FEATURE_JOINTS)
    if "urdf" not in engine.capabilities().model_formats:
        raise CheckSkippedError("the engine loads no URDF")
    infos = engine.load_model("urdf", RIG, None, "r_", fixed_base=True)
    shapes = [(i.name, i.shape, i.model) for i in infos]
    expect(shapes == [("r_base", "model", "r_base"), ("r_arm", "link", "r_base"),
                      ("r_carriage", "link", "r_base"), ("r_tip", "link", "r_base")],
           "load_model's entities", "the root, then its three links", shapes)
    joints = {j.name: j for j in engine.joints()}
    seen = {n: (j.type, j.parent, j.child, j.mode) for n, j in joints.items()}
    expect(seen == {"r_hinge": ("revolute", "r_base", "r_arm", "none"),
                    "r_slider": ("prismatic", "r_arm", "r_carriage", "none"),
                    "r_mount": ("fixed", "r_carriage", "r_tip", "none")},
           "joints()", "hinge, slider and mount as in the file, no target held", seen)
    hinge = joints["r_hinge"]
    expect_close(np.array(hinge.axis), np.array([0.0, 1.0, 0.0]), 1e-9, "the hinge's axis")
    expect((hinge.lower, hinge.upper) == (-1.5, 1.5), "the hinge's limits", "(-1.5, 1.5)",
           (hinge.lower, hinge.upper))


def check_joint_state_round_trip(ctx: CheckContext) -> None:
    """Joint positions and velocities set between steps read back as set (1e-9), and the
    links move with them: a hinge turned by 0.5 rad swings the carriage's frame about y."""
    engine = ctx.engine
    load_rig(engine)
    engine.set_joint_states(DRIVEN, np.array([0.5, 0.1]), np.array([0.2, -0.3]))
    positions, velocities, _ = engine.get_joint_states(DRIVEN)
    expect_close(positions, np.array([0.5, 0.1]), 1e-9, "joint positions set")
    expect_close(velocities, np.array([0.2, -0.3]), 1e-9, "joint velocities set")
    poses, _ = states(engine, ["r_carriage"])
    # The carriage slid 0.1 m along the arm's x, which turned 0.5 rad about y at z = 1.
    expected = np.array([0.1 * np.cos(0.5), 0.0, 1.0 - 0.1 * np.sin(0.5)])
    expect_close(poses[0, :3], expected, 1e-6, "the carriage's frame after the teleport")


def check_target_law(ctx: CheckContext) -> None:
    """A position target applies kp (target - q), clipped to max_effort, minus kd q̇ at the
    velocity the step ends with (damping is implicit, and not clipped), and an effort target
    its value clipped, as the effort get_joint_states reports after one step."""
    engine = ctx.engine
    load_rig(engine)
    skip_unless(engine, FEATURE_JOINT_TARGETS)
    skip_unless(engine, FEATURE_TARGET_POSITION)
    skip_unless(engine, FEATURE_TARGET_EFFORT)
    engine.set_joint_states(DRIVEN, np.array([0.2, 0.0]), np.zeros(2))
    kp, kd = np.array([40.0, 30.0]), np.array([2.0, 1.0])
    engine.set_joint_targets(DRIVEN, "position", np.array([0.3, 0.1]), kp, kd,
                             np.array([np.inf, 1.0]))
    engine.step(1)
    _, velocities, efforts = engine.get_joint_states(DRIVEN)
    expect_close(efforts, np.array([40.0 * 0.1, 1.0]) - kd * velocities, 1e-6,
                 "the position law's effort (the slider's drive clipped to 1 N)")
    engine.set_joint_targets(DRIVEN, "effort", np.array([-3.0, 5.0]), np.zeros(2),
                             np.zeros(2), np.array([np.inf, 2.0]))
    engine.step(1)
    _, _, efforts = engine.get_joint_states(DRIVEN)
    expect_close(efforts, np.array([-3.0, 2.0]), 1e-9, "effort targets (clipped to 2 N)")


def check_wrench(ctx: CheckContext) -> None:
    """A held horizontal force F on a free body of mass m accelerates it at F/m (1 %), and
    it stops acting once cleared."""
    engine = ctx.engine
    skip_unless(engine, FEATURE_WRENCH)
    engine.spawn([group("sphere", ["ball"], [0, 0, 10.0], mass=2.0)])
    engine.set_wrenches(["ball"], np.array([[3.0, 0, 0, 0, 0, 0]]), None)
    steps = round(0.5 / engine.timestep)
    engine.step(steps)
    _, twists = states(engine, ["ball"])
    t = steps * engine.timestep
    expect_close(twists[0, :1], np.array([1.5 * t]), 0.01 * 1.5 * t, "speed under F/m")
    engine.clear_wrenches(None)
    engine.step(steps)
    _, after = states(engine, ["ball"])
    expect_close(after[0, :1], twists[0, :1], 1e-9, "speed once the wrench is cleared")


def check_joint_rewind(ctx: CheckContext) -> None:
    """restore_joints puts every joint back as loaded, at rest, with no target held."""
    engine = ctx.engine
    load_rig(engine)
    loaded, _, _ = engine.get_joint_states(DRIVEN)
    engine.set_joint_states(DRIVEN, np.array([0.7, 0.3]), np.array([1.0, 1.0]))
    if FEATURE_TARGET_EFFORT in engine.capabilities().features:
        engine.set_joint_targets(DRIVEN, "effort", np.full(2, 1.0), np.zeros(2),
                                 np.zeros(2), np.full(2, np.inf))
    engine.restore_joints()
    positions, velocities, _ = engine.get_joint_states(DRIVEN)
    expect_close(positions, loaded, 1e-9, "joint positions after restore_joints")
    expect_close(velocities, np.zeros(2), 1e-9, "joint velocities after restore_joints")
    modes = {j.name: j.mode for j in engine.joints() if j.name in DRIVEN}
    expect(set(modes.values()) == {"none"}, "target modes after restore_joints", "none",
           modes)
