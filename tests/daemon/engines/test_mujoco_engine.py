"""The MuJoCo engine on its own, without a daemon: state kept across edits, physics, errors.

What every engine must do is checked by galton.daemon.engines.check (test_engine_check.py);
here is what is MuJoCo's own: its pool, its compiles, sleep, the sleep guard, its limits.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support.materials import board_defaults

from galton.daemon.engines.base import FEATURE_LOAD_MODEL, FEATURE_STATIC_POSE
from galton.daemon.engines.mujoco import engine as mujoco_engine
from galton.daemon.engines.mujoco import parked as mujoco_parked
from galton.daemon.engines.mujoco.engine import MujocoEngine
from galton.daemon.engines.mujoco.mj_spec import damping_ratio
from galton.daemon.engines.mujoco.sleep_guard import HOLD_LIMIT_S
from galton.protocol import (
    BODY_SHAPES,
    BodyGroup,
    BodyProperties,
    FeatureUnsupportedError,
    GaltonError,
    InvalidArgumentError,
    NameNotUniqueError,
    NotFoundError,
    OperationFailedError,
    ResourceLimitError,
)

GRAVITY = 9.81
DEFAULT_STEP = 0.002
RADIUS = 0.05
IDENTITY = (0.0, 0.0, 0.0, 1.0)
LIMITS = (1e6, 1e5)  # the daemon's default max_position (m) and max_speed (m/s)
ROBOT = """<mujoco>
  <worldbody>
    <body name="base" pos="0 0 1"><freejoint/><geom type="box" size=".1 .1 .1"/>
      <body name="arm" pos="0 0 .2"><joint type="hinge" axis="0 1 0"/>
        <geom type="capsule" size=".02 .1"/></body>
    </body>
    <body name="post" pos="1 0 .5"><geom type="box" size=".05 .05 .5"/></body>
    <body name="pendulum" pos="-1 0 1"><joint type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 .3 0 0" size=".02"/></body>
  </worldbody>
