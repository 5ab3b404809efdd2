"""calibrate fits a joint's damping on every engine: a pendulum let go in a "reality" side
world whose hinge is damped (0.4 N·m·s/rad) is recorded; the live world's own pendulum,
undamped, is calibrated from a snapshot of the same start, and ``apply`` sets the fit,
which a fork keeps and a restore of the earlier snapshot undoes."""

from __future__ import annotations

import pytest
from support.models import G, Pendulum, joints, load, set_joint_states

from galton.client import Client

TRUE_DAMPING = 0.4  # N·m·s/rad: the swing (pivot inertia 0.26 kg·m²) loses a third a second
DT = 0.002


def pendulum_urdf(damping: float) -> str:
    """support.models.Pendulum with a "tip" link welded at the bob: the bob link's frame is
    the hinge's (it turns in place), the tip's swings, and calibrate fits positions."""
    text = Pendulum(damping=damping).urdf()
    tip = f"""  <link name="tip"><inertial><mass value="0.001"/>
    <inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="weld" type="fixed"><parent link="bob"/><child link="tip"/>
    <origin xyz="0 0 {-Pendulum().length}"/></joint>
</robot>"""
    return text.replace("</robot>", tip)


def pendulum_world(sim: Client, damping: float) -> None:
    sim.set_params({"timestep": DT, "gravity": [0.0, 0.0, -G]})
    load(sim, "urdf", text=pendulum_urdf(damping))
    set_joint_states(sim, ["hinge"], [1.0], [0.0])


def test_a_joint_damping_is_fitted_to_what_was_seen(sim: Client) -> None:
    sim.create_world("reality")
    reality = sim.world("reality")
    try:
        pendulum_world(reality, TRUE_DAMPING)
        seen = reality.predict(0.6, every=0.03, read=["tip"])
    finally:
        sim.delete_world("reality")
    pendulum_world(sim, 0.0)
    sim.snapshot(slot="start")
    result = sim.calibrate({"hinge.damping": (0.0, 2.0)}, ["tip"], seen.times, seen.poses,
                           slot="start", max_predictions=40, population=6, apply=True)
    assert result.fitted["hinge.damping"] == pytest.approx(TRUE_DAMPING, rel=0.1), result
    assert result.error_after < result.error_before / 10
    fitted = result.fitted["hinge.damping"]
    assert damping_of(sim) == pytest.approx(fitted)  # applied
    sim.fork_world("copy")
    try:
        assert damping_of(sim.world("copy")) == pytest.approx(fitted)  # a fork keeps it
    finally:
        sim.delete_world("copy")
    sim.restore(slot="start")  # the slot was taken before: undamped again
    assert damping_of(sim) == 0.0


def damping_of(sim: Client) -> float:
    return next(j.damping for j in joints(sim) if j.name == "hinge")
