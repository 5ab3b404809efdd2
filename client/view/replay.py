"""A recorded trial replayed in the page (``galton-client view FILE`` or ``view DIR``): the
same drawing as the live view, a time slider, play/pause and a choice of recording."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
import viser

from galton.client.sdk.recording import Recording, recordings_in
from galton.client.view.scene import WorldDrawing, framing

FRAME_PERIOD_S = 1 / 30
HIDDEN_Z = -1e3  # an entity absent from a sample (not yet released) is drawn out of sight


def visible_poses(poses: np.ndarray) -> np.ndarray:
    """A sample's poses with absent entities (NaN) moved out of sight."""
    shown = poses.copy()
    absent = np.isnan(shown).any(axis=1)
    shown[absent] = [0.0, 0.0, HIDDEN_Z, 0.0, 0.0, 0.0, 1.0]
    return shown


class ReplayView:
    """The replay page; ``run`` plays until ``stop`` is set."""

    def __init__(self, paths: list[Path], server: viser.ViserServer,
                 camera: tuple[np.ndarray, np.ndarray] | None) -> None:
        self.paths = {path.name: path for path in paths}
        self.server = server
        self.camera = camera
        self.drawing = WorldDrawing(server.scene, "/replay")
        server.scene.set_up_direction("+z")
        server.scene.add_grid("/grid", width=10, height=10, plane="xy", position=(0, 0, -0.01))
        gui = server.gui
        gui.configure_theme(dark_mode=False, control_width="medium")
        self.choice = gui.add_dropdown("Recording", tuple(self.paths))
        self.clock = gui.add_markdown("")
        self.playing = gui.add_checkbox("Playing", True)
        self.speed = gui.add_slider("Speed", min=0.05, max=4.0, step=0.05, initial_value=1.0)
        self.frame = gui.add_slider("Frame", min=0, max=1, step=1, initial_value=0)
        self.recording = self._load(self.choice.value)
        self.choice.on_update(lambda _event: self._switch())

    @classmethod
    def open(cls, source: Path, server: viser.ViserServer,
             camera: tuple[np.ndarray, np.ndarray] | None) -> ReplayView:
        return cls(recordings_in(source), server, camera)

    def _load(self, name: str) -> Recording:
        recording = Recording.load(self.paths[name])
        self.frame.max = max(len(recording.times) - 1, 1)
        self.frame.value = 0  # type: ignore[misc]  # viser's handles take assignments
        first = visible_poses(recording.poses[0]) if len(recording.times) else np.zeros((0, 7))
        self.drawing.rebuild(recording.infos, recording.names, first, recording.shapes)
        framed = self.camera or framing(recording.infos, recording.names,
                                        np.nan_to_num(recording.poses[-1]))
        if framed is not None:
            self.server.initial_camera.position = np.asarray(framed[0], dtype=float)
            self.server.initial_camera.look_at = np.asarray(framed[1], dtype=float)
        return recording

    def _switch(self) -> None:
        self.recording = self._load(self.choice.value)

    def run(self, stop: threading.Event) -> None:
        sim_clock = 0.0
        last = time.monotonic()
        while not stop.wait(FRAME_PERIOD_S):
            now = time.monotonic()
            recording, times = self.recording, self.recording.times
            if not len(times):
                continue
            index = int(self.frame.value)
            if self.playing.value:
                sim_clock = max(sim_clock, float(times[index])) + (now - last) * self.speed.value
                index = int(np.searchsorted(times, sim_clock, side="right")) - 1
                if index >= len(times) - 1:
                    index, sim_clock = 0, float(times[0])  # loop
                self.frame.value = max(index, 0)  # type: ignore[misc]
            else:
                sim_clock = float(times[index])
            last = now
            self.drawing.update(visible_poses(recording.poses[max(index, 0)]))
            self.clock.content = (f"replay **{self.choice.value}**  \n"
                                  f"sim time **{times[max(index, 0)]:.3f} s**  "
                                  f"frame {index} of {len(times) - 1}")
