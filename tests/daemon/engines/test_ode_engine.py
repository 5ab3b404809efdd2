"""The ODE engine on its own, in-process: what is its own beyond the engine checks
(test_engine_check.py runs those): Webots' settings, sleeping, snapshots of sleeping worlds,
the QuickStep option, contact reports and ray casts."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from galton.analysis.board import BoardSpec
from galton.daemon.engines.ode.engine import OdeEngine
from galton.protocol import BodyGroup
from galton.protocol.mesh import box_mesh

RADIUS = 0.05
WEBOTS = {"timestep": 0.002, "ode.stepper": "world", "ode.cfm": 1e-5, "ode.erp": 0.2,
          "ode.contact_soft_cfm": 0.001, "ode.contact_soft_erp": 0.2,
          "ode.bounce_velocity": 0.01, "ode.max_contacts": 10, "ode.auto_disable": True,
          "ode.disable_time": 1.0, "default_friction": 1.0, "default_restitution": 0.5}


@pytest.fixture
def engine() -> Iterator[OdeEngine]:
    made = OdeEngine()
    yield made
    made.close()


def poses_at(positions: Any) -> np.ndarray:
    rows = np.atleast_2d(np.asarray(positions, dtype=float))
    return np.column_stack([rows, np.tile([0.0, 0.0, 0.0, 1.0], (len(rows), 1))])


def balls(names: list[str], positions: Any, **options: Any) -> BodyGroup:
    return BodyGroup("sphere", (RADIUS,), names, poses_at(positions), **options)


def ground() -> BodyGroup:
    return BodyGroup("plane", (5.0, 5.0), ["ground"], poses_at([0, 0, 0]), static=True)


def seconds(engine: OdeEngine, duration: float) -> None:
    engine.step(round(duration / engine.timestep))


def test_the_defaults_are_webots_settings(engine: OdeEngine) -> None:
    params = engine.capabilities().params
    assert {name: params[name]["default"] for name in WEBOTS} == WEBOTS
    assert BoardSpec.load("paper-webots").contacts["ode"].params["timestep"] == 0.032


def test_a_ball_bounces_back_half_as_fast_at_any_step(engine: OdeEngine) -> None:
    """Webots' bounce 0.5 (0.48 with its soft contact), at 2 ms as at Webots' 32 ms: the
    soft CFM follows the step (params.py, ode.soft_cfm_step)."""
    for timestep in (0.002, 0.032):
        engine.clear()
        engine.set_params({"timestep": timestep})
        engine.spawn([ground(), balls(["ball"], [0, 0, 0.2], twists=[[0, 0, -3.0, 0, 0, 0]])])
        down = up = 0.0
        for _ in range(round(0.3 / timestep)):
            engine.step(1)
            speed = float(engine.get_states(["ball"])[1][0, 2])
            down, up = min(down, speed), max(up, speed)
        assert up / -down == pytest.approx(0.48, abs=0.02)


def test_bodies_at_rest_sleep_leave_the_callback_and_wake_when_hit(engine: OdeEngine) -> None:
    engine.spawn([ground(), balls(["resting"], [0, 0, RADIUS])])
    seconds(engine, 1.5)
    assert not engine._bodies["resting"].awake
    before = engine._collider.pairs
    engine.step(10)
    assert engine._collider.pairs == before  # a sleeping ball on the floor costs no call
    engine.spawn([balls(["falling"], [0.0, 0.0, 0.5])])
    seconds(engine, 0.5)
    assert engine._bodies["resting"].awake


def _pile(engine: OdeEngine) -> None:
    positions = [[0.02 * (i % 2), 0.01 * (i % 3), 0.1 + 0.11 * i] for i in range(6)]
    engine.spawn([ground(), balls([f"s{i}" for i in range(6)], positions)])


def test_a_snapshot_of_a_sleeping_pile_replays_bit_for_bit(engine: OdeEngine) -> None:
    """Sleep flags travel; idle counters restart on both sides (canonical), so a ball
    dropped on the pile wakes it the same way in the source and in the restored world."""
    engine.spawn([ground(), balls([f"s{i}" for i in range(6)],
                                  [[0.2 * i, 0.0, RADIUS + 0.01] for i in range(6)])])
    seconds(engine, 2.0)
    assert not any(b.awake for b in engine._moving)
    copy = OdeEngine()
    try:
        copy.restore(engine.snapshot())
        for world in (engine, copy):
            world.spawn([balls(["dropped"], [0.01, 0.0, 1.2])])
            seconds(world, 1.5)
        names = [f"s{i}" for i in range(6)] + ["dropped"]
        for mine, theirs in zip(engine.get_states(names), copy.get_states(names), strict=True):
            assert np.array_equal(mine, theirs)
    finally:
        copy.close()


def test_quickstep_replays_bit_for_bit() -> None:
    runs = []
    for _ in range(2):
        engine = OdeEngine()
        engine.set_params({"ode.stepper": "quick", "solver_iterations": 10})
        _pile(engine)
        seconds(engine, 0.5)
        runs.append(engine.get_states([f"s{i}" for i in range(6)])[0])
        engine.close()
    assert np.array_equal(runs[0], runs[1])


def test_a_resting_ball_reports_its_weight_pushing_down(engine: OdeEngine) -> None:
    engine.spawn([ground(), balls(["ball"], [0, 0, RADIUS], mass=2.0)])
    engine.set_params({"ode.auto_disable": False})
    seconds(engine, 0.5)
    firsts, seconds_, points, normals, forces, depths = engine.contacts(["ball"])
    assert len(firsts) == 1 and {firsts[0], seconds_[0]} == {"ball", "ground"}
    down = np.array([0.0, 0.0, -1.0 if firsts[0] == "ball" else 1.0])
    np.testing.assert_allclose(normals[0], down, atol=1e-9)
    assert forces[0] == pytest.approx(2.0 * 9.81, rel=0.02)
    assert abs(points[0, 2]) < 0.005 and 0 <= depths[0] < 0.005


def test_a_ray_hits_the_nearest_ball(engine: OdeEngine) -> None:
    engine.spawn([ground(), balls(["near", "far"], [[1, 0, 1], [2, 0, 1]])])
    hits, names, points, normals, distances = engine.raycast(
        np.array([[0.0, 0, 1], [0.0, 0, 3]]), np.array([[1.0, 0, 0], [0, 1.0, 0]]), 10.0)
    assert hits.tolist() == [True, False] and names == ["near", ""]
    np.testing.assert_allclose(points[0], [1 - RADIUS, 0, 1], atol=1e-9)
    np.testing.assert_allclose(normals[0], [-1, 0, 0], atol=1e-9)
    assert distances[0] == pytest.approx(1 - RADIUS) and np.isnan(distances[1])


def test_a_robot_with_targets_and_a_wrench_replays_after_a_restore(engine: OdeEngine) -> None:
    from galton.daemon.engines.check.joints import DRIVEN, RIG

    engine.load_model("urdf", RIG, None, "r_", fixed_base=True)
    engine.spawn([ground(), balls(["ball"], [0.3, 0.0, 2.0])])
    engine.set_joint_targets(DRIVEN, "position", np.array([0.4, 0.1]), np.array([40.0, 30.0]),
                             np.array([2.0, 1.0]), np.array([np.inf, 5.0]))
    engine.set_wrenches(["r_tip"], np.array([[0.0, 0.0, 3.0, 0.0, 0.0, 0.0]]), None)
    engine.step(50)
    copy = OdeEngine()
    try:
        copy.restore(engine.snapshot())
        names = ["r_base", "r_arm", "r_carriage", "r_tip", "ball"]
        for world in (engine, copy):
            world.step(200)
        for mine, theirs in zip(engine.get_states(names), copy.get_states(names), strict=True):
            assert np.array_equal(mine, theirs)
        assert np.array_equal(engine.get_joint_states(DRIVEN)[2], copy.get_joint_states(
            DRIVEN)[2])
    finally:
        copy.close()


def test_a_mesh_off_its_origin_weighs_its_volume_and_replays_bit_for_bit(
        engine: OdeEngine) -> None:
    """A moving mesh box whose vertices lie 0.1 m off its origin: ODE's integral gives its
    mass (1000 kg/m³ × 0.032 m³); its body sits at that centre, yet it reports its origin,
    and a snapshot (which carries the mesh) replays its spin bit for bit."""
    vertices, faces = box_mesh((0.2, 0.2, 0.1))
    crate = BodyGroup("mesh", (0.3, 0.2, 0.1), ["crate"], poses_at([1.0, 0.0, 0.3]),
                      vertices=vertices + np.array([0.1, 0.0, 0.0]), faces=faces)
    engine.spawn([ground(), crate])
    assert engine.properties(["crate"])[0, 0] == pytest.approx(32.0)
    seconds(engine, 1.0)
    pose = engine.get_states(["crate"])[0][0]
    assert pose[:3] == pytest.approx([1.0, 0.0, 0.1], abs=1e-3)
    engine.set_states(["crate"], None, np.array([[0.0, 0.0, 2.0, 0.0, 0.0, 3.0]]))
    copy = OdeEngine()
    try:
        copy.restore(engine.snapshot())
        for world in (engine, copy):
            seconds(world, 0.2)
        for mine, theirs in zip(engine.get_states(["crate"]), copy.get_states(["crate"]),
                                strict=True):
            assert np.array_equal(mine, theirs)
    finally:
        copy.close()


def _hostile_copies(data: dict[str, Any]) -> Iterator[tuple[str, dict[str, Any]]]:
    """The snapshot with one moving body's or link's numbers made hostile: each would abort
    ODE (dxNormalize4) at the next step if it were written into ODE's memory."""
    import copy as copying

    from galton.daemon.engines.ode.native import AVEL, QUAT
    ball = next(k for k, b in enumerate(data["bodies"]) if b.get("name") == "ball")
    model = next(k for k, b in enumerate(data["bodies"]) if "model" in b)
    for label, start, values in (("zero quaternion", QUAT, [0.0] * 4),
                                 ("huge quaternion", QUAT, [1e155, 0.0, 0.0, 0.0]),
                                 ("huge spin", AVEL, [1e300, 0.0, 0.0])):
        edited = copying.deepcopy(data)
        edited["bodies"][ball]["state"][start:start + len(values)] = values
        yield f"ball {label}", edited
        edited = copying.deepcopy(data)
        edited["bodies"][model]["links"][1]["state"][start:start + len(values)] = values
        yield f"link {label}", edited
    edited = copying.deepcopy(data)
    edited["bodies"][ball]["wrench"] = [1e308, 0.0, 0.0, 0.0, 0.0, 0.0]
    yield "huge wrench", edited
    edited = copying.deepcopy(data)
    edited["bodies"][model]["joints"][0]["kp"] = 1e308
    yield "huge gain", edited


