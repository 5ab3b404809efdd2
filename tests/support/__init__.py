"""Helpers for tests: building bodies, snapshotting a daemon's scene, laws of known effect."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from galton.analysis import stats
from galton.client import Client, plane, spheres

BALL_RADIUS = 0.05


def ball_row(count: int, prefix: str = "ball", z: float = 1.0, **options: object) -> tuple:
    """``count`` spheres in a row along x, 0.2 m apart, at height z."""
    names = [f"{prefix}_{i}" for i in range(count)]
    positions = np.column_stack([np.arange(count) * 0.2, np.zeros(count), np.full(count, z)])
    return names, spheres(names, positions, BALL_RADIUS, **options)


@dataclass
class Snapshot:
    """Everything a rejected request must leave as it was."""

    entities: list
    poses: np.ndarray
    twists: np.ndarray
    step: int
    state: str

    def assert_same(self, other: Snapshot) -> None:
        assert self.entities == other.entities
        assert np.array_equal(self.poses, other.poses)
        assert np.array_equal(self.twists, other.twists)
        assert (self.step, self.state) == (other.step, other.state)


def snapshot(sim: Client) -> Snapshot:
    entities = sorted(sim.list(), key=lambda e: e.name)
    states = sim.get_states()
    status = sim.status()
    return Snapshot(entities, states.poses, states.twists, status.step, status.state)


def ground_and_balls(sim: Client, count: int = 3) -> list[str]:
    sim.spawn(plane())
    names, group = ball_row(count)
    sim.spawn(group)
    return names


def tilted_law(w: float) -> np.ndarray:
    """Binomial(11, 1/2) moved towards the tails (w > 0) or the centre (w < 0) until its
    Cohen's w is exactly ``abs(w)``."""
    p = stats.bin_probabilities()
    direction = (np.arange(12) - 5.5) ** 2 - np.sum(p * (np.arange(12) - 5.5) ** 2)
    direction = direction * p  # sums to 0: the law stays a law
    return p + w * direction / np.sqrt(np.sum(direction**2 / p))


def companion(sim: Client, timeout: float = 10.0) -> Client:
    """A second client of the same daemon over the same transport (a Zenoh client shares
    the session; a ZeroMQ one opens its own connection)."""
    if sim.transport.kind == "zmq":
        return Client(sim.instance, f"zmq+{sim.transport.endpoint}", timeout=timeout)  # type: ignore[attr-defined]
    return Client(sim.instance, session=sim.session, timeout=timeout)


def raw_replies(sim: Client, op: str, payload: bytes, timeout: float = 10.0) -> list[bytes]:
    """Every reply to a request sent as these exact bytes, over the client's transport."""
    return sim.transport.send_raw(op, payload, timeout)


# A state within the world's limits whose next steps carry it beyond them (9e4 m/s at a
# metre short of the 1e6 m edge): how a client makes a world diverge, now that a state
# beyond the limits is refused where it is set (issue 35).
EDGE_POSE = np.array([[999_999.0, 0, 0.5, 0, 0, 0, 1]])
EDGE_TWIST = np.array([[9e4, 0, 0, 0, 0, 0]])


def send_over_the_edge(sim: Client, name: str = "ball") -> None:
    """Set ``name`` where its next step takes the world past its limits."""
    sim.set_states([name], poses=EDGE_POSE, twists=EDGE_TWIST)
