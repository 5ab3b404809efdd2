"""Worlds and reads shared by the PyBullet snapshot and clone tests: piles, the KUKA's text,
an MJCF trio, and runs read as raw bytes to compare bit for bit."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from galton.daemon.engines.pybullet.engine import PybulletEngine
from galton.protocol import BodyGroup
from support.models import ROBOTS

SEED = 25
Run = list[bytes]  # every state read along a run, as raw bytes (exact, -0.0 and NaN too)


def poses_at(positions: Any, angles: Any = None) -> np.ndarray:
    """Poses at these positions, turned about x by ``angles`` (radians) when given."""
    positions = np.atleast_2d(np.asarray(positions, dtype=float))
    poses = np.zeros((len(positions), 7))
    poses[:, :3], poses[:, 6] = positions, 1.0
    if angles is not None:
        poses[:, 3], poses[:, 6] = np.sin(np.divide(angles, 2)), np.cos(np.divide(angles, 2))
    return poses


def pile(rng: np.random.Generator, prefix: str = "", count: int = 12) -> list[BodyGroup]:
    """A plane and a heap of spheres and turned boxes dropped close together, so that they
    land in one another and keep many contacts."""
    spots = rng.uniform([-0.15, -0.15, 0.05], [0.15, 0.15, 0.5], (2 * count, 3))
    return [BodyGroup("plane", (2.0, 2.0), [prefix + "ground"], poses_at([0, 0, 0]),
                      static=True),
            BodyGroup("sphere", (0.04,), [f"{prefix}s{i}" for i in range(count)],
                      poses_at(spots[:count])),
            BodyGroup("box", (0.05, 0.03, 0.02), [f"{prefix}b{i}" for i in range(count)],
                      poses_at(spots[count:], rng.uniform(0, np.pi, count)), mass=0.2,
                      friction=0.8)]


def kuka_text() -> str:
    """The KUKA iiwa's URDF with its mesh paths absolute (model_files.py's job)."""
    folder = ROBOTS["kuka"].parent
    return ROBOTS["kuka"].read_text(encoding="utf-8").replace('filename="', f'filename="{folder}/')


def names_of(engine: PybulletEngine) -> list[str]:
    return list(engine.bodies) + list(engine.robots.links)


def record(engine: PybulletEngine, names: list[str], steps: int, every: int = 25,
           between: Callable[[PybulletEngine, int], None] | None = None) -> Run:
    """Step ``steps`` in batches of ``every``, reading every state (and joint state) after
    each batch; ``between`` makes the same requests on any engine between batches."""
    joints = [j.name for j in engine.joints() if j.type in ("revolute", "prismatic")]
    out: Run = []
    for k in range(steps // every):
        if between is not None:
            between(engine, k)
        engine.step(every)
        out.extend(array.tobytes() for array in engine.get_states(names))
        if joints:
            out.extend(array.tobytes() for array in engine.get_joint_states(joints))
    return out


def now(engine: PybulletEngine, names: list[str]) -> Run:
    """Every state, joint state (with the last step's efforts) and property, read now."""
    joints = [j.name for j in engine.joints() if j.type in ("revolute", "prismatic")]
    arrays = [*engine.get_states(names), engine.properties(names)]
    if joints:
        arrays.extend(engine.get_joint_states(joints))
    return [array.tobytes() for array in arrays]


def restored(make: Callable[[], PybulletEngine], data: dict[str, Any]) -> PybulletEngine:
    engine = make()
    engine.restore(data)
    return engine


def assert_same_run(a: Run, b: Run) -> None:
    assert len(a) == len(b)
    first = next((k for k, (x, y) in enumerate(zip(a, b, strict=True)) if x != y), None)
    assert first is None, f"the runs part at read {first} of {len(a)}"



MJCF = """<mujoco model="trio">
  <worldbody>
    <geom type="plane" size="5 5 0.1"/>
    <body name="ball" pos="0 0 0.3"><joint type="free"/><geom type="sphere" size="0.1"/></body>
    <body name="cube" pos="0.05 0 0.6"><joint type="free"/><geom type="box" size=".1 .1 .1"/>
    </body>
    <body name="stick" pos="0 0.1 0.9"><joint type="free"/>
      <geom type="capsule" size="0.03 0.1"/></body>
  </worldbody>
</mujoco>"""
