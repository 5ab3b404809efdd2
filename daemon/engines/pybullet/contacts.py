"""The contact points of a PyBullet world's last step, as the engine contract has them.

getContactPoints gives, per point, the two bodies and links, the points on each surface,
``contactNormalOnB`` (pointing from B to A), ``contactDistance`` (negative: penetration)
and the normal force of the last step's solve. The contract wants the normal from the first
entity to the second, so it is turned round; the position is midway between the surfaces.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping

import numpy as np
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet.render import code

Contacts = tuple[list[str], list[str], np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def contacts(bc: BulletClient, codes: Mapping[int, str], names: Collection[str] | None
             ) -> Contacts:
    """Every contact point between two entities, or those involving any of ``names``."""
    firsts: list[str] = []
    seconds: list[str] = []
    rows: list[list[float]] = []
    for point in bc.getContactPoints():
        a = codes.get(code(point[1], point[3]))
        b = codes.get(code(point[2], point[4]))
        if a is None or b is None or (names is not None and a not in names
                                      and b not in names):
            continue
        firsts.append(a)
        seconds.append(b)
        rows.append([*point[5], *point[6], *point[7], point[8], point[9]])
    table = np.array(rows, float).reshape(len(rows), 11)
    positions = (table[:, 0:3] + table[:, 3:6]) / 2.0
    normals = -table[:, 6:9]
    penetrations = np.maximum(-table[:, 9], 0.0)
    forces = np.maximum(table[:, 10], 0.0)
    return firsts, seconds, positions, normals, forces, penetrations
