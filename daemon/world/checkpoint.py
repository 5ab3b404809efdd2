"""Checkpoints on disk (``galton-daemon --state-dir DIR``): the live world saved as a
snapshot blob periodically and when the daemon stops, and restored when a daemon of the
same instance starts again, so a killed or restarted daemon comes back with its world.

The file is ``DIR/<instance>.snapshot`` (msgpack, docs/protocol.md "snapshot"), written to
a temporary name and renamed, so a crash mid-write leaves the previous checkpoint whole. A
checkpoint that cannot be restored is moved aside to ``<instance>.snapshot.bad`` and the
daemon starts empty, saying so.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from pathlib import Path

from galton.daemon.core.limits import Limits
from galton.daemon.engines.base import Engine
from galton.daemon.world.snapshot import decode, encode, snapshot_of, world_from
from galton.daemon.world.world import World
from galton.protocol import GaltonError

log = logging.getLogger("galton.daemon")
DEFAULT_PERIOD_S = 10.0


def checkpoint_path(state_dir: Path, instance: str) -> Path:
    return state_dir / f"{instance}.snapshot"


def save(world: World, path: Path, key: bytes | None = None) -> int:
    """Write the world's snapshot atomically (sealed with ``key``, --snapshot-key);
    returns its size in bytes."""
    blob = encode(snapshot_of(world, canonical=False), key)
    temporary = path.with_name(path.name + ".tmp")
    temporary.write_bytes(blob)
    os.replace(temporary, path)
    return len(blob)


def load(path: Path, make_engine: Callable[[str], Engine], name: str,
         limits: Limits, key: bytes | None = None) -> World | None:
    """The world a checkpoint holds, or None (no checkpoint, or one set aside as bad)."""
    if not path.is_file():
        return None
    try:
        return world_from(decode(path.read_bytes(), limits, key), make_engine, name,
                          limits)
    except (GaltonError, OSError) as error:
        bad = path.with_name(path.name + ".bad")
        os.replace(path, bad)
        log.warning("the checkpoint %s cannot be restored (%s); moved to %s, starting empty",
                    path, error, bad)
        return None
