"""What a trial looked like: galton-client bench renders each engine's first trial beside
the report (and, asked, an animated replay), the camera sees the whole board, and a report
shows the pictures its results name, or why one is missing."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
from support.daemons import start_daemon
from support.synthetic_runs import law_trials
from typer.testing import CliRunner

from galton.analysis.board import BoardSpec
from galton.analysis.records import ExperimentResults
from galton.analysis.report import render_report
from galton.analysis.summary import summarise
from galton.client import Client, EmbeddedDaemon
from galton.client.bench.build import board_groups
from galton.client.bench.picture import (
    PICTURE_SIZE,
    Animation,
    board_camera,
    encode_apng,
    first_trials,
)
from galton.client.bench.trial import TrialConfig
from galton.client.cli.app import app
from galton.protocol.png import decode_png

runner = CliRunner()
SEED = 26
DRAWS = 200
BALL_RED = (200, 60, 60)  # brighter red, darker green and blue than this: a ball's pixel


def test_bench_renders_the_first_trial_beside_the_report(daemons: dict[str, EmbeddedDaemon],
                                                         tmp_path: Path) -> None:
    daemon = start_daemon(daemons, "mujoco")
    out = tmp_path / "run"
    result = runner.invoke(app, [
        "bench", "--connect", daemon.endpoint, "--instances", daemon.instance, "--engines",
        "mujoco", "--board", "small", "--balls", "10", "--repetitions", "2", "--animation",
        "--out", str(out), "--json"])
    assert result.exit_code == 0, result.output
    picture = decode_png((out / "board_mujoco.png").read_bytes())
    assert picture.shape == (PICTURE_SIZE[1], PICTURE_SIZE[0], 3)
    red = ((picture[..., 0] > BALL_RED[0]) & (picture[..., 1] < BALL_RED[1])
           & (picture[..., 2] < BALL_RED[2]))
    assert red[picture.shape[0] * 3 // 4:].sum() > 10 * red[:picture.shape[0] // 2].sum()
    assert apng_frames((out / "board_mujoco_trial.png").read_bytes()) == Animation().frames
    report = (out / "report.md").read_text()
    assert "![mujoco: the board after its first trial](board_mujoco.png)" in report
    assert "(board_mujoco_trial.png)" in report
    saved = json.loads((out / "results.json").read_text())["extra"]["pictures"]
    assert set(saved.values()) == {"board_mujoco.png", "board_mujoco_trial.png"}


def test_the_board_camera_sees_the_whole_board(mujoco_sim: Client) -> None:
    board = BoardSpec.load("paper")
    mujoco_sim.spawn(*board_groups(board, "mujoco"))
    mujoco_sim.delete(["front_glass"])
    view = {**board_camera(board, (135, 180)), "outputs": ["segmentation"]}
    (image,) = mujoco_sim.render(view)
    assert image.segmentation is not None
    seen = {image.labels[i] for i in np.unique(image.segmentation) if i >= 0}
    everything = {e.name for e in mujoco_sim.list(tag="board")}
    assert everything <= seen
    assert (image.segmentation[:, 0] == -1).any()  # room around the board: it fits


def test_first_trials_pick_each_engines_first() -> None:
    board = BoardSpec.load("small")
    plan = [TrialConfig(e, board, r) for e in ("mujoco", "pybullet") for r in range(3)]
    assert first_trials(plan) == {0: "mujoco", 3: "pybullet"}


def test_a_report_shows_pictures_or_why_there_is_none() -> None:
    law = np.full(12, 1 / 12)
    trials = law_trials("mujoco", "all-at-once", 100, law, SEED)
    pictures = {"mujoco: the board after its first trial": "board_mujoco.png",
                "pybullet: the board after its first trial": "no picture (cannot render)"}
    results = ExperimentResults(trials=trials, extra={"pictures": pictures})
    summaries = summarise(trials, draws=DRAWS)
    text = render_report(results, summaries, [], (), draws=DRAWS)
    assert "![mujoco: the board after its first trial](board_mujoco.png)" in text
    assert "pybullet: the board after its first trial: no picture (cannot render)" in text
    plain = render_report(ExperimentResults(trials=trials), summaries, [], (), draws=DRAWS)
    assert "What a trial looked like" not in plain


def apng_frames(data: bytes) -> int:
    """The frame count an animated PNG declares (its acTL chunk)."""
    at = data.index(b"acTL")
    frames: int = struct.unpack(">I", data[at + 4:at + 8])[0]
    return frames


def test_an_apng_declares_its_frames() -> None:
    frames = [np.full((4, 5, 3), k, np.uint8) for k in range(3)]
    data = encode_apng(frames, 100)
    assert apng_frames(data) == 3
    assert np.array_equal(decode_png(data), frames[0])  # viewers without APNG: frame one
