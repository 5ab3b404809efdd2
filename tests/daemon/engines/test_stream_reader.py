"""A state stream's pose reader (Engine.pose_reader) reads what get_states reads, for every
kind of body, and the world says when a reader must be made anew (World.layout)."""

from __future__ import annotations

import numpy as np
import pytest
from support.mujoco_worlds import KUKA, bodies, floor

from galton.daemon.engines import create_engine
from galton.daemon.world.world import World
from galton.protocol import BodyGroup

SEED = 41


def _world(engine: str) -> World:
    world = World(create_engine(engine))
    rng = np.random.default_rng(SEED)
    world.spawn([floor(), bodies("sphere", [f"s{i}" for i in range(40)], (0.04,), rng),
                 bodies("box", [f"b{i}" for i in range(5)], (0.05, 0.04, 0.03), rng)])
    return world


@pytest.mark.parametrize("engine", ["mujoco", "pybullet", "ode", "dart"])
def test_the_reader_reads_what_get_states_reads_while_the_world_plays(engine: str) -> None:
    world = _world(engine)
    world.load_model("urdf", None, str(KUKA), "k/", search=[KUKA.parent])
    names = sorted(world.entities)  # the floor, free bodies, a model's root and links
    read = world.engine.pose_reader(names)
    for _ in range(3):
        world.step(25)
        np.testing.assert_array_equal(read(), world.engine.get_states(names)[0])
    world.engine.close()


@pytest.mark.parametrize("engine", ["mujoco", "pybullet", "ode", "dart"])
def test_a_new_layout_after_delete_and_spawn_gets_a_reader_that_agrees(engine: str) -> None:
    world = _world(engine)
    before = world.layout
    world.delete(["s3", "b1"])
    world.spawn([BodyGroup(shape="sphere", size=(0.04,), names=["late"],
                           poses=np.array([[0.2, 0.1, 0.5, 0, 0, 0, 1.0]]))])
    assert world.layout == before + 2
    names = sorted(world.entities)
    read = world.engine.pose_reader(names)
    world.step(10)
    np.testing.assert_array_equal(read(), world.engine.get_states(names)[0])
    world.engine.reset_dynamics()  # PyBullet makes every body again (new ids)
    world.step(10)
    np.testing.assert_array_equal(read(), world.engine.get_states(names)[0])
    world.engine.close()


@pytest.mark.parametrize("engine", ["ode", "dart"])
def test_a_reader_kept_over_a_remade_body_reads_the_new_one(engine: str) -> None:
    """ODE's reader gathers from the bodies' memory: a body deleted and made again under
    its name lives elsewhere, and a reader that outlives that must find it, never read the
    freed memory."""
    world = _world(engine)
    names = sorted(world.entities)
    read = world.engine.pose_reader(names)
    world.step(5)
    world.delete(["s3"])
    world.spawn([BodyGroup(shape="sphere", size=(0.04,), names=["filler", "s3"],
                           poses=np.array([[-0.7, 0.4, 0.9, 0, 0, 0, 1.0],
                                           [0.7, -0.4, 0.9, 0, 0, 0, 1.0]]))])
    world.step(5)
    poses = read()
    np.testing.assert_array_equal(poses, world.engine.get_states(names)[0])
    assert poses[names.index("s3")][0] == pytest.approx(0.7)
    world.engine.close()
