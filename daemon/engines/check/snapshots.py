"""Engine checks for snapshots and clones (skipped unless the engine lists "snapshot"):
a snapshot restored into a fresh engine goes on exactly as its source, and a clone is an
independent copy that goes on as the source would."""

from __future__ import annotations

import msgpack
import numpy as np

from galton.daemon.engines.base import FEATURE_SNAPSHOT, Engine
from galton.daemon.engines.check.support import (
    CheckContext,
    expect_identical,
    ground,
    group,
    skip_unless,
    states,
)

PILE = [f"s{i}" for i in range(6)]


def _pile(engine: Engine) -> None:
    """Six spheres dropped onto each other and a plane, in contact after 0.2 s."""
    positions = [[0.02 * (i % 2), 0.0, 0.2 + 0.11 * i] for i in range(len(PILE))]
    engine.spawn([ground(), group("sphere", PILE, positions)])
    engine.step(round(0.2 / engine.timestep))


def check_snapshot_continuation(ctx: CheckContext) -> None:
    """A snapshot (through msgpack, as it travels) restored into a fresh engine goes on bit
    for bit as its source, with a teleport between the steps; restored twice, twice alike."""
    source = ctx.engine
    skip_unless(source, FEATURE_SNAPSHOT)
    _pile(source)
    data = msgpack.unpackb(msgpack.packb(source.snapshot(), use_bin_type=True), raw=False)
    copies = [ctx.fresh(), ctx.fresh()]
    for copy in copies:
        copy.restore(data)
    kick = np.array([[0.5, 0.0, 1.0, 0.0, 0.0, 0.0]])
    for engine in (source, *copies):
        engine.step(50)
        engine.set_states(["s0"], None, kick)
        engine.step(50)
    poses, twists = states(source, PILE)
    for copy in copies:
        seen_poses, seen_twists = states(copy, PILE)
        expect_identical(seen_poses, poses, "a restored world's poses after 100 steps")
        expect_identical(seen_twists, twists, "a restored world's twists after 100 steps")


def check_clone_independent(ctx: CheckContext) -> None:
    """A clone goes on as a snapshot of its source restored without disturbing it would,
    and changing one never changes the other."""
    source = ctx.engine
    skip_unless(source, FEATURE_SNAPSHOT)
    _pile(source)
    twin = ctx.fresh()
    twin.restore(source.snapshot(canonical=False))
    clone = source.clone()
    ctx.made.append(clone)
    clone.set_states(["s1"], None, np.array([[0.0, 0.0, 3.0, 0.0, 0.0, 0.0]]))
    twin.set_states(["s1"], None, np.array([[0.0, 0.0, 3.0, 0.0, 0.0, 0.0]]))
    before = states(source, PILE)
    clone.step(40)
    twin.step(40)
    expect_identical(states(clone, PILE)[0], states(twin, PILE)[0],
                     "a clone's poses against a restored snapshot's")
    expect_identical(states(source, PILE)[0], before[0], "the source's poses as the clone "
                     "stepped")