</mujoco>"""


def group(shape: str, names: Sequence[str], positions: Sequence[Sequence[float]],
          size: Sequence[float] = (RADIUS,), **options: Any) -> BodyGroup:
    rows = np.array([[*p, *IDENTITY] for p in positions], dtype=float)
    return BodyGroup(shape=shape, size=tuple(size), names=list(names), poses=rows, **options)


def ground() -> BodyGroup:
    return group("plane", ["ground"], [[0, 0, 0]], size=(5, 5), static=True)


def ball(name: str = "ball", z: float = 1.0, **options: Any) -> BodyGroup:
    return group("sphere", [name], [[0, 0, z]], **options)


def run(engine: MujocoEngine, seconds: float) -> None:
    engine.step(round(seconds / engine.timestep))


@pytest.fixture
def engine() -> MujocoEngine:
    return MujocoEngine()


def test_capabilities_describe_the_engine(engine: MujocoEngine) -> None:
    caps = engine.capabilities()
    assert caps.engine == "mujoco" and caps.engine_version
    assert set(caps.body_shapes) == set(BODY_SHAPES) and caps.model_formats == ("mjcf", "urdf")
    assert {FEATURE_LOAD_MODEL, FEATURE_STATIC_POSE} <= set(caps.features)
    assert caps.params["timestep"]["default"] == DEFAULT_STEP
    assert set(caps.params) == set(engine.get_params())


def test_angular_velocity_is_about_world_axes(engine: MujocoEngine) -> None:
    engine.set_params({"gravity": [0, 0, 0]})
    tilted = Rotation.from_euler("x", 90, degrees=True)
    pose = np.array([[0, 0, 0, *tilted.as_quat()]])
    spin = np.array([[0, 0, 0, 0, 0, 1.0]])
    engine.spawn([BodyGroup(shape="sphere", size=(0.1,), names=["s"], poses=pose,
                            twists=spin)])
    run(engine, 0.5)
    poses, twists = engine.get_states(["s"])
    expected = Rotation.from_euler("z", 0.5) * tilted
    assert (Rotation.from_quat(poses[0, 3:]) * expected.inv()).magnitude() < 1e-3
    np.testing.assert_allclose(twists[0], spin[0], atol=1e-9)


def test_a_batch_of_1000_spheres_costs_one_recompile(engine: MujocoEngine,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    calls = _count_compiles(monkeypatch)
    names = [f"ball_{i}" for i in range(1000)]
    grid = [[i % 40 * 0.2, i // 40 * 0.2, 1.0] for i in range(1000)]
    engine.spawn([group("sphere", names, grid)])
    assert len(calls) == 1
    poses, _ = engine.get_states(names)
    np.testing.assert_allclose(poses[:, :3], grid)
    engine.delete(names[::2])
    assert len(calls) == 1  # all parked in the pool: no compile
    best = min(_timed(lambda: engine.get_states(names[1::2])) for _ in range(20))
    assert best < 0.005


def _timed(call: Callable[[], object]) -> float:
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


@pytest.mark.parametrize("how", ["update", "default"])
def test_restitution_makes_a_ball_bounce(how: str) -> None:
    peaks = {}
    for e in (0.0, 0.6):
        world = MujocoEngine()
        world.spawn([ground(), ball(z=1.0)])
        if how == "update":
            world.update(["ground", "ball"], BodyProperties(restitution=e))
        else:
            world.set_params({"default_restitution": e, "default_static_restitution": e})
        run(world, 0.6)
        heights = []
        for _ in range(300):
            world.step(1)
            heights.append(world.get_states(["ball"])[0][0, 2])
        peaks[e] = max(heights)
    assert peaks[0.0] < 0.1 < peaks[0.6]


def test_damping_ratio_inverts_the_bounce_formula() -> None:
    assert damping_ratio(0.0, 0.1) == 1.0
    zeta = damping_ratio(0.5, 0.01)
    assert math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2)) == pytest.approx(0.5)
    assert damping_ratio(0.99, 0.1) == 0.1


def test_a_static_body_moves_by_set_states_and_rejects_a_twist(engine: MujocoEngine) -> None:
    engine.spawn([group("cylinder", ["early"], [[3, 3, 0.5]], size=(0.1, 0.5), static=True)])
    engine.spawn([group("box", ["shelf"], [[0, 0, 0.5]], size=(0.3, 0.3, 0.05), static=True),
                  ball(z=0.6)])
    run(engine, 0.5)
    resting = engine.get_states(["ball"])[0][0, 2]
    assert resting == pytest.approx(0.55 + RADIUS, abs=0.005)
    with pytest.raises(InvalidArgumentError, match="static"):
        engine.set_states(["shelf", "ball"], None, np.array([[0, 0, 0, 0, 0, 1.0], [0] * 6]))
    away = np.array([[5.0, 0, 0.5, *IDENTITY]])
    engine.set_states(["shelf"], away, np.zeros((1, 6)))
    poses, twists = engine.get_states(["shelf"])
    np.testing.assert_array_equal(poses, away)
    assert not twists.any()
    engine.spawn([ball("late", z=3.0)])
    engine.delete(["early"])
    np.testing.assert_array_equal(engine.get_states(["shelf"])[0], away)
    run(engine, 0.3)
    assert engine.get_states(["ball"])[0][0, 2] < resting - 0.2


def test_sleeping_bodies_wake_when_moved_or_their_support_moves(engine: MujocoEngine) -> None:
    engine.set_params({"mujoco.sleep_tolerance": 0.02})
    engine.spawn([group("box", ["shelf"], [[0, 0, 0.5]], size=(0.3, 0.3, 0.05), static=True),
                  ball(z=0.6), ground(), ball("parked", z=RADIUS)])
    run(engine, 2.0)
    assert not engine.get_states(["ball", "parked"])[1].any()  # asleep: exactly at rest
    engine.set_states(["shelf"], np.array([[5.0, 0, 0.5, *IDENTITY]]), None)
    engine.set_states(["parked"], np.array([[2.0, 0, 1.0, *IDENTITY]]), None)
    run(engine, 0.3)
    assert engine.get_states(["ball"])[0][0, 2] < 0.4
    assert engine.get_states(["parked"])[0][0, 2] < 0.7


def test_update_changes_mass_and_keeps_the_state(engine: MujocoEngine) -> None:
    # Sleeping off: in zero gravity, sleeping would stop ball a's slow rebound outright.
    engine.set_params({"gravity": [0, 0, 0], "mujoco.sleep_tolerance": 0.0})
    engine.spawn([group("sphere", ["a", "b"], [[0, 0, 1], [0.5, 0, 1]], friction=0.0)])
    engine.set_states(["a"], None, np.array([[1.0, 0, 0, 0, 0, 0]]))
    engine.step(10)
    before = engine.get_states(["a", "b"])
    engine.update(["b"], BodyProperties(mass=3 * 1000 * 4 / 3 * math.pi * RADIUS**3,
                                        rgba=(1, 0, 0, 1), friction=0.0))
    for got, want in zip(engine.get_states(["a", "b"]), before, strict=True):
        np.testing.assert_array_equal(got, want)
    run(engine, 1.0)
    velocity = engine.get_states(["a", "b"])[1][:, 0]
    assert velocity[0] + 3 * velocity[1] == pytest.approx(1.0, abs=1e-3)
    assert velocity[1] > 0.2


def test_params_set_get_and_keep_state(engine: MujocoEngine) -> None:
    engine.spawn([ball(z=5.0)])
    engine.step(50)
    before = engine.get_states(["ball"])
    engine.set_params({"timestep": 0.001, "mujoco.solver": "cg", "solver_iterations": 30,
                       "mujoco.solref": [0.01, 0.5], "default_friction": 0.3})
    assert engine.timestep == 0.001
    params = engine.get_params()
    assert params["mujoco.solver"] == "cg" and params["mujoco.solref"] == [0.01, 0.5]
    for got, want in zip(engine.get_states(["ball"]), before, strict=True):
        np.testing.assert_array_equal(got, want)


def _piles_after(threads: int, seconds: float) -> tuple[tuple[np.ndarray, np.ndarray], int]:
    """Three separate piles of balls (three islands) dropped onto a floor; their states
    and the number of worker threads MuJoCo ran with at the end."""
    engine = MujocoEngine()
    engine.set_params({"mujoco.threads": threads})
    engine.spawn([group("box", ["floor"], [[0, 0, -0.05]], size=(3, 3, 0.05), static=True)])
    for pile in range(3):
        names = [f"p{pile}_{i}" for i in range(20)]
        engine.spawn([group("sphere", names, [[pile * 1.0 + 0.01 * (i % 3), 0.01 * (i % 2),
                                                0.1 + 0.11 * i] for i in range(20)])])
    run(engine, seconds)
    states = engine.get_states([f"p{p}_{i}" for p in range(3) for i in range(20)])
    workers = engine.workers
    engine.close()
    return states, workers


def test_worker_threads_give_bit_identical_physics(monkeypatch: pytest.MonkeyPatch) -> None:
    """MuJoCo's thread pool solves islands in parallel; the trajectories must not change."""
    monkeypatch.setattr(mujoco_engine, "WORKERS_ON_CONTACTS", 1)  # crowded from 1 contact
    (single, none), (threaded, workers) = _piles_after(0, 1.0), _piles_after(2, 1.0)
    assert (none, workers) == (0, 2)
    for got, want in zip(threaded, single, strict=True):
        np.testing.assert_array_equal(got, want)
    assert single[0][:, 2].max() < 1.0  # the piles did fall and collide


def test_worker_threads_start_only_in_a_crowded_world() -> None:
    """A few bodies: no workers (their hand-off would cost more than it saves)."""
    assert _piles_after(2, 0.5)[1] == 0


