"""Worlds and comparisons shared by the MuJoCo snapshot and clone tests: piles, a KUKA under
targets and a wrench, a world's full state, and bit-for-bit checks of two engines."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pybullet_data

from galton.daemon.engines.mujoco.engine import MujocoEngine
from galton.daemon.world.model_files import resolve_model
from galton.protocol import BodyGroup

KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa/model.urdf"
ALONG_Y = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))  # a lying cylinder
SEED = 25


def bodies(shape: str, names: list[str], size: tuple[float, ...], rng: np.random.Generator,
           height: float = 0.3, **options: Any) -> BodyGroup:
    """Bodies dropped at random over a 1 m square, turned at random."""
    poses = np.zeros((len(names), 7))
    poses[:, :2] = rng.uniform(-0.5, 0.5, (len(names), 2))
    poses[:, 2] = height + rng.uniform(0.0, 1.0, len(names))
    turns = rng.normal(size=(len(names), 4))
    poses[:, 3:] = turns / np.linalg.norm(turns, axis=1, keepdims=True)
    return BodyGroup(shape=shape, size=size, names=names, poses=poses, **options)


def floor() -> BodyGroup:
    return BodyGroup(shape="plane", size=(3.0, 3.0), names=["floor"],
                     poses=np.array([[0, 0, 0, 0, 0, 0, 1.0]]), static=True)


def pile(engine: MujocoEngine, rng: np.random.Generator, prefix: str = "",
         count: int = 70) -> None:
    """Spheres (a group big enough to be built apart and attached) and boxes on a floor."""
    engine.spawn([bodies("sphere", [f"{prefix}s{i}" for i in range(count)], (0.04,), rng),
                  bodies("box", [f"{prefix}b{i}" for i in range(12)], (0.05, 0.04, 0.03),
                         rng, friction=0.8, restitution=0.1)])


def kuka(engine: MujocoEngine) -> list[str]:
    """kuka_iiwa, fixed, integrated implicitly (see test_mujoco_joints.kuka)."""
    engine.set_params({"mujoco.integrator": "implicitfast"})
    text = resolve_model("urdf", KUKA.read_text(), str(KUKA), [])
    engine.load_model("urdf", text, None, "k/")
    return [j.name for j in engine.joints() if j.type == "revolute"]


def state(engine: MujocoEngine) -> np.ndarray:
    """Every entity's pose and twist, every joint's state and effort, the properties."""
    names = sorted(engine.entities)
    joints = [j.name for j in engine.joints() if j.type in ("revolute", "prismatic")]
    parts = [*engine.get_states(names), engine.properties(names)]
    if joints:
        parts += engine.get_joint_states(joints)
    return np.concatenate(parts, axis=None)


def restored(snapshot: dict[str, Any]) -> MujocoEngine:
    engine = MujocoEngine()
    engine.restore(snapshot)
    return engine


def assert_same_runs(a: MujocoEngine, b: MujocoEngine,
                     requests: list[Callable[[MujocoEngine], None]]) -> None:
    """The same requests on both give the same states, bit for bit, after each one."""
    np.testing.assert_array_equal(state(a), state(b))
    for request in requests:
        request(a)
        request(b)
        np.testing.assert_array_equal(state(a), state(b))
    assert a.state_within(1e6, 1e5) and b.state_within(1e6, 1e5)


def arrays(struct: Any) -> dict[str, np.ndarray]:
    """Every array of an MjModel or MjData but the data's arena (remade by each step)."""
    arena = ("efc_", "efm_", "iefc_", "island_", "map_", "iacc", "ifrc", "solver_")
    return {n: getattr(struct, n) for n in dir(struct) if not n.startswith(("_", *arena))
            and isinstance(getattr(struct, n, None), np.ndarray)}


SLEEP_BOOKS = ("tree_asleep", "tree_awake", "body_awake", "body_awake_ind",
               "parent_awake_ind", "dof_awake_ind")


def carried(data: Any) -> dict[str, np.ndarray]:
    """What a snapshot carries of an MjData: its float arrays and its sleep records."""
    return {n: v for n, v in arrays(data).items() if v.dtype == np.float64 or n in SLEEP_BOOKS}


def assert_same_world(a: MujocoEngine, b: MujocoEngine) -> None:
    """The compiled models alike in every array but the names (big groups' bodies are
    renamed in the spec after their compile: the source's model may hold their temporary
    names, which nothing reads); the data in every float array and the sleep records (its
    other integers are remade by the next step)."""
    for one, other in ((a.model, b.model), (a.data, b.data)):
        mine, theirs = arrays(one), arrays(other)
        mine = carried(one) if one is a.data else \
            {n: v for n, v in mine.items() if not n.startswith(("name_", "names"))}
        assert [n for n in mine if not np.array_equal(mine[n], theirs[n],
                                                      equal_nan=True)] == []
    assert [(n, getattr(a.data, n)) for n in ("ntree_awake", "nbody_awake", "nv_awake")] == \
        [(n, getattr(b.data, n)) for n in ("ntree_awake", "nbody_awake", "nv_awake")]


def steps(count: int) -> Callable[[MujocoEngine], None]:
    return lambda engine: engine.step(count)


def settled_pile(engine: MujocoEngine, rng: np.random.Generator) -> None:
    """A pile on a floor stepped until some of it sleeps in contact."""
    engine.spawn([floor()])
    pile(engine, rng)
    engine.step(1500)
    assert (engine.data.tree_asleep >= 0).any() and engine.data.ncon > 0


def pile_requests() -> list[Callable[[MujocoEngine], None]]:
    """Steps, a ball thrown up through the pile and a dynamics reset: what a settled pile's
    copy must follow bit for bit."""
    return [steps(1), steps(200), lambda e: e.set_states(
        ["s3"], np.array([[0, 0, 1.0, 0, 0, 0, 1]]), np.array([[0, 0, -1.0, 0, 0, 3]])),
        steps(400), lambda e: e.reset_dynamics(), steps(100)]


def kuka_under_targets(engine: MujocoEngine, rng: np.random.Generator) -> list[str]:
    """A KUKA holding position targets, pushed by a wrench, beside a small pile; its joints."""
    engine.spawn([floor()])
    joints = kuka(engine)
    pile(engine, rng, count=10)
    n = len(joints)
    engine.set_joint_targets(joints, "position", np.linspace(-0.5, 0.5, n), np.full(n, 300.0),
                             np.full(n, 20.0), np.full(n, np.inf))
    engine.set_wrenches(["k/lbr_iiwa_link_7"], np.array([[0, 0, 5.0, 0, 0, 1.0]]),
                        np.array([[0.0, 0.0, 1.2]]))
    engine.step(300)
    return joints


def retarget(joints: list[str]) -> Callable[[MujocoEngine], None]:
    """The first two joints switched to velocity targets and the wrenches cleared."""
    def request(engine: MujocoEngine) -> None:
        engine.set_joint_targets(joints[:2], "velocity", np.ones(2), np.zeros(2),
                                 np.full(2, 5.0), np.full(2, 50.0))
        engine.clear_wrenches(None)
    return request
