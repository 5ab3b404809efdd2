"""Learning from surprise: a box's friction changes in reality, the model notices (its
anomaly score stays high), recalibrates from what it saw, and agrees with reality again.

Two worlds in one daemon: the live world is the robot's internal model; a fork of it,
"reality", plays the real world. Each episode a hand pushes a box across a table at
1.5 m/s in both; every 50 ms a camera sees reality's box (seeded noise of 1 mm a side) and
the model compares it with its own box (compare's ``trigger``: the daemon counts the
surprising comparisons in a row; a SurpriseWatch keeps the episode's observations, what a
calibration fits to). In episode 1 both agree. Before episode 2 reality's table is
polished: the box's friction falls from 0.8 to 0.3 and it slides further than the model
expects. The score stays above 3 for 4 cycles in a row: the daemon suggests a calibration
(the reply's ``suggested``, and a ``calibration_suggested`` event for any other listener),
the model calibrates the box's friction on the episode it saw (``calibrate`` with
``apply``), and in episode 3 its scores are low again.

With --auto the daemon closes the loop itself: the trigger carries the fit
(``trigger``'s ``calibrate``: the box's friction, its bounds, ``apply``), so the comparison
that makes the streak 8 long (enough of the slide to fit) starts the calibration in the
daemon, over the streak's own observations (no SurpriseWatch), with the tracker's
velocities given to compare (the start's twists); the example waits for its
``calibration_finished`` event (the fitted friction, already applied) before stepping on.
Fitted on 8 samples of the slide rather than the whole episode (with up to 200
predictions), the friction comes within a few per cent, and episode 3's scores are low
again.

Starts its own daemon unless --connect is given:
python examples/learn_from_surprise.py [--engine mujoco|pybullet] [--seed N] [--auto]
                                       [--connect ENDPOINT --instance NAME]
"""

from __future__ import annotations

import argparse
import sys
import threading
from dataclasses import dataclass
from typing import Any

import numpy as np

from galton.client import Client, EmbeddedDaemon, SurpriseWatch, boxes, plane

CYCLE_S = 0.05
CYCLES = 12  # an episode: 0.6 s, the box at rest before its end
MODEL_FRICTION, REAL_FRICTION = 0.8, 0.3
NOISE_M = 0.001
SIGMA_M = 0.005
THRESHOLD, WINDOW = 3.0, 4
# --auto fits the streak's own observations, so it waits for a longer streak: 8 samples,
# 0.35 s of the slide (4 were too few to pin the start's speed from noisy positions).
AUTO_WINDOW = 8
AUTO_PREDICTIONS = 200  # fewer samples: a longer search to pin the friction as closely
FIT = {"box.friction": (0.1, 1.0)}
MAX_PREDICTIONS = 100
PUSH = np.array([[1.5, 0.0, 0.0, 0.0, 0.0, 0.0]])  # the hand's push, m/s
# The table's surface, per engine, that lets the box's own friction decide their contact
# (docs/PHYSICS.md, "Calibration"): a heavy moving slab.
TABLE = {"mujoco": (0.0, 0.0), "pybullet": (1.0, 0.0)}


@dataclass(frozen=True)
class LearningRun:
    """Each episode's highest anomaly score, and what calibration fitted."""

    peaks: list[float]
    fitted: float
    predictions: int


def scene(sim: Client, engine: str) -> np.ndarray:
    """A table (a heavy slab) and a box resting on it; the box's start pose."""
    friction, restitution = TABLE[engine]
    sim.reset("all")
    sim.spawn(plane())
    sim.spawn(boxes(["table"], [[0.5, 0.0, 0.05]], [1.5, 0.6, 0.05], mass=500.0,
                    friction=friction, restitution=restitution))
    sim.spawn(boxes(["box"], [[0.0, 0.0, 0.15]], [0.05, 0.05, 0.05], mass=1.0,
                    friction=MODEL_FRICTION))
    sim.step(round(0.3 / sim.status().timestep))  # settled
    return sim.get_states(["box"]).poses