def test_a_hostile_snapshot_is_refused_before_ode_sees_it(engine: OdeEngine) -> None:
    """Issue 46: a re-sealed blob's body state is written straight into ODE's memory; a
    zero quaternion, a huge spin or a huge wrench or gain in it must be refused first."""
    from galton.daemon.engines.check.joints import RIG
    from galton.protocol import InvalidArgumentError
    engine.load_model("urdf", RIG, None, "r_", fixed_base=True)
    engine.spawn([ground(), balls(["ball"], [0.3, 0.0, 2.0])])
    engine.set_wrenches(["ball"], np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]]), None)
    engine.step(5)
    data = engine.snapshot()
    for label, hostile in _hostile_copies(data):
        copy = OdeEngine()
        try:
            with pytest.raises(InvalidArgumentError):
                copy.restore(hostile)
        finally:
            copy.close()
        assert label
    copy = OdeEngine()
    try:
        copy.restore(data)  # the untouched one still restores, and steps
        copy.step(5)
    finally:
        copy.close()


@pytest.mark.parametrize(("old", "new"), [
    ('<mass value="0.5"/>', '<mass value="1e-300"/>'),
    ('ixx=".001" iyy=".001" izz=".001"', 'ixx="1e-320" iyy="1e-320" izz="1e-320"'),
    ('ixx=".001" iyy=".001" izz=".001"', 'ixx=".001" iyy=".001" izz="-1"'),
])
def test_a_link_ode_would_abort_on_is_refused(engine: OdeEngine, old: str, new: str) -> None:
    """Issue 46: a URDF link of 1e-300 kg (or a degenerate inertia) pushed by an effort made
    ODE's quaternion infinite (SIGABRT in dxNormalize4); now load_model refuses it, and
    the world holds nothing of it."""
    from galton.client.fuzz.extremes import ARM
    from galton.protocol import InvalidArgumentError
    assert old in ARM
    with pytest.raises(InvalidArgumentError, match="upper"):
        engine.load_model("urdf", ARM.replace(old, new, 1), None, "t_", fixed_base=True)
    assert engine.joints() == []
    engine.spawn([ground(), balls(["ball"], [0.0, 0.0, 1.0])])
    engine.step(5)
