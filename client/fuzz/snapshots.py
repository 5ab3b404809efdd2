"""Re-sealed corrupt snapshots for the fuzz campaign: a real blob, one field of its body
edited, and its digest computed again, as anyone can (issue 35, item 3).

The daemon must then either refuse the blob and change nothing, or restore a world that is
consistent in every read (``consistent``): every entity ``list`` names readable by
``get_states``, of a known shape.
"""

from __future__ import annotations

import copy
import hashlib
from collections.abc import Callable
from typing import Any

import msgpack
import numpy as np

from galton.client.sdk.client import Client
from galton.protocol import BODY_SHAPES, GaltonError, RemoteError

KNOWN_SHAPES = (*BODY_SHAPES, "model", "link")
ODD_VALUES: tuple[Any, ...] = (2, -1.0, 0.0, 1e308, "", "x", None, [], {}, True,
                               [1.0, 2.0, 3.0, 4.0])


def reseal(body: dict[str, Any]) -> bytes:
    """A blob of this body, sealed with the unkeyed digest a daemon without a key uses."""
    raw = msgpack.packb(body, use_bin_type=True)
    digest = hashlib.blake2b(raw, digest_size=32).digest()
    blob: bytes = msgpack.packb({"galton_snapshot": 1, "blake2b": digest, "body": raw},
                                use_bin_type=True)
    return blob


def open_blob(blob: bytes) -> dict[str, Any]:
    """The body of a snapshot blob (trusted: one the daemon just made)."""
    body: dict[str, Any] = msgpack.unpackb(msgpack.unpackb(blob, raw=False)["body"],
                                           raw=False)
    return body


def _paths(value: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every place in the body a value sits (map keys and list indices)."""
    found = [prefix] if prefix else []
    if isinstance(value, dict):
        for key, inner in value.items():
            found += _paths(inner, (*prefix, key))
    elif isinstance(value, list):
        for index, inner in enumerate(value[:8]):
            found += _paths(inner, (*prefix, index))
    return found


def _set(body: Any, path: tuple[Any, ...], value: Any) -> None:
    for key in path[:-1]:
        body = body[key]
    body[path[-1]] = value


def corrupt(body: dict[str, Any], rng: np.random.Generator) -> dict[str, Any]:
    """A copy of the body with one value replaced (an odd value, or a renamed entity), or
    one key dropped."""
    edited = copy.deepcopy(body)
    paths = _paths(edited)
    path = paths[int(rng.integers(len(paths)))]
    roll = rng.random()
    if roll < 0.15:
        parent: Any = edited
        for key in path[:-1]:
            parent = parent[key]
        if isinstance(parent, dict):
            del parent[path[-1]]
            return edited
    entities = edited.get("entities") or []
    if roll < 0.35 and entities:
        entity = entities[int(rng.integers(len(entities)))]
        entity["name"] = str(entity["name"]) + "_renamed"
        return edited
    _set(edited, path, ODD_VALUES[int(rng.integers(len(ODD_VALUES)))])
    return edited


def consistent(client: Client) -> str | None:
    """Why the world is inconsistent, or None when every read agrees."""
    try:
        entities = client.call("list")["entities"]
        shapes = [e["shape"] for e in entities]
        odd = [s for s in shapes if s not in KNOWN_SHAPES]
        if odd:
            return f"list serves shape {odd[0]!r}"
        names = [e["name"] for e in entities]
        if names:
            client.call("get_states", {"names": names})
    except GaltonError as error:
        return f"{type(error).__name__}: {error}"
    return None


def resealed_campaign(client: Client, count: int, rng: np.random.Generator,
                      look: Callable[[], str]) -> list[str]:
    """Restore ``count`` re-sealed corrupt copies of the present world; what went wrong.

    ``look`` hashes the world: a refused blob must leave it the same. An accepted one must
    be consistent; the original is restored again after it."""
    original = client.call("snapshot", {"blob": True})["blob"]
    body = open_blob(original)
    problems: list[str] = []
    for index in range(count):
        before = look()
        edited = corrupt(body, rng)
        try:
            client.call("restore", {"blob": reseal(edited)})
        except RemoteError as error:
            if look() != before:
                problems.append(f"#{index}: refused ({error.code.name}) yet changed the world")
            continue
        why = consistent(client)
        if why is not None:
            problems.append(f"#{index}: accepted an inconsistent world: {why}")
        client.call("restore", {"blob": original})
    return problems