class Calibrations:
    """The daemon's calibrations, as its events tell of them (--auto)."""

    def __init__(self) -> None:
        self.finished: list[dict[str, Any]] = []
        self.arrived = threading.Event()

    def on_event(self, event: dict[str, Any]) -> None:
        if event.get("kind") == "calibration_finished":
            self.finished.append(event)
            self.arrived.set()

    def wait(self) -> dict[str, Any]:
        """The calibration the daemon started: its result (an error ends the example)."""
        if not self.arrived.wait(120):
            raise TimeoutError("the daemon's calibration did not finish within 120 s")
        self.arrived.clear()
        done = self.finished[-1]
        if "error" in done:
            raise RuntimeError(f"the daemon's calibration failed: {done['message']}")
        return done


def episode(sim: Client, reality: Client, start: np.ndarray, watch: SurpriseWatch,
            rng: np.random.Generator, auto: Calibrations | None = None) -> tuple[float, bool]:
    """Push the box in both worlds and watch; the peak score, and whether surprised.
    With ``auto``, the trigger starts the daemon's calibration, waited for here."""
    for world in (sim, reality):
        world.set_states(["box"], start, PUSH)
    watch.start(sim.status().sim_time, ["box"], start)
    steps = round(CYCLE_S / sim.status().timestep)
    fit = None if auto is None else {"fit": FIT, "apply": True,
                                     "max_predictions": AUTO_PREDICTIONS}
    peak, surprised = 0.0, False
    for _ in range(CYCLES):
        sim.step(steps)
        reality.step(steps)
        states = reality.get_states(["box"])
        seen = states.poses.copy()
        seen[:, :2] += rng.normal(0.0, NOISE_M, (1, 2))
        # --auto: a tracker's velocities too, the start the daemon's fit takes (estimated
        # from three noisy positions 50 ms apart, the start's speed is a few cm/s off)
        speeds = None if auto is None else states.twists
        found = sim.compare(["box"], seen, speeds, sigma_position=SIGMA_M,
                            trigger=(THRESHOLD, WINDOW if auto is None else AUTO_WINDOW),
                            calibrate=fit)
        peak = max(peak, found.score)
        watch.observe(found.sim_time, seen, found.score)
        surprised = found.suggested or surprised
        if auto is not None and found.calibrating:
            auto.wait()  # the daemon steps no live world while it calibrates
    return peak, surprised


def learn(sim: Client, engine: str, seed: int, auto: bool = False) -> LearningRun:
    rng = np.random.default_rng(seed)
    start = scene(sim, engine)
    sim.fork_world("reality")
    reality = sim.world("reality")
    watch = SurpriseWatch(THRESHOLD, WINDOW)
    calibrations = Calibrations() if auto else None
    peaks, fitted, predictions = [], MODEL_FRICTION, 0
    try:
        with sim.on_event(calibrations.on_event if calibrations else lambda event: None):
            for number in range(3):
                if number == 1:
                    reality.update(["box"], friction=REAL_FRICTION)  # the table is polished
                peak, surprised = episode(sim, reality, start, watch, rng, calibrations)
                peaks.append(peak)
                if surprised and calibrations is not None:
                    done = calibrations.finished[-1]
                    fitted, predictions = done["fitted"]["box.friction"], done["predictions"]
                elif surprised:
                    names, times, poses = watch.observed()
                    fit = sim.calibrate(FIT, names, times, poses, twists=PUSH, apply=True,
                                        max_predictions=MAX_PREDICTIONS, seed=seed)
                    fitted, predictions = fit.fitted["box.friction"], fit.predictions
    finally:
        sim.delete_world("reality")
    who = "the daemon" if auto else "the model"
    print(f"{sim.status().engine}: peak anomaly score per episode "
          f"{', '.join(f'{p:.1f}' for p in peaks)}; friction fitted by {who} {fitted:.3f} "
          f"(reality {REAL_FRICTION}) in {predictions} predictions")
    return LearningRun(peaks, fitted, predictions)


def main(argv: list[str]) -> LearningRun:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco", choices=tuple(TABLE))
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--connect", help="a running daemon's endpoint")
    parser.add_argument("--instance", default="galton")
    parser.add_argument("--auto", action="store_true",
                        help="the daemon starts the calibration itself (trigger's calibrate)")
    args = parser.parse_args(argv)
    if args.connect:
        with Client(args.instance, args.connect, timeout=60.0) as sim:
            return learn(sim, sim.status().engine, args.seed, args.auto)
    with EmbeddedDaemon(args.engine) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=60.0) as sim:
        return learn(sim, args.engine, args.seed, args.auto)


if __name__ == "__main__":
    main(sys.argv[1:])
