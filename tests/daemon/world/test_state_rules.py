"""State changes only when a request asks for it (issue 35, items 1, 2 and 4): a refused
state is never applied, a read never faults a world, and nothing observable (contacts,
efforts) moves without a step. On both engines, over Zenoh (engine semantics)."""

from __future__ import annotations

import numpy as np
import pytest
from support import send_over_the_edge, snapshot
from support.models import get_joint_states, model_snapshot, set_joint_states, set_targets
from support.urdf import ARM_URDF

from galton.client import Client, plane, spheres
from galton.protocol import InvalidArgumentError, PhysicsError

TOO_FAST = 1.5e5  # beyond the default max_speed of 1e5 m/s


def test_a_refused_joint_state_is_not_applied(sim: Client) -> None:
    sim.call("load_model", {"format": "urdf", "text": ARM_URDF, "fixed_base": True})
    before = model_snapshot(sim)
    with pytest.raises(InvalidArgumentError, match="150000"):
        sim.call("set_joint_states", {"names": ["hinge"], "positions": 0.1,
                                      "velocities": TOO_FAST, "read": ["arm"]})
    model_snapshot(sim).assert_same(before)
    assert not sim.status().faulted
    assert sim.step(2).step == 2


def test_a_refused_twist_is_not_applied_and_reads_never_fault(sim: Client) -> None:
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05))
    before = snapshot(sim)
    with pytest.raises(InvalidArgumentError, match="limit"):
        sim.set_states(["ball"], twists=np.array([[TOO_FAST, 0, 0, 0, 0, 0]]))
    snapshot(sim).assert_same(before)
    assert not sim.status().faulted


def test_a_state_within_the_limits_faults_at_the_step_not_at_a_read(sim: Client) -> None:
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05))
    send_over_the_edge(sim)
    for _ in range(2):
        assert sim.get_states(["ball"]).positions[0, 0] == 999_999.0
    assert not sim.status().faulted
    with pytest.raises(PhysicsError, match="diverged"):
        sim.step(5)
    assert sim.status().faulted


def test_contacts_and_efforts_do_not_change_without_a_step(sim: Client) -> None:
    """Spawning and deleting an unrelated body (a recompile on MuJoCo) leaves the last
    step's contacts and the joints' efforts as they were."""
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.049]], 0.05))
    sim.call("load_model", {"format": "urdf", "text": ARM_URDF, "fixed_base": True,
                            "prefix": "r_"})
    set_targets(sim, ["r_hinge"], "position", 0.5, kp=5.0, kd=0.1)
    sim.step(7)
    contacts, efforts = sim.contacts(), get_joint_states(sim).efforts
    assert len(contacts.a) > 0 and np.any(efforts)
    sim.spawn(spheres(["far"], [[50, 50, 5]], 0.05))
    sim.delete(["far"])
    after = sim.contacts()
    assert (after.a, after.b) == (contacts.a, contacts.b)
    np.testing.assert_array_equal(after.positions, contacts.positions)
    np.testing.assert_array_equal(after.forces, contacts.forces)
    np.testing.assert_array_equal(get_joint_states(sim).efforts, efforts)


def test_set_joint_states_keeps_a_state_within_the_limits(sim: Client) -> None:
    sim.call("load_model", {"format": "urdf", "text": ARM_URDF, "fixed_base": True})
    set_joint_states(sim, ["hinge"], 0.3, 2.0)
    states = get_joint_states(sim, ["hinge"])
    assert (states.positions[0], states.velocities[0]) == pytest.approx((0.3, 2.0))
