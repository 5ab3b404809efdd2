"""What a trial looked like (the paper's Fig. 2): the board rendered after a trial, and on
request a short animation of a trial replayed beside the record.

Pictures are taken only after a trial's record is complete, so the bench's figures never
include rendering. The front glass is removed from the finished world first: PyBullet's
TinyRenderer draws it opaque and it would hide the board.
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from galton.analysis.board import BoardSpec
from galton.client.bench.build import ball_group
from galton.client.bench.trial import TrialConfig, prepare_world
from galton.client.sdk.client import Client
from galton.client.sdk.perception import camera
from galton.protocol import GaltonError, OperationFailedError
from galton.protocol.png import SIGNATURE, chunk, encode_png

PICTURE_SIZE = (540, 720)  # width, height: the board is taller than wide
ANIMATION_SIZE = (270, 360)
FOV_DEG = 40.0
MARGIN = 1.08  # the board fills the picture but for this much room around it
GLASS_TAG = "glass"


@dataclass(frozen=True)
class Animation:
    """How a trial's animation is sampled: ``frames`` pictures ``every`` s of sim time."""

    frames: int = 60
    every: float = 0.1
    delay_ms: int = 100


def board_camera(board: BoardSpec, size: tuple[int, int] = PICTURE_SIZE) -> dict[str, Any]:
    """A camera in front of the glass, facing the board, the whole board in view."""
    half_width = board.walls.inner_x + board.walls.thickness
    half_height = max(board.walls.height, board.pins.top_row_z) / 2
    tangent = math.tan(math.radians(FOV_DEG / 2))
    distance = MARGIN * max(half_height / tangent, half_width / (tangent * size[0] / size[1]))
    centre = (0.0, board.cavity.centre_y, half_height)
    eye = (0.0, board.cavity.centre_y - distance, half_height)
    return camera(eye, centre, up=(0, 0, 1), fov=FOV_DEG, size=size, near=0.1,
                  far=3 * distance)


def _without_glass(sim: Client) -> None:
    glass = [e.name for e in sim.list(tag=GLASS_TAG)]
    if glass:
        sim.delete(glass)


def render_board(sim: Client, board: BoardSpec, path: Path) -> Path:
    """The finished trial in ``sim``'s world as an RGB PNG at ``path`` (the world's glass
    is deleted: call only when its trial is recorded)."""
    _without_glass(sim)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(encode_png(_rgb(sim, board_camera(board))))
    return path


def _rgb(sim: Client, view: dict[str, Any]) -> np.ndarray:
    (image,) = sim.render(view)
    if image.rgb is None:
        raise OperationFailedError("the daemon sent no rgb image for a camera asking for it")
    return image.rgb


def animate_trial(sim: Client, trial: TrialConfig, path: Path,
                  plan: Animation = Animation()) -> Path:
    """Replay ``trial`` on ``sim`` (a fresh world; the record is not touched) and write an
    animated PNG of it: balls released at their times, a frame every ``plan.every`` s."""
    shake, names = prepare_world(sim, trial)
    _without_glass(sim)
    view = board_camera(trial.board, ANIMATION_SIZE)
    times = shake.release.times
    released, frames = 0, []
    for k in range(plan.frames):
        now = k * plan.every
        ready = int(np.searchsorted(times, now + 1e-9, side="right"))
        if ready > released:
            sim.spawn(ball_group(trial.board, trial.engine, names[released:ready],
                                 shake.release.positions[released:ready]))
            released = ready
        if now > 0:
            sim.run_until(now)
        frames.append(_rgb(sim, view))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(encode_apng(frames, plan.delay_ms))
    return path


def encode_apng(frames: list[np.ndarray], delay_ms: int) -> bytes:
    """An animated PNG of (h, w, 3) uint8 frames, looping; viewers without APNG show the
    first frame."""
    height, width = frames[0].shape[:2]
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    out = [SIGNATURE, chunk(b"IHDR", header),
           chunk(b"acTL", struct.pack(">II", len(frames), 0))]
    sequence = 0
    for index, frame in enumerate(frames):
        control = struct.pack(">IIIIIHHBB", sequence, width, height, 0, 0, delay_ms, 1000,
                              0, 0)
        out.append(chunk(b"fcTL", control))
        sequence += 1
        rows = np.hstack([np.zeros((height, 1), np.uint8), frame.reshape(height, -1)])
        data = zlib.compress(rows.tobytes(), 6)
        if index == 0:
            out.append(chunk(b"IDAT", data))
        else:
            out.append(chunk(b"fdAT", struct.pack(">I", sequence) + data))
            sequence += 1
    out.append(chunk(b"IEND", b""))
    return b"".join(out)


def first_trials(plan: list[TrialConfig]) -> dict[int, str]:
    """The index in ``plan`` of each engine's first trial."""
    found: dict[int, str] = {}
    for index, trial in enumerate(plan):
        if trial.engine not in found.values():
            found[index] = trial.engine
    return found


def take_pictures(sim: Client, trial: TrialConfig, folder: Path,
                  animation: Animation | None) -> dict[str, str]:
    """The finished trial's picture (and its replay's animation): file names by what they
    show, or why there is none (an engine that cannot render leaves the bench going)."""
    taken: dict[str, str] = {}
    board, replay = f"{trial.engine}: the board after its first trial", (
        f"{trial.engine}: its first trial, replayed")
    try:
        taken[board] = render_board(sim, trial.board,
                                    folder / f"board_{trial.engine}.png").name
        if animation is not None:
            taken[replay] = animate_trial(
                sim, trial, folder / f"board_{trial.engine}_trial.png", animation).name
    except GaltonError as error:
        taken.setdefault(board, f"no picture ({error})")
    return taken
