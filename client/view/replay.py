"""A recorded trial replayed in the page (``galton-client view FILE`` or ``view DIR``): the
same drawing as the live view, a time slider, play/pause and a choice of recording."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
import viser

from galton.client.sdk.recording import Recording, recordings_in
from galton.client.view.drawing import WorldDrawing, framing

FRAME_PERIOD_S = 1 / 30
TIME_STEP_S = 0.001  # the time slider's resolution (sim time)
HIDDEN_Z = -1e3  # an entity absent from a sample (not yet released) is drawn out of sight


def visible_poses(poses: np.ndarray) -> np.ndarray:
    """A sample's poses with absent entities (NaN) moved out of sight."""
    shown = poses.copy()
    absent = np.isnan(shown).any(axis=1)
    shown[absent] = [0.0, 0.0, HIDDEN_Z, 0.0, 0.0, 0.0, 1.0]
    return shown


class ReplayView:
    """The replay page; ``run`` plays until ``stop`` is set. Its panel: the recording, the
    clock, Play and Pause, the speed and a time slider (seconds of sim time) to seek."""

    def __init__(self, paths: list[Path], server: viser.ViserServer,
                 camera: tuple[np.ndarray, np.ndarray] | None) -> None:
        self.paths = {path.name: path for path in paths}
        self.server = server
        self.camera = camera
        gui = server.gui  # the panel first: a page that connects gets it before the scene
        gui.configure_theme(dark_mode=False, control_width="medium")
        self.choice = gui.add_dropdown("Recording", tuple(self.paths))
        self.clock = gui.add_markdown("")
        self.playing = True
        self.drew = threading.Event()  # set at each new drawing (a test waits on it)
        gui.add_button("Play").on_click(lambda _event: self.play(True))
        gui.add_button("Pause").on_click(lambda _event: self.play(False))
        self.speed = gui.add_slider("Speed", min=0.05, max=4.0, step=0.05, initial_value=1.0)
        self.time = gui.add_slider("Time (s)", min=0.0, max=1.0, step=TIME_STEP_S,
                                   initial_value=0.0)
        self.drawing = WorldDrawing(server.scene, "/replay")
        server.scene.set_up_direction("+z")
        server.scene.add_grid("/grid", width=10, height=10, plane="xy", position=(0, 0, -0.01))
        self.recording = self._load(self.choice.value)
        self.choice.on_update(lambda _event: self._switch())

    @classmethod
    def open(cls, source: Path, server: viser.ViserServer,
             camera: tuple[np.ndarray, np.ndarray] | None) -> ReplayView:
        return cls(recordings_in(source), server, camera)

    def play(self, playing: bool) -> None:
        """Play or pause (the buttons); paused, the time slider alone moves the replay."""
        self.playing = playing

    def _load(self, name: str) -> Recording:
        recording = Recording.load(self.paths[name])
        times = recording.times
        self.time.min = float(times[0]) if len(times) else 0.0
        self.time.max = max(float(times[-1]) if len(times) else 0.0,
                            self.time.min + TIME_STEP_S)
        self.time.value = self.time.min  # type: ignore[misc]  # viser's handles take assignments
        first = visible_poses(recording.poses[0]) if len(times) else np.zeros((0, 7))
        self.drawing.rebuild(recording.infos, recording.names, first, recording.shapes)
        framed = self.camera or framing(recording.infos, recording.names,
                                        np.nan_to_num(recording.poses[-1]))
        if framed is not None:
            self.server.initial_camera.position = np.asarray(framed[0], dtype=float)
            self.server.initial_camera.look_at = np.asarray(framed[1], dtype=float)
        return recording

    def _switch(self) -> None:
        self.recording = self._load(self.choice.value)

    def frame_at(self, sim_time: float) -> int:
        """The index of the last sample at or before ``sim_time``."""
        found = int(np.searchsorted(self.recording.times, sim_time, side="right")) - 1
        return min(max(found, 0), len(self.recording.times) - 1)

    def run(self, stop: threading.Event) -> None:
        last = time.monotonic()
        drawn: tuple[int, bool] | None = None
        while not stop.wait(FRAME_PERIOD_S):
            now = time.monotonic()
            recording, times = self.recording, self.recording.times
            if not len(times):
                continue
            sim_clock = float(self.time.value)
            if self.playing:
                sim_clock += (now - last) * self.speed.value
                if sim_clock > float(times[-1]):
                    sim_clock = float(times[0])  # loop
                self.time.value = sim_clock  # type: ignore[misc]
            last = now
            index = self.frame_at(sim_clock)
            if (index, self.playing) == drawn:
                continue  # nothing new to draw: the page stays quiet
            drawn = index, self.playing
            self.drawing.update(visible_poses(recording.poses[index]))
            self.clock.content = (f"replay **{self.choice.value}**  \n"
                                  f"sim time **{times[index]:.3f} s**  "
                                  f"frame {index} of {len(times) - 1}  \n"
                                  f"{'playing' if self.playing else 'paused'}")
            self.drew.set()
