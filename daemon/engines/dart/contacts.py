"""The contact points of a DART world's last step, as the engine contract has them.

DART's collision result gives per point the two collision objects, the point, the normal
from the second object to the first, the penetration depth and, once the constraint
solver has run, the contact force on the first. The contract wants the normal from the
first entity to the second, so it is turned round, and the normal force as a magnitude.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import Any

import numpy as np

Contacts = tuple[list[str], list[str], np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def node_key(node: Any) -> tuple[str, str]:
    """What names a body node across dartpy's wrappers: its skeleton's and its own name."""
    return node.getSkeleton().getName(), node.getName()


def contacts(world: Any, entities: Mapping[tuple[str, str], str],
             names: Collection[str] | None) -> Contacts:
    """Every contact point between two entities, or those involving any of ``names``."""
    firsts: list[str] = []
    seconds: list[str] = []
    rows: list[np.ndarray] = []
    for contact in world.getLastCollisionResult().getContacts():
        a = entities.get(_entity_key(contact.collisionObject1))
        b = entities.get(_entity_key(contact.collisionObject2))
        if a is None or b is None or (names is not None and a not in names
                                      and b not in names):
            continue
        normal = -np.asarray(contact.normal, dtype=float)  # now from a to b
        force = abs(float(np.dot(np.asarray(contact.force, dtype=float), normal)))
        firsts.append(a)
        seconds.append(b)
        rows.append(np.concatenate([np.asarray(contact.point, dtype=float), normal,
                                    [force, max(float(contact.penetrationDepth), 0.0)]]))
    table = np.array(rows, float).reshape(len(rows), 8)
    return (firsts, seconds, table[:, 0:3], table[:, 3:6], table[:, 6].copy(),
            table[:, 7].copy())


def _entity_key(obj: Any) -> tuple[str, str]:
    return node_key(obj.getShapeFrame().asShapeNode().getBodyNodePtr())
