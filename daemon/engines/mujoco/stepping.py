"""The MuJoCo engine's time, as functions of the engine: ``step`` with its periodic looks
(worker threads for a crowd, balls balanced on a crown), the divergence check and the
rewind (``reset_dynamics``).

The looks fall every ``LOOK_EVERY_STEPS`` steps of the world, counted across requests, so
they land on the same steps however the steps are split into requests (a step(1) loop or
one long run_until give the same trajectory).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from galton.daemon.engines.mujoco import mj_spec as ms
from galton.daemon.engines.mujoco import state as mst
from galton.protocol import OperationFailedError

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

# Steps of the world between two looks at the contact count and at balls asleep on a crown.
LOOK_EVERY_STEPS = 50
# Steps between two wake-ups of slow bodies that touch nothing: fewer than the slow steps
# MuJoCo counts before a tree sleeps (MIN_AWAKE), and a divisor of LOOK_EVERY_STEPS.
AWAKE_EVERY_STEPS = 5
# MuJoCo's d.tree_asleep: -(MIN_AWAKE + 1) for an awake tree moving fast, counting up by one
# per slow step to 0, when the tree sleeps (and its velocity is zeroed).
MIN_AWAKE = 10


def step(engine: MujocoEngine, count: int) -> None:
    """MuJoCo's own errors in a step (its arena overflowing) leave the data unusable:
    the world reads as diverged until cleared."""
    engine.warnings[ms.DIVERGENCE_WARNINGS] = 0
    engine.observed = None  # the step makes what is observed anew (observed)
    while count > 0:
        run = min(count, AWAKE_EVERY_STEPS - engine.steps_since_look % AWAKE_EVERY_STEPS)
        try:
            mujoco.mj_step(engine.model, engine.data, run)
        except mujoco.FatalError as exc:
            engine.broken = True
            raise OperationFailedError(f"MuJoCo failed in a step ({exc}); the world "
                                       "must be reset") from exc
        count -= run
        engine.steps_since_look += run
        if engine.steps_since_look % AWAKE_EVERY_STEPS == 0:
            keep_drifting_awake(engine.model, engine.data)
        if engine.steps_since_look == LOOK_EVERY_STEPS:
            engine.look()
    engine.diverged |= bool(engine.warnings[ms.DIVERGENCE_WARNINGS].any())


def keep_drifting_awake(m: mujoco.MjModel, d: mujoco.MjData) -> None:
    """Sleep only what is at rest: a slow tree that touches nothing (a ball coasting in
    free fall or zero gravity) starts its count of slow steps again, so MuJoCo never stops
    it. Only trees already counting are looked at, and only those that can collide (a
    parked body collides with nothing and may sleep); a tree in contact counts on, so
    piles sleep as before."""
    if not m.opt.enableflags & mujoco.mjtEnableBit.mjENBL_SLEEP:
        return
    counting = np.flatnonzero((d.tree_asleep < 0) & (d.tree_asleep >= -MIN_AWAKE))
    if not len(counting):
        return
    roots = m.tree_bodyadr[counting]
    counting = counting[(m.body_contype[roots] | m.body_conaffinity[roots]) != 0]
    touching = m.body_treeid[m.geom_bodyid[d.contact.geom[:d.ncon]]].ravel()
    drifting = counting[~np.isin(counting, touching)]
    d.tree_asleep[drifting] = -(MIN_AWAKE + 1)


def look(engine: MujocoEngine) -> None:
    """The periodic look: worker threads for a crowd, balls balanced on a crown. It
    costs about 40 µs, twice a small world's step, so never once per step."""
    engine.steps_since_look = 0
    engine.track_crowding()
    if engine.sleep_guard is not None:
        engine.sleep_guard.check(engine.model, engine.data, engine.writable_model)


def state_within(engine: MujocoEngine, max_position: float, max_speed: float) -> bool:
    """numpy over qpos, qvel and mocap (see state.within); MuJoCo's own warnings
    of a blow-up, or a world left half-changed by a failed delete, count as diverged."""
    if engine.diverged or engine.broken:
        return False
    return mst.within(engine.data, engine.index, engine.watched(), max_position, max_speed)


def reset_dynamics(engine: MujocoEngine) -> None:
    """Forget warm starts; also clear what a divergence left beyond the entities' roots."""
    m, d = engine.model, engine.data
    bad = ~np.isfinite(d.qpos)
    d.qpos[bad] = m.qpos0[bad]
    d.qvel[~np.isfinite(d.qvel)] = 0.0
    d.qacc_warmstart[:] = 0.0
    d.qacc[:] = 0.0
    mst.wake_all(m, d)
    engine.observed = None
    engine.diverged = False
    restart_looks(engine)


def restart_looks(engine: MujocoEngine) -> None:
    """The periodic looks start over, with a fresh sleep guard: a rewound or cleared
    world replays its trajectory exactly."""
    engine.steps_since_look = 0
    if engine.sleep_guard is not None:
        engine.sleep_guard.release_all(engine.model)
        engine.sleep_guard = engine.new_sleep_guard()
