"""The live page: the daemon's world as its state stream draws it, side worlds as ghosts,
the clock, the anomaly score of ``compare`` as a running chart, contacts on demand, and
play/pause/step/reset for an operator (a viewer's page has none).

Opening the page changes nothing: the view reads (``stream_states``, ``list``,
``list_worlds``, ``contacts``) and acts only when an operator presses a button.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np
import viser
import viser.uplot

from galton.client.sdk.client import Client
from galton.client.sdk.drawn_shapes import shapes_for_drawing
from galton.client.sdk.streams import StateSample, StateStream
from galton.client.view.drawing import WorldDrawing, framing
from galton.protocol import AccessDeniedError, GaltonError, RequestTimeoutError

log = logging.getLogger("galton.client")

GHOST_OPACITY = 0.5
GHOST_TINT = (255, 150, 0)  # what the model expects: orange beside the real red
PREDICT_TINT = (160, 80, 255)
FUTURES = 8  # the operator's "Imagine" button: futures of 1 s, sampled every 50 ms,
FUTURE_EVERY_S = 0.05
FUTURE_SIGMA_M = 0.002  # from positions perturbed by this much
FUTURE_TINT = (205, 180, 255)  # faint: the prediction's tint, washed out
WORLDS_PERIOD_S = 1.0  # side worlds are looked for this often
CONTACTS_PERIOD_S = 0.25
SCORE_HISTORY = 300  # points of the anomaly chart
PROBE_TIMEOUT_S = 2.0
STEP_COUNT = 100


class Latest:
    """The newest sample of one stream, handed from the transport's thread to the page's."""

    def __init__(self, wake: threading.Event) -> None:
        self.sample: StateSample | None = None
        self.wake = wake

    def put(self, sample: StateSample) -> None:
        self.sample = sample
        self.wake.set()

    def take(self) -> StateSample | None:
        sample, self.sample = self.sample, None
        return sample


def may_operate(client: Client) -> bool:
    """Whether this client's role may change the world, asked without changing anything:
    ``release_control`` when nobody holds control is no change, a holder's refusal
    (CONTROL_HELD) says the role may, and a viewer gets ACCESS_DENIED (or, over Zenoh's
    access control, no answer)."""
    try:
        client.request("release_control", timeout=PROBE_TIMEOUT_S).raise_for_code()
    except (AccessDeniedError, RequestTimeoutError):
        return False
    except GaltonError:
        return True
    return True


class Followed:
    """One world followed by a stream and drawn by a WorldDrawing."""

    def __init__(self, client: Client, drawing: WorldDrawing, rate: float,
                 wake: threading.Event) -> None:
        self.client = client
        self.drawing = drawing
        self.latest = Latest(wake)
        self.stream: StateStream = client.stream_states(rate=rate, callback=self.latest.put)
        self.stale = True  # the scene must be listed again before the next draw

    def draw(self) -> StateSample | None:
        """Draw the newest sample, if any; the scene is listed again when its names change."""
        sample = self.latest.take()
        if sample is None:
            return None
        if sample.ended is not None:
            return sample
        if self.stale or sample.names != self.drawing.names:
            infos = self.client.list()
            self.drawing.rebuild(infos, sample.names, sample.poses,
                                 shapes_for_drawing(self.client, infos))
            self.stale = False
        else:
            self.drawing.update(sample.poses)
        return sample

    def close(self) -> None:
        self.stream.close()
        self.drawing.clear()


class LiveView:
    """The page of one daemon; ``run`` serves it until ``stop`` is set."""

    def __init__(self, client: Client, server: viser.ViserServer, rate: float = 20.0,
                 operator: bool | None = None, camera: tuple[np.ndarray, np.ndarray] | None
                 = None) -> None:
        self.client = client
        self.server = server
        self.rate = rate
        self.camera = camera
        self.wake = threading.Event()
        self.operator = may_operate(client) if operator is None else operator
        server.scene.set_up_direction("+z")
        server.scene.add_grid("/grid", width=10, height=10, plane="xy", position=(0, 0, -0.01))
        self.live = Followed(client, WorldDrawing(server.scene, "/live"), rate, self.wake)
        self.ghosts: dict[str, Followed] = {}
        self.prediction = WorldDrawing(server.scene, "/predict", GHOST_OPACITY, PREDICT_TINT,
                                       moving_only=True)
        self.scores: deque[tuple[float, float]] = deque(maxlen=SCORE_HISTORY)
        self.scores_seen = 0
        self.future_segments = 0  # trails drawn by the last "Imagine"
        self._framed = False
        self._build_gui()
        self.events = client.on_event(self._on_event)

    # -- the page ---------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.server.gui
        gui.configure_theme(dark_mode=False, control_width="medium")
        self.clock = gui.add_markdown("**waiting for the first sample**")
        self.message = gui.add_markdown("")
        if self.operator:
            with gui.add_folder("Operator"):
                for label, action in (("Play", self._play), ("Pause", self._pause),
                                      (f"Step {STEP_COUNT}", self._step),
                                      ("Reset", self._reset), ("Predict 1 s", self._predict),
                                      (f"Imagine {FUTURES} futures", self._imagine)):
                    gui.add_button(label).on_click(self._on_click(action))
        with gui.add_folder("Show"):
            self.show_ghosts = gui.add_checkbox("Side worlds (ghosts)", True)
            self.show_contacts = gui.add_checkbox("Contacts", False)
        self.chart = gui.add_uplot(
            (np.zeros(0), np.zeros(0)),
            (viser.uplot.Series(label="sim time (s)"),
             viser.uplot.Series(label="anomaly score", stroke="red", width=2)),
            title="compare: anomaly score", aspect=2.0)

    def _on_click(self, action: Callable[[], None]) -> Callable[[Any], None]:
        return lambda _event: self._act(action)

    def _act(self, action: Callable[[], None]) -> None:
        """Run an operator's action; a refusal is shown on the page, not raised."""
        try:
            action()
            self.message.content = ""
        except GaltonError as error:
            self.message.content = f"**refused**: {error}"

    def _play(self) -> None:
        self.client.play()

    def _pause(self) -> None:
        self.client.pause()

    def _step(self) -> None:
        self.client.step(STEP_COUNT)

    def _reset(self) -> None:
        self.client.reset("state")

    def _predict(self) -> None:
        """Where the bodies will be in one second, drawn as a ghost over the live world."""
        names = list(self.live.drawing.names)
        if not names:
            return
        prediction = self.client.predict(1.0, read=names)
        poses = np.asarray(prediction.poses)[-1]
        infos = self.client.list()
        self.prediction.rebuild(infos, names, poses.reshape(-1, 7),
                                shapes_for_drawing(self.client, infos))

    def _imagine(self) -> None:
        """FUTURES futures of one second, each from positions perturbed by a few mm, drawn
        as faint trails: where the bodies may go, and how far apart."""
        names = list(self.live.drawing.names)
        if not names:
            return
        found = self.client.predict(1.0, every=FUTURE_EVERY_S, read=names, futures=FUTURES,
                                    perturb={"position": FUTURE_SIGMA_M})
        paths = np.asarray(found.poses)[..., :3]  # (futures, samples, bodies, 3)
        starts, ends = paths[:, :-1], paths[:, 1:]
        segments = np.stack([starts, ends], axis=-2).reshape(-1, 2, 3)
        self.future_segments = len(segments)
        self.server.scene.add_line_segments("/futures", segments, FUTURE_TINT,
                                            thickness=2.0, thickness_units="screen")

    def _on_event(self, event: dict[str, Any]) -> None:
        """A scene change makes the drawing list the scene again; a comparison's score
        goes on the chart."""
        if event.get("kind") == "scene":
            world = event.get("world")
            for followed in (self.live, *self.ghosts.values()):
                if world in (None, followed.stream.world):
                    followed.stale = True
            if event.get("op") == "compare" and "score" in event:
                self.scores.append((float(event.get("sim_time", time.monotonic())),
                                    float(event["score"])))
                self.scores_seen += 1
                self.wake.set()

    # -- the loop ---------------------------------------------------------------------
    def run(self, stop: threading.Event) -> None:
        next_worlds = next_contacts = 0.0
        drawn_scores = 0
        while not stop.is_set():
            self.wake.wait(0.5)
            self.wake.clear()
            now = time.monotonic()
            with self.server.atomic():
                self._draw_live()
                for ghost in self.ghosts.values():
                    if self.show_ghosts.value:
                        ghost.draw()
                    elif ghost.drawing.names:
                        ghost.drawing.clear()
                        ghost.stale = True
            if now >= next_worlds:
                next_worlds = now + WORLDS_PERIOD_S
                self._follow_side_worlds()
            if now >= next_contacts and self.show_contacts.value:
                next_contacts = now + CONTACTS_PERIOD_S
                self._draw_contacts()
            elif not self.show_contacts.value:
                self.server.scene.remove_by_name("/contacts")
            if self.scores_seen != drawn_scores:
                drawn_scores = self.scores_seen
                self._draw_scores()

    def _draw_live(self) -> None:
        sample = self.live.draw()
        if sample is None:
            return
        if not self._framed:
            self._frame(sample)
        self.clock.content = (
            f"**{sample.state}**  world `{sample.world}`  \n"
            f"sim time **{sample.sim_time:.3f} s**  step {sample.step}  \n"
            f"RTF **{sample.rtf:.3f}**  bodies {len(sample.names)}  \n"
            f"role: {'operator' if self.operator else 'viewer (read only)'}")

    def _frame(self, sample: StateSample) -> None:
        """Point the camera at the bodies once there are some (or where --camera says)."""
        framed = self.camera or framing(self.live.drawing.infos, sample.names, sample.poses)
        if framed is None:
            return
        position, look_at = (np.asarray(point, dtype=float) for point in framed)
        self.server.initial_camera.position = position
        self.server.initial_camera.look_at = look_at
        for connected in self.server.get_clients().values():
            connected.camera.position = position
            connected.camera.look_at = look_at
        self._framed = True

    def _follow_side_worlds(self) -> None:
        """A ghost for every side world (a fork: what the model expects beside what is)."""
        try:
            names = {w.name for w in self.client.list_worlds()[1:]}
        except GaltonError as error:
            log.warning("could not list the worlds: %s", error)
            return
        for gone in set(self.ghosts) - names:
            self.ghosts.pop(gone).close()
        for name in names - set(self.ghosts):
            try:
                self.ghosts[name] = Followed(
                    self.client.world(name),
                    WorldDrawing(self.server.scene, f"/ghosts/{name}", GHOST_OPACITY,
                                 GHOST_TINT, moving_only=True), self.rate, self.wake)
            except GaltonError as error:  # deleted meanwhile
                log.info("no ghost for world %s: %s", name, error)

    def _draw_contacts(self) -> None:
        try:
            found = self.client.contacts()
        except GaltonError:
            return
        points = np.asarray(found.positions, dtype=np.float32).reshape(-1, 3)
        self.server.scene.add_point_cloud("/contacts", points, colors=(255, 40, 200),
                                          point_size=0.02)

    def _draw_scores(self) -> None:
        if not self.scores:
            return
        times, scores = zip(*self.scores, strict=True)
        self.chart.data = (np.asarray(times), np.asarray(scores))

    def close(self) -> None:
        self.events.close()
        for ghost in self.ghosts.values():
            ghost.close()
        self.live.close()
