"""The one seam through which calibrate evaluates its candidates: each candidate is a set
of parameter values; its error is how far a prediction from the start, with those values,
lands from what was observed. Today each candidate runs on its own copy of the start
world (``clone_of``), one after another on the physics thread; the live world is never
touched. The imagination issue's many-futures ``predict`` can take this function's place
(one batch of futures per generation) without calibrate changing."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from galton.daemon.core.fit_params import Parameter, apply_values
from galton.daemon.core.limits import Limits
from galton.daemon.world.scene import World
from galton.daemon.world.snapshot import clone_of
from galton.protocol import PhysicsError


@dataclass(frozen=True)
class Observation:
    """Where the observed bodies were seen: ``steps`` after the start (increasing, > 0) and
    their positions then, (samples, bodies, 3), NaN where a body was not seen."""

    names: list[str]
    steps: np.ndarray
    positions: np.ndarray

    @property
    def horizon(self) -> int:
        return int(self.steps[-1]) if len(self.steps) else 0


def evaluate_candidates(start: World, params: Sequence[Parameter],
                        candidates: Sequence[Mapping[str, float]], observation: Observation,
                        limits: Limits) -> np.ndarray:
    """Each candidate's position error (m): the mean distance, over the observed bodies and
    samples, between where a prediction from ``start`` with the candidate's values puts
    each body and where it was seen. ``start`` itself is left as it was."""
    return np.array([_error(start, params, values, observation, limits)
                     for values in candidates])


def _error(start: World, params: Sequence[Parameter], values: Mapping[str, float],
           observation: Observation, limits: Limits) -> float:
    copy = clone_of(start, f"{start.name}:candidate", limits)
    try:
        apply_values(copy, params, values)
        predicted = predicted_positions(copy, observation)
    except PhysicsError:  # a candidate whose world diverges is as wrong as can be
        return math.inf
    finally:
        copy.engine.close()
    return position_error(predicted, observation.positions)


def predicted_positions(world: World, observation: Observation) -> np.ndarray:
    """The observed bodies' positions at each observed step, stepping ``world`` there."""
    rows = np.empty(observation.positions.shape)
    done = 0
    for index, step in enumerate(observation.steps):
        if step > done:
            world.step(int(step) - done)
            done = int(step)
        world.verify()
        rows[index] = world.get_states(observation.names)[0][:, :3]
    return rows


def position_error(predicted: np.ndarray, observed: np.ndarray) -> float:
    """The mean distance over the (sample, body) pairs that were seen."""
    distances = np.linalg.norm(predicted - observed, axis=-1)
    seen = np.isfinite(distances)
    return float(distances[seen].mean()) if seen.any() else 0.0