def test_worker_threads_stop_when_the_crowd_thins(engine: MujocoEngine,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(mujoco_engine, "WORKERS_ON_CONTACTS", 1)
    monkeypatch.setattr(mujoco_engine, "WORKERS_OFF_CONTACTS", 1)
    engine.spawn([ground(), ball(z=RADIUS, twists=[[1.0, 0, 0, 0, 0, 0]])])  # rolls: 1 contact
    run(engine, 0.2)
    assert engine.workers == 1
    engine.set_states(["ball"], np.array([[0, 0, 50.0, *IDENTITY]]), None)  # no contact left
    run(engine, 0.2)
    assert engine.workers == 0


def test_worker_threads_can_change_at_run_time(engine: MujocoEngine,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(mujoco_engine, "WORKERS_ON_CONTACTS", 1)
    engine.spawn([ground(), ball(z=RADIUS, twists=[[1.0, 0, 0, 0, 0, 0]])])  # rolls: 1 contact
    engine.set_params({"mujoco.threads": 3})
    run(engine, 0.2)
    assert engine.workers == 3
    engine.set_params({"mujoco.threads": 0})
    assert engine.workers == 0 and engine.get_params()["mujoco.threads"] == 0
    with pytest.raises(InvalidArgumentError):
        engine.set_params({"mujoco.threads": -1})


def test_params_are_all_or_none(engine: MujocoEngine) -> None:
    before = engine.get_params()
    with pytest.raises(InvalidArgumentError):
        engine.set_params({"timestep": 0.001, "mujoco.cone": "round"})
    with pytest.raises(InvalidArgumentError):
        engine.set_params({"mujoco.solimp": [0.9, 0.95, 0.001, 0.5, 0.5]})
    assert engine.get_params() == before
    assert engine.timestep == DEFAULT_STEP


def test_load_model_makes_top_level_bodies_models_and_inner_ones_links(
        engine: MujocoEngine) -> None:
    engine.spawn([ground()])
    infos = engine.load_model("mjcf", ROBOT, None, "r1/")
    assert [(i.name, i.static, i.source, i.shape, i.model) for i in infos] == [
        ("r1/base", False, "model", "model", "r1/base"),
        ("r1/arm", False, "model", "link", "r1/base"),
        ("r1/post", True, "model", "model", "r1/post"),
        ("r1/pendulum", False, "model", "model", "r1/pendulum")]
    infos = [i for i in infos if i.shape == "model"]
    poses, _ = engine.get_states([i.name for i in infos])
    np.testing.assert_allclose(poses[:, :3], [[0, 0, 1], [1, 0, 0.5], [-1, 0, 1]])
    engine.load_model("mjcf", ROBOT, None, "r2/")
    run(engine, 1.0)
    assert engine.state_within(*LIMITS)
    assert engine.get_states(["r1/pendulum"])[1][0, 4] != 0
    with pytest.raises(FeatureUnsupportedError, match="joints"):
        engine.set_states(["r1/pendulum"], np.array([[0, 0, 3.0, *IDENTITY]]), None)
    engine.set_states(["r1/pendulum"], poses[2:], np.zeros((1, 6)))
    assert not engine.get_states(["r1/pendulum"])[1].any()
    engine.update(["r1/base"], BodyProperties(mass=5.0, friction=0.2))
    engine.delete([i.name for i in infos])
    engine.step(10)
    assert engine.get_states(["r2/base"])[0][0, 2] < 1.0


def test_a_broken_model_changes_nothing(engine: MujocoEngine, tmp_path: Path) -> None:
    engine.spawn([ball(z=2.0)])
    engine.step(20)
    before = engine.get_states(["ball"])
    broken = [ROBOT.replace("</mujoco>", ""),
              ROBOT.replace('size=".1 .1 .1"', 'size="-1"'),
              "<mujoco><worldbody><geom type='plane' size='1 1 1'/></worldbody></mujoco>"]
    for text in broken:
        with pytest.raises(InvalidArgumentError, match="MJCF"):
            engine.load_model("mjcf", text, None, "x/")
    engine.load_model("mjcf", ROBOT, None, "x/")
    with pytest.raises(NameNotUniqueError, match="x/base"):
        engine.load_model("mjcf", ROBOT, None, "x/")
    with pytest.raises(NameNotUniqueError, match="x/arm"):
        engine.spawn([ball("fine"), ball("x/arm")])
    with pytest.raises(NotFoundError):
        engine.get_states(["fine"])
    with pytest.raises(InvalidArgumentError):
        engine.load_model("mjcf", None, str(tmp_path / "missing.xml"), "y/")
    with pytest.raises(FeatureUnsupportedError):
        engine.load_model("sdf", "<sdf/>", None, "z/")
    for got, want in zip(engine.get_states(["ball"]), before, strict=True):
        np.testing.assert_array_equal(got, want)


def test_a_model_loads_from_a_path(engine: MujocoEngine, tmp_path: Path) -> None:
    path = tmp_path / "robot.xml"
    path.write_text(ROBOT)
    assert len(engine.load_model("mjcf", None, str(path), "p/")) == 4


def test_divergence_is_reported_logged_and_recoverable(engine: MujocoEngine,
                                                       monkeypatch: pytest.MonkeyPatch,
                                                       tmp_path: Path,
                                                       caplog: pytest.LogCaptureFixture) -> None:
    monkeypatch.chdir(tmp_path)
    engine.spawn([ground(), ball(z=0.5)])
    start = engine.get_states(["ball"])
    engine.set_states(["ball"], None, np.full((1, 6), 1e300))
    engine.step(5)
    assert not engine.state_within(*LIMITS)
    assert "unstable" in caplog.text
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
    engine.set_states(["ball"], *start)
    engine.reset_dynamics()
    engine.step(5)
    assert engine.state_within(*LIMITS)
    engine.set_states(["ball"], np.array([[0, 0, math.nan, *IDENTITY]]), None)
    engine.step(1)
    assert not engine.state_within(*LIMITS)


def test_state_within_reads_spin_about_world_axes(engine: MujocoEngine) -> None:
    """A free joint keeps its angular velocity in the body frame: 10 rad/s about world z,
    for a ball turned onto its side, is 10 about a body axis but still 10 about z."""
    engine.set_params({"gravity": [0, 0, 0]})
    tilted = Rotation.from_euler("xyz", [0.7, -0.4, 1.2]).as_quat()
    engine.spawn([BodyGroup("sphere", (0.1,), ["s"], np.array([[0, 0, 1, *tilted]]),
                            twists=np.array([[0, 0, 3.0, 0, 0, 10.0]]))])
    engine.step(1)
    assert engine.state_within(10.0, 10.001)
    assert not engine.state_within(10.0, 9.999)  # the spin
    assert not engine.state_within(1.0, 11.0)  # the height
    engine.set_states(["s"], None, np.array([[0, 0, 0, 7.0, 7.0, 0]]))  # |w| 9.9, each 7
    engine.step(1)
    assert engine.state_within(10.0, 7.001) and not engine.state_within(10.0, 6.999)


def test_parked_bodies_and_scenery_are_not_watched(engine: MujocoEngine) -> None:
    """Deleted balls wait 1 km below the world; static bodies may stand anywhere."""
    engine.spawn([ball("gone"), ball("kept", z=0.5),
                  group("box", ["far"], [[0, 0, -5e6]], size=(1, 1, 1), static=True)])
    engine.delete(["gone"])
    engine.step(5)
    assert engine.state_within(100.0, 100.0)


def test_a_loaded_models_jointed_parts_are_watched(engine: MujocoEngine) -> None:
    engine.load_model("mjcf", ROBOT, None, "r/")
    engine.step(1)
    assert engine.state_within(*LIMITS) and not engine.state_within(1.1, 1e5)  # base at z=1.2


SPHERE_MASS = 1000 * 4 / 3 * math.pi * RADIUS**3


def test_properties_tell_defaults_given_values_and_updates(engine: MujocoEngine) -> None:
    engine.spawn([ground(), ball("plain"), ball("given", mass=2.0, friction=0.9,
                                               restitution=0.1)])
    names = ["ground", "plain", "given"]
    np.testing.assert_allclose(engine.properties(names), [
        [math.nan, 1.0, 0.0], [SPHERE_MASS, 1.0, 0.0], [2.0, 0.9, 0.1]])
    engine.set_params({"default_friction": 0.7, "default_restitution": 0.5,
                       "default_static_friction": 0.3})
    np.testing.assert_allclose(engine.properties(names), [
        [math.nan, 0.3, 0.0], [SPHERE_MASS, 0.7, 0.5], [2.0, 0.9, 0.1]])
    engine.update(["plain", "ground"], BodyProperties(mass=1.5, friction=0.2, restitution=0.4))
    engine.set_params({"default_friction": 0.6})
    np.testing.assert_allclose(engine.properties(names), [
        [math.nan, 0.2, 0.4], [1.5, 0.2, 0.4], [2.0, 0.9, 0.1]])
    engine.delete(["given"])
    engine.spawn([ball("pooled", mass=2.0, friction=0.9, restitution=0.1)])  # a parked twin
    np.testing.assert_allclose(engine.properties(["pooled"]), [[2.0, 0.9, 0.1]])
    with pytest.raises(NotFoundError):
        engine.properties(["given"])


def test_properties_of_a_loaded_model(engine: MujocoEngine) -> None:
    """A model's mass is its subtree's, its friction its first geom's; its restitution is
    unknown (NaN: MuJoCo has none) until set."""
    engine.load_model("mjcf", ROBOT, None, "r/")
    names = ["r/base", "r/post", "r/pendulum"]
    m = engine.model
    masses = [float(m.body_subtreemass[engine.ids[n]]) for n in names]
    np.testing.assert_allclose(engine.properties(names), [
        [masses[0], 1.0, math.nan], [math.nan, 1.0, math.nan], [masses[2], 1.0, math.nan]])
    engine.update(["r/base"], BodyProperties(mass=5.0, friction=0.3, restitution=0.5))
    np.testing.assert_allclose(engine.properties(["r/base"]), [[5.0, 0.3, 0.5]])


# -- a refused change changes nothing ----------------------------------------------------
def _records(engine: MujocoEngine) -> tuple[object, ...]:
    """Everything a failed call must leave as it was: the spec, model, data, the engine's
    entities, ids and pool."""
    pool = {key: list(bodies) for key, bodies in engine.parked._parked.items()}
    return (engine.mj_spec.to_xml(), engine.model, engine.data, dict(engine.ids),
            list(engine.entities), pool)


def _busy_world(engine: MujocoEngine) -> None:
    engine.spawn([ground(), ball("a"), ball("b", z=2.0),
                  group("sphere", [f"many{i}" for i in range(100)], _grid(100, 3.0))])
    engine.load_model("mjcf", ROBOT, None, "r/")
    engine.step(10)


@pytest.mark.parametrize("names", [["a"], ["many3", "b"], ["r/base"]])
def test_a_refused_mass_changes_nothing_and_later_edits_work(engine: MujocoEngine,
                                                             names: list[str]) -> None:
    """A mass MuJoCo refuses used to stay in the spec, so every later recompile failed
    (and a delete then lost its bodies with a KeyError); a friction given with it was
    applied."""
    _busy_world(engine)
    before, props = _records(engine), engine.properties(names)
    with pytest.raises(InvalidArgumentError, match="mass"):
        engine.update(names, BodyProperties(mass=1e-300, friction=0.9, restitution=0.9))
    assert _records(engine) == before
    np.testing.assert_array_equal(engine.properties(names), props)
    engine.spawn([group("box", ["crate"], [[2, 2, 1]], size=(0.1, 0.1, 0.1))])  # compiles
    engine.delete([*names, "crate"])
    engine.update(["many7"], BodyProperties(mass=2.0))
    assert engine.properties(["many7"])[0, 0] == 2.0


@pytest.mark.parametrize("count", [1, 100])  # added directly, and attached (see mujoco_parked)
def test_a_refused_spawn_changes_nothing(engine: MujocoEngine, count: int) -> None:
    _busy_world(engine)
    before = _records(engine)
    names = [f"new{i}" for i in range(count)]
    with pytest.raises(InvalidArgumentError, match="mass"):
        engine.spawn([group("capsule", names, _grid(count, 4.0), size=(0.05, 0.1),
                            mass=1e-300)])
    assert _records(engine) == before
    engine.spawn([group("capsule", names, _grid(count, 4.0), size=(0.05, 0.1))])
    engine.delete(names)


CAMERA_ON_A = """<mujoco><worldbody>
  <body name="a" pos="0 0 1"><freejoint/><geom size=".1"/></body>
  <body name="c" pos="2 0 1"><geom size=".1"/><camera mode="targetbody" target="a"/></body>
</worldbody></mujoco>"""


def test_a_delete_mujoco_refuses_changes_nothing(engine: MujocoEngine) -> None:
    """Another body's camera aims at "m/a": MuJoCo cannot compile the world without it."""
    _busy_world(engine)
    engine.load_model("mjcf", CAMERA_ON_A, None, "m/")
    before = _records(engine)
    with pytest.raises(InvalidArgumentError, match="camera"):
        engine.delete(["a", "b", "m/a"])
    assert _records(engine) == before
    engine.delete(["a", "b", "m/a", "m/c"])
    engine.spawn([ball("a")])


def test_a_delete_whose_recompile_fails_faults_the_world_until_cleared(
        engine: MujocoEngine, monkeypatch: pytest.MonkeyPatch) -> None:
    """Removed bodies cannot be put back: if the recompile after them fails after all, the
    world reads as diverged (the World pauses it) until cleared."""
    _busy_world(engine)

    def failing(self: MujocoEngine, *args: int | None) -> None:
        raise InvalidArgumentError("MuJoCo rejected the change: out of luck")

    monkeypatch.setattr(MujocoEngine, "compile", failing)
    with pytest.raises(OperationFailedError, match="reset"):
        engine.delete([f"many{i}" for i in range(100)] + ["r/base"])
    assert not engine.state_within(*LIMITS)
    monkeypatch.undo()
    engine.clear()
    engine.spawn([ball()])
    engine.step(1)
    assert engine.state_within(*LIMITS)


# -- names ----------------------------------------------------------------------------------
def test_a_model_body_with_a_taken_name_is_refused(engine: MujocoEngine) -> None:
    """By an entity (a top-level body, or an inner one) or by another model's inner body."""
    engine.spawn([ball("r2/arm"), ball("r3/base", z=2.0)])
    engine.load_model("mjcf", ROBOT, None, "r/")
    before = _records(engine)
    for prefix, taken in (("r/", "r/base"), ("r2/", "r2/arm"), ("r3/", "r3/base")):
        with pytest.raises(NameNotUniqueError, match=taken):
            engine.load_model("mjcf", ROBOT, None, prefix)
        assert _records(engine) == before
    clash = ROBOT.replace('"arm"', '"elbow"').replace('"base"', '"base2"').replace(
        '"pendulum"', '"pendulum2"').replace('"post"', '"arm"')  # "r/arm": r's inner arm
    with pytest.raises(NameNotUniqueError, match="r/arm"):
        engine.load_model("mjcf", clash, None, "r/")
    with pytest.raises(NameNotUniqueError, match="r/arm"):
        engine.spawn([ball("r/arm")])  # a link
    engine.delete(["r/base"])  # its arm goes with it
    engine.spawn([ball("r/arm")])


@pytest.mark.parametrize("name", ["world", "galton.parked.1"])
def test_the_engines_own_body_names_are_refused(engine: MujocoEngine, name: str) -> None:
    engine.spawn([ball("a")])
    engine.delete(["a"])  # parks it as galton.parked.1
    with pytest.raises(InvalidArgumentError, match="own"):
        engine.spawn([ball(name)])


PRINTABLE = [chr(c) for c in range(0x20, 0x7F)] + ["é", "中", "\u00a0", "😀"]


def test_any_printable_prefix_loads_or_is_refused_with_a_typed_error(
        engine: MujocoEngine) -> None:
    engine.spawn([ball("keep", z=2.0)])
    before = engine.get_states(["keep"])
    for prefix in [*PRINTABLE, *(f"a{c}/" for c in PRINTABLE), ".", "..", "/", "a b"]:
        try:
            infos = engine.load_model("mjcf", ROBOT, None, prefix)
        except GaltonError:
            continue
        engine.delete([info.name for info in infos if info.shape == "model"])
    for got, want in zip(engine.get_states(["keep"]), before, strict=True):
        np.testing.assert_array_equal(got, want)


def slide_friction(engine: MujocoEngine, crate: str) -> float:
    """Launch a resting crate at 1 m/s along x; its deceleration over 0.1 s, in g."""
    engine.set_states([crate], None, np.array([[1.0, 0, 0, 0, 0, 0]]))
    run(engine, 0.1)
    return float((1.0 - engine.get_states([crate])[1][0, 0]) / 0.1 / GRAVITY)


def test_board_materials_bounce_like_a_hard_ball_and_slide_with_low_friction(
        engine: MujocoEngine) -> None:
    """The drop test behind docs/physics/mujoco.md: e ≈ 0.68 from 1 m, μ ≈ 0.5 sliding."""
    engine.set_params(board_defaults("mujoco"))
    floor = group("box", ["floor"], [[0, 0, -0.05]], size=(2, 2, 0.05), static=True)
    engine.spawn([floor, group("sphere", ["ball"], [[0, 0, 1.045]], size=(0.045,), mass=0.38)])
    speeds = []
    for _ in range(round(1.0 / engine.timestep)):
        engine.step(1)
        speeds.append(engine.get_states(["ball"])[1][0, 2])
    impact = int(np.argmax(np.array(speeds) > 0))
    bounce = max(speeds[impact:]) / -min(speeds[:impact])
    assert 0.6 < bounce < 0.75
    engine.spawn([group("box", ["crate"], [[1, 1, 0.05]], size=(0.05, 0.05, 0.05), mass=1.0)])
    run(engine, 0.2)
    assert 0.4 < slide_friction(engine, "crate") < 0.6


def test_a_contact_with_a_static_body_takes_the_static_surface(engine: MujocoEngine) -> None:
    """Scenery outranks moving bodies (geom priority): the crate's own friction is ignored
    on the floor, while the floor's friction, default or updated, decides."""
    engine.set_params(board_defaults("mujoco"))
    engine.spawn([group("box", ["floor"], [[0, 0, -0.05]], size=(2, 2, 0.05), static=True),
                  group("box", ["crate"], [[0, 0, 0.05]], size=(0.05, 0.05, 0.05), mass=1.0,
                        friction=1.0)])
    run(engine, 0.2)
    assert 0.4 < slide_friction(engine, "crate") < 0.6  # the floor's 0.5, not 1.0
    engine.update(["floor"], BodyProperties(friction=0.2))
    engine.set_states(["crate"], np.array([[0, 0, 0.05, *IDENTITY]]), None)
    run(engine, 0.2)
    assert 0.15 < slide_friction(engine, "crate") < 0.25
    engine.set_params({"default_static_friction": 0.8})  # the floor keeps its own 0.2
    engine.set_states(["crate"], np.array([[0, 0, 0.05, *IDENTITY]]), None)
    run(engine, 0.2)
    assert 0.15 < slide_friction(engine, "crate") < 0.25


def test_moving_bodies_collide_with_their_own_surface(engine: MujocoEngine) -> None:
    """Two balls meeting head-on bounce with the moving bodies' default restitution (0.3:
    measured e ≈ 0.38), whatever the scenery's; lowering it to 0.1 deadens them (e ≈ 0.2)."""
    engine.set_params(board_defaults("mujoco"))
    engine.set_params({"gravity": (0.0, 0.0, 0.0), "default_static_restitution": 0.0})
    bounces = []
    for restitution in (None, 0.1):
        if restitution is not None:
            engine.set_params({"default_restitution": restitution})
        poses = np.array([[-0.2, 0, 1, *IDENTITY], [0.2, 0, 1, *IDENTITY]])
        twists = np.array([[1.0, 0, 0, 0, 0, 0], [-1.0, 0, 0, 0, 0, 0]])
        engine.spawn([BodyGroup("sphere", (0.045,), ["a", "b"], poses, twists=twists,
                                mass=0.38)])
        run(engine, 0.5)
        velocity = engine.get_states(["a", "b"])[1][:, 0]
        bounces.append((velocity[1] - velocity[0]) / 2.0)
        engine.delete(["a", "b"])
    assert 0.3 < bounces[0] < 0.6
    assert 0.1 < bounces[1] < 0.3


def test_balls_at_rest_on_static_bodies_fall_asleep(engine: MujocoEngine) -> None:
    """With the defaults, a dropped ball stops bouncing and sleeps (no contact chatter).

    Static bodies are not mocap bodies, which MuJoCo keeps awake with all they touch.
    """
    engine.spawn([group("box", ["floor"], [[0, 0, -0.05]], size=(2, 2, 0.05), static=True),
                  group("cylinder", ["pin"], [[1, 0, 0.5]], size=(0.1, 0.3), static=True),
                  group("sphere", ["a"], [[0, 0, 0.545]], size=(0.045,), mass=0.38)])
    run(engine, 3.0)
    assert not engine.get_states(["a"])[1].any()  # asleep: exactly at rest
    engine.set_states(["pin"], np.array([[1, 0, 2.0, *IDENTITY]]), None)
    np.testing.assert_array_equal(engine.get_states(["pin"])[0][0, :3], [1, 0, 2.0])


ALONG_Y = (math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))  # a cylinder's axis turned onto y


def _posed(shape: str, name: str, pose: Sequence[float], size: Sequence[float],
           **options: Any) -> BodyGroup:
    return BodyGroup(shape=shape, size=tuple(size), names=[name],
                     poses=np.array([pose], dtype=float), **options)


def _crown_scene(support: str) -> list[BodyGroup]:
    """A ball set down 0.3 mm off the top of a lying pin, or of a ball resting on a floor."""
    floor = group("box", ["floor"], [[0, 0, -0.05]], size=(2, 2, 0.05), static=True)
    if support == "pin":
        below = _posed("cylinder", "below", (0, 0, 1.0, *ALONG_Y), (0.1, 0.3), static=True)
        top = 1.0 + 0.1 + 0.045
    else:
        below = group("sphere", ["below"], [[0, 0, 0.045]], size=(0.045,), mass=0.38)
        top = 0.045 + 0.09
    return [floor, below, group("sphere", ["a"], [[0.0003, 0, top]], size=(0.045,), mass=0.38)]


def _asleep_on_top(engine: MujocoEngine, support: str) -> float:
    """Spawn the crown scene with the guard off, let the ball fall asleep on top; its z."""
    start = float(_crown_scene(support)[2].poses[0, 2])
    engine.set_params({"mujoco.wake_balanced": False})
    engine.spawn(_crown_scene(support))
    run(engine, 2.0)
    pose, twist = engine.get_states(["a"])
    assert not twist.any() and pose[0, 2] == pytest.approx(start, abs=2e-3)  # asleep on top
    return start


def test_a_ball_asleep_on_a_pins_apex_is_woken_and_rolls_off(engine: MujocoEngine) -> None:
    """Sleeping would keep a ball balanced on a pin's apex for ever (about one ball in 5,000
    on the paper board); mujoco.wake_balanced wakes it and it rolls off, as a real one would.
    """
    start = _asleep_on_top(engine, "pin")
    engine.set_params({"mujoco.wake_balanced": True})
    run(engine, 3.0)
    assert engine.get_states(["a"])[0][0, 2] < start - 0.05  # rolled off the crown
    assert engine.sleep_guard is not None and not engine.sleep_guard.held


def test_a_ball_asleep_on_another_balls_crown_is_left_alone(engine: MujocoEngine) -> None:
    """Only fixed crowns count: a ball on a ball is in a pile, whose island it would keep
    awake."""
    start = _asleep_on_top(engine, "ball")
    engine.set_params({"mujoco.wake_balanced": True})
    run(engine, 1.0)
    pose, twist = engine.get_states(["a"])
    assert not twist.any() and pose[0, 2] == pytest.approx(start, abs=2e-3)


def test_a_ball_that_stays_on_its_crown_is_let_go_and_sleeps(engine: MujocoEngine) -> None:
    """Exactly on top, nothing tips the ball off; after HOLD_LIMIT_S the guard stops keeping
    it (and its pile) awake, and does not hold it again while it sleeps."""
    scene = _crown_scene("pin")
    scene[2].poses[0, 0] = 0.0  # dead centre: perfect balance
    engine.spawn(scene)
    run(engine, 1.0)
    assert engine.sleep_guard is not None and engine.sleep_guard.held
    run(engine, HOLD_LIMIT_S + 1.0)
    pose, twist = engine.get_states(["a"])
    assert not engine.sleep_guard.held
    assert not twist.any() and pose[0, 2] > 1.1  # asleep on the crown after all


def _arch_scene() -> list[BodyGroup]:
    """Two balls as a 500-ball paper trial left them asleep (seed 8, repetition 3): B on the
    shoulder of a pin, 15 degrees from its top; A on B, against the side of the pin above,
    by the back wall."""
    return [_posed("box", "wall", (0, 0.325, 3.5, 0, 0, 0, 1), (1, 0.05, 1), static=True),
            _posed("cylinder", "upper_pin", (0.75, 0, 3.904, *ALONG_Y), (0.1, 0.275),
                   static=True),
            _posed("cylinder", "lower_pin", (0.5, 0, 3.704, *ALONG_Y), (0.1, 0.275),
                   static=True),
            _posed("sphere", "A", (0.605, 0.2298, 3.9042, *IDENTITY), (0.045,), mass=0.38),
            _posed("sphere", "B", (0.5387, 0.2299, 3.8437, *IDENTITY), (0.045,), mass=0.38)]


@pytest.mark.parametrize("guard", [False, True])
def test_an_arch_on_a_pins_shoulder_is_not_frozen_by_sleep(engine: MujocoEngine,
                                                           guard: bool) -> None:
    """A creeps down the upper pin's side at about the sleep tolerance, so the pair falls
    asleep at once and, unguarded, stays there for good; awake, as the guard keeps B, the
    arch slips and both balls fall (as they do with sleeping off)."""
    engine.set_params({"mujoco.wake_balanced": guard})
    engine.spawn(_arch_scene())
    run(engine, 4.0)
    poses, twists = engine.get_states(["A", "B"])
    if guard:
        assert (poses[:, 2] < 3.6).all()  # both below the lower pin's centre: fallen
    else:
        assert not twists.any() and poses[1, 2] == pytest.approx(3.8437, abs=1e-3)


def test_clearing_the_world_gives_a_held_ball_its_sleep_policy_back(
        engine: MujocoEngine) -> None:
    """clear() parks bodies in the same compiled model: none may stay barred from sleep."""
    engine.spawn(_crown_scene("pin"))
    run(engine, 0.2)
    assert engine.sleep_guard is not None and engine.sleep_guard.held  # still on the crown
    engine.clear()
    never = int(mujoco.mjtSleepPolicy.mjSLEEP_NEVER)
    assert not (engine.model.tree_sleep_policy == never).any()


def test_how_steps_are_split_into_requests_does_not_change_the_trajectory() -> None:
    """The guard's looks fall on the world's own steps: a controller stepping one step at a
    time and a trial stepping in long runs see the same ball roll off the same crown."""
    trajectories = []
    for pieces in ([1] * 1500, [7, 50, 443, 1000], [1500]):
        engine = MujocoEngine()
        engine.spawn(_crown_scene("pin"))
        held = False
        for count in pieces:
            engine.step(count)
            held |= bool(engine.sleep_guard is not None and engine.sleep_guard.held)
        trajectories.append(engine.get_states(["a"]))
        assert held or pieces == [1500]  # the guard acted (seen between requests)
    for poses, twists in trajectories[1:]:
        np.testing.assert_array_equal(poses, trajectories[0][0])
        np.testing.assert_array_equal(twists, trajectories[0][1])
    assert trajectories[0][0][0, 2] < 1.1  # rolled off the crown


def test_a_rewound_world_replays_the_same_trajectory(engine: MujocoEngine) -> None:
    """stop (every body back to its created state, then reset_dynamics) replays the run
    exactly, even where the guard acted and the periodic looks were mid-period."""
    engine.spawn(_crown_scene("pin"))
    names = ["a", "below", "floor"]
    created = engine.get_states(names)
    runs = []
    for _ in range(2):
        engine.step(1525)  # not a multiple of the looks' period
        runs.append(engine.get_states(["a"]))
        engine.set_states(names, *created)
        engine.reset_dynamics()
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    assert runs[0][0][0, 2] < 1.1  # the guard made it roll off the crown


def test_wake_balanced_takes_only_a_boolean(engine: MujocoEngine) -> None:
    guard = engine.sleep_guard
    with pytest.raises(InvalidArgumentError, match=r"mujoco\.wake_balanced"):
        engine.set_params({"mujoco.wake_balanced": 1})
    assert engine.get_params()["mujoco.wake_balanced"] is True and engine.sleep_guard is guard


def test_balls_at_a_stable_rest_still_sleep_with_the_sleep_guard(
        engine: MujocoEngine) -> None:
    """On a flat cap, a floor, or between two pins, nothing is held awake."""
    engine.spawn([
        group("box", ["floor"], [[0, 0, -0.05]], size=(2, 2, 0.05), static=True),
        group("cylinder", ["post"], [[1, 0, 0.5]], size=(0.1, 0.5), static=True),
        _posed("cylinder", "left", (-1.12, 0, 1.0, *ALONG_Y), (0.1, 0.3), static=True),
        _posed("cylinder", "right", (-0.88, 0, 1.0, *ALONG_Y), (0.1, 0.3), static=True),
        group("sphere", ["on_cap", "on_floor", "wedged"],
              [[1.02, 0, 1.05], [0, 0, 0.05], [-1.0, 0, 1.2]], size=(0.045,), mass=0.38)])
    run(engine, 3.0)
    poses, twists = engine.get_states(["on_cap", "on_floor", "wedged"])
    assert not twists.any()  # all three asleep
    assert poses[0, 2] > 1.0 and poses[2, 2] > 1.0
    assert engine.sleep_guard is not None and not engine.sleep_guard.held


def test_contact_dimension_must_be_one_mujoco_has(engine: MujocoEngine) -> None:
    with pytest.raises(InvalidArgumentError, match="1, 3, 4, 6"):
        engine.set_params({"mujoco.condim": 5})
    engine.spawn([ball()])
    engine.set_params({"mujoco.condim": 6, "mujoco.rolling_friction": 0.001})
    assert engine.get_params()["mujoco.condim"] == 6


# -- the pool of parked bodies -----------------------------------------------------------
def _count_compiles(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    calls: list[int] = []
    original = MujocoEngine.compile

    def counting(self: MujocoEngine, *args: int | None) -> None:
        calls.append(1)
        original(self, *args)

    monkeypatch.setattr(MujocoEngine, "compile", counting)
    return calls


def _grid(n: int, z: float = 1.0) -> list[list[float]]:
    return [[i % 10 * 0.2, i // 10 * 0.2, z] for i in range(n)]


def test_a_spawn_of_a_kind_with_parked_twins_needs_no_compile(
        engine: MujocoEngine, monkeypatch: pytest.MonkeyPatch) -> None:
    calls = _count_compiles(monkeypatch)
    engine.spawn([ground(), group("sphere", ["a", "b"], _grid(2))])
    assert len(calls) == 1
    names = [f"ball_{i}" for i in range(10)]
    engine.spawn([group("sphere", names, _grid(10, 2.0), twists=np.tile([1.0, 0, 0, 0, 0, 0],
                                                                           (10, 1)))])
    assert len(calls) == 1  # bound to parked spares
    poses, twists = engine.get_states(names)
    np.testing.assert_allclose(poses[:, :3], _grid(10, 2.0))
    np.testing.assert_allclose(twists[:, 0], 1.0)
    run(engine, 4.0)
    poses, _ = engine.get_states(names)
    np.testing.assert_allclose(poses[:, 2], RADIUS, atol=5e-3)  # they collide with the ground
    engine.spawn([group("sphere", ["big"], _grid(1, 3.0), size=(0.2,))])
    assert len(calls) == 2  # another kind: compiled


def test_parked_bodies_are_invisible(engine: MujocoEngine) -> None:
    engine.spawn([ground(), ball("ball", z=0.5)])
    engine.delete(["ball"])
    engine.spawn([ball("other", z=0.3)])
    run(engine, 3.0)
    pose, _ = engine.get_states(["other"])
    np.testing.assert_allclose(pose[0, 2], RADIUS, atol=5e-3)
    engine.set_states(["other"], np.array([[0, 0, RADIUS * 0.99, *IDENTITY]]), None)
    engine.step(1)
    touching = engine.model.geom_bodyid[engine.data.contact.geom[:engine.data.ncon]]
    assert engine.data.ncon == 1  # the ground and "other" only: no parked body touches
    assert set(touching.ravel()) == {engine.ids["other"], engine.ids["ground"]}
    for name in ("ball", "ball_0"):
        with pytest.raises(NotFoundError):
            engine.get_states([name])
    m, d = engine.model, engine.data
    parked = [b for b in range(1, m.nbody) if b not in engine.ids.values()]
    assert parked and not m.body_contype[parked].any() and not m.body_conaffinity[parked].any()
    heights = d.xpos[parked, 2].copy()
    run(engine, 1.0)
    np.testing.assert_array_equal(d.xpos[parked, 2], heights)  # gravity does not pull them


def test_delete_then_respawn_reuses_and_keeps_other_states(
        engine: MujocoEngine, monkeypatch: pytest.MonkeyPatch) -> None:
    engine.spawn([ball("keep", z=5.0, twists=np.array([[0.3, 0, 0, 0, 0, 2.0]])),
                  ball("gone", z=1.0)])
    run(engine, 0.2)
    calls = _count_compiles(monkeypatch)
    engine.delete(["gone"])
    before = engine.get_states(["keep"])
    engine.spawn([ball("again", z=1.0)])
    assert not calls[1:]  # the delete's one compile; the respawn none
    for got, want in zip(engine.get_states(["keep"]), before, strict=True):
        np.testing.assert_array_equal(got, want)


def test_a_cleared_world_respawns_without_compiling_and_repeats_itself(
        engine: MujocoEngine, monkeypatch: pytest.MonkeyPatch) -> None:
    names = [f"b{i}" for i in range(10)]
    results, calls = [], _count_compiles(monkeypatch)
    for _ in range(3):
        engine.clear()
        engine.spawn([ground()])
        engine.spawn([group("sphere", names, [[i * 0.07, 0, 0.3 + 0.15 * i]
                                              for i in range(10)])])
        run(engine, 1.0)
        results.append(engine.get_states(names))
        assert engine.get_states(names)[0].shape == (10, 7)
    assert len(calls) == 2  # the first ground, the first balls; then all from the pool
    for again in results[1:]:  # pooled after a clear, the same as compiled afresh
        for got, want in zip(again, results[0], strict=True):
            np.testing.assert_array_equal(got, want)


def test_an_updated_body_is_not_parked_as_its_kind(engine: MujocoEngine) -> None:
    engine.spawn([ball("ball")])
    engine.update(["ball"], BodyProperties(friction=0.9))
    engine.delete(["ball"])
    engine.spawn([ball("next")])
    gid = engine.model.body_geomadr[engine.ids["next"]]
    assert engine.model.geom_friction[gid, 0] == engine.get_params()["default_friction"]


# -- size ---------------------------------------------------------------------------------
def _spheres(prefix: str, count: int, z: float, **options: Any) -> BodyGroup:
    side = math.ceil(math.sqrt(count))
    return group("sphere", [f"{prefix}{i}" for i in range(count)],
                 [[i % side * 0.2, i // side * 0.2, z] for i in range(count)], **options)


def test_thousands_of_static_bodies_step(engine: MujocoEngine) -> None:
    """MuJoCo's default arena left out the broadphase's nbody²/2-int buffers: 3,000 static
    spheres overflowed it at the first step."""
    engine.spawn([_spheres("pin", 3000, 0.0, static=True), ball(z=0.5)])
    run(engine, 1.0)
    assert 2 * RADIUS - 0.01 < engine.get_states(["ball"])[0][0, 2] < 0.3  # on pin0
    assert engine.state_within(*LIMITS)


def test_5000_free_spheres_fit_in_memory(engine: MujocoEngine) -> None:
    """MuJoCo's default arena, 40·nv² bytes, asked for 57 GB here: "Could not allocate
    memory"."""
    engine.spawn([ground(), _spheres("ball", 5000, 1.0)])
    engine.step(2)
    assert engine.model.narena < 40 * engine.model.nv ** 2 / 5
    assert engine.get_states(["ball4999"])[0][0, 2] < 1.0


@pytest.mark.slow  # a timing: on demand (-m slow), not in CI; benchmarks/spawn_scale.py
def test_spawn_cost_grows_linearly_with_the_bodies() -> None:
    """2,000 and 8,000 static spheres in one spawn: 0.09 and 0.41 s measured; before, MuJoCo's
    walk of the whole spec per body added made them 0.09 and 1.6 s."""
    def spawn_time(count: int) -> float:
        engine = MujocoEngine()
        group = _spheres("s", count, 0.0, static=True)
        return _timed(lambda: engine.spawn([group]))

    small = min(spawn_time(2000) for _ in range(2))
    assert spawn_time(8000) < 10 * small


def test_a_world_past_mujocos_body_limit_is_refused_up_front(engine: MujocoEngine) -> None:
    engine.spawn([ball("a")])
    before = _records(engine)
    with pytest.raises(ResourceLimitError, match="65533"):
        engine.spawn([_spheres("s", 70_000, 0.0, static=True)])
    assert _records(engine) == before


def test_attached_and_added_bodies_simulate_alike(monkeypatch: pytest.MonkeyPatch) -> None:
    """A group of ATTACH_MIN or more is built apart and attached: the same world, to the
    bit, as one whose bodies were added one by one."""
    results = []
    for attach_min in (mujoco_parked.ATTACH_MIN, 10_000):
        monkeypatch.setattr(mujoco_parked, "ATTACH_MIN", attach_min)
        engine = MujocoEngine()
        engine.spawn([ground(), group("sphere", [f"b{i}" for i in range(100)],
                                      [[i % 10 * 0.07, i // 10 * 0.07, 0.3 + 0.1 * i]
                                       for i in range(100)], friction=0.4)])
        engine.step(300)
        results.append(engine.get_states([f"b{i}" for i in range(100)]))
        assert not any(name.startswith("\x01") for name in engine.ids)
        assert "<default" not in engine.mj_spec.to_xml()  # no class left by the attaches
    for got, want in zip(*results, strict=True):
        np.testing.assert_array_equal(got, want)


def test_a_compile_past_max_free_bodies_is_refused_up_front(engine: MujocoEngine) -> None:
    """MuJoCo's compile is quadratic in free bodies: a spawn that would compile more than
    mujoco.max_free_bodies of them is refused before anything is done (a 65,000-ball spawn
    used to keep the daemon busy for longer than 15 minutes)."""
    engine.set_params({"mujoco.max_free_bodies": 4})
    engine.spawn([ground(), group("sphere", ["a", "b"], [[0, 0, 1], [1, 0, 1]])])
    before = engine.mj_spec.to_xml()
    with pytest.raises(ResourceLimitError, match="max_free_bodies") as caught:
        engine.spawn([group("box", ["c", "d", "e"], [[2, 0, 1], [3, 0, 1], [4, 0, 1]],
                            size=(0.05, 0.05, 0.05))])
    assert caught.value.details["count"] > 4
    assert engine.mj_spec.to_xml() == before
    statics = group("sphere", [f"s{i}" for i in range(10)], [[i, 1, 0] for i in range(10)])
    statics.static = True
    engine.spawn([statics])  # static bodies cost the compile nothing of that kind
    engine.step(2)
