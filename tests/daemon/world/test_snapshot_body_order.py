"""A snapshot taken after big batch spawns restores every body as it was (issue 35): the
paper board spawned in its groups (MuJoCo builds big groups apart and attaches them, and
parks spare twins beside them), a tray and 100 balls resting on it. Restored from a slot or
from a blob, the world steps (MuJoCo used to answer PHYSICS_ERROR: the snapshot's MJCF
compiled the bodies in another order than its arrays were taken in) and the same steps give
the same states bit for bit. On every engine, over Zenoh."""

from __future__ import annotations

import numpy as np

from galton.analysis.board import BoardSpec
from galton.client import Client, boxes, spheres
from galton.client.bench.build import board_groups

BALLS = 100
RADIUS = 0.045
MASS = 0.3817
TRAY = (20.5, 0.5, -1.0)
TRAY_HALF = (1.0, 1.0, 0.05)
STEPS = 50


def _board_tray_and_balls(sim: Client, engine: str) -> list[str]:
    """The board, then a tray, then balls in a 10 x 10 grid resting on it: three spawns."""
    sim.spawn(*board_groups(BoardSpec.load("paper"), engine, 0.0))
    sim.spawn(boxes(["tray"], [TRAY], TRAY_HALF, static=True))
    names = [f"ball{i}" for i in range(BALLS)]
    grid = np.arange(BALLS)
    positions = np.column_stack([
        TRAY[0] - 0.45 + (grid % 10) * 0.1, TRAY[1] - 0.45 + (grid // 10) * 0.1,
        np.full(BALLS, TRAY[2] + TRAY_HALF[2] + RADIUS)])
    sim.spawn(spheres(names, positions, RADIUS, mass=MASS))
    return names


def _run(sim: Client, names: list[str]) -> np.ndarray:
    states = sim.step_and_read(STEPS, names)
    return np.hstack([states.poses, states.twists])


def test_a_world_of_big_spawns_steps_after_a_restore_as_its_source(sim: Client,
                                                                   engine: str) -> None:
    names = _board_tray_and_balls(sim, engine)
    sim.step(5)
    taken = sim.snapshot("board", blob=True)
    assert taken.blob is not None
    first = _run(sim, names)
    sim.restore("board")
    np.testing.assert_array_equal(_run(sim, names), first)
    sim.restore(blob=taken.blob)
    np.testing.assert_array_equal(_run(sim, names), first)
    assert np.isfinite(first).all()
    assert (first[:, 2] > TRAY[2]).all()  # the balls rest on the tray, not below it
