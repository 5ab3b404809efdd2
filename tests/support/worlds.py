"""Helpers of the worlds and snapshots tests: a client whose daemon holds no side world and
no snapshot slot before and after the test (the session's daemons outlive each test), and
scenes with contacts to compare bit for bit."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from galton.client import Client, boxes, plane, spheres

BALL_RADIUS = 0.05


def clear_worlds(sim: Client) -> None:
    """Delete every side world and every snapshot slot of ``sim``'s daemon."""
    for world in sim.list_worlds():
        if not world.live:
            sim.delete_world(world.name)
    for slot in sim.snapshots():
        assert slot.slot is not None
        sim.delete_snapshot(slot.slot)


@contextmanager
def clean(sim: Client) -> Iterator[Client]:
    clear_worlds(sim)
    try:
        yield sim
    finally:
        clear_worlds(sim)


def contact_scene(sim: Client) -> list[str]:
    """Ground, a stack of overlapping spheres and boxes: contacts from the first step."""
    sim.spawn(plane())
    balls = [f"ball_{i}" for i in range(4)]
    sim.spawn(spheres(balls, [[0.03 * i, 0.01 * i, 0.05 + 0.09 * i] for i in range(4)],
                      BALL_RADIUS))
    crates = ["crate_0", "crate_1"]
    sim.spawn(boxes(crates, [[0.3, 0.0, 0.05], [0.32, 0.01, 0.14]], [0.05, 0.05, 0.05]))
    return balls + crates


def same_states(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> bool:
    return bool(np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]))
