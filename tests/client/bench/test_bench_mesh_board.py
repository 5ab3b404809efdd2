"""The bench's groups for the paper-mesh board (every part a static mesh, the same poses and
reach as the primitives'), a few balls through it on every engine, and a board whose balls
carry their own inertia."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from galton.analysis.board import BoardSpec
from galton.client import Client
from galton.client.bench.build import ball_group, board_groups
from galton.client.bench.experiment import ExperimentConfig
from galton.client.bench.trial import TrialConfig, run_trial
from galton.protocol import BodyGroup


def test_the_mesh_board_is_the_paper_board_in_meshes() -> None:
    primitives = board_groups(BoardSpec.load("paper"), "mujoco")
    meshes = board_groups(BoardSpec.load("paper-mesh"), "mujoco")
    assert {g.shape for g in meshes} == {"mesh"} and all(g.static for g in meshes)
    assert [g.names for g in meshes] == [g.names for g in primitives]
    for prim, mesh in zip(primitives, meshes, strict=True):
        assert np.array_equal(prim.poses, mesh.poses)
        reach = (prim.size[0], prim.size[0], prim.size[1]) if prim.shape == "cylinder" \
            else prim.size
        assert mesh.size == pytest.approx(reach)
        BodyGroup.from_wire(mesh.to_wire())  # every part passes the protocol's checks


def test_a_ball_inertia_reaches_every_ball_count() -> None:
    board = BoardSpec.load("small")
    board = board.replace(ball=dataclasses.replace(board.ball, inertia=0.1))
    trial_board = ExperimentConfig(board=board, balls=(5,)).board_for(5)
    assert trial_board.ball.inertia == 0.1 and trial_board.ball.count == 5
    group = ball_group(trial_board, "mujoco", ["a"], np.zeros((1, 3)))
    assert group.inertia == (0.1, 0.1, 0.1)


def test_a_few_balls_settle_on_the_mesh_board(sim: Client, engine: str) -> None:
    """Every engine runs the paper-mesh board (ODE as trimeshes, DART as MeshShapes):
    three seeded balls through it, none lost, every part a mesh entity."""
    board = BoardSpec.load("paper-mesh")
    board = board.replace(ball=dataclasses.replace(board.ball, count=3))
    record = run_trial(sim, TrialConfig(engine, board, repetition=0, seed=3))
    assert (record.settled, record.lost, record.unsettled) == (3, 0, 0)
    assert sum(record.counts) == 3
    assert {e.shape for e in sim.list(tag="board")} == {"mesh"}
