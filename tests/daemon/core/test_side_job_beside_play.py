"""A side world's step request while the live world plays: the live world's steps are its
own, and never count towards the side world's request (the side world takes exactly the
steps it was asked for)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from support.worlds import clean

from galton.client import Client, spheres


@pytest.fixture
def world(sim: Client) -> Iterator[Client]:
    with clean(sim) as client:
        try:
            yield client
        finally:
            client.stop()
            client.reset()


def test_a_side_world_takes_exactly_its_steps_while_the_live_world_plays(
        world: Client) -> None:
    world.spawn(spheres(["live_ball"], [[0, 0, 1]], 0.05))
    world.create_world("side")
    side = world.world("side")
    side.spawn(spheres(["ball"], [[0, 0, 1]], 0.05))
    world.play(rtf=0.0)  # the live world steps as fast as it can beside the side job
    try:
        stamp = side.step(3000)
        read = side.step_and_read(500, ["ball"])
    finally:
        world.pause()
    assert world.status().step > 0
    assert stamp.step == 3000
    assert side.status().step == 3500
    assert read.step == 3500
