"""A snapshot whose body was edited and sealed again is refused, or restores a world that
is consistent in every read (issue 35, item 3); the same for the spawned meshes' triangles
it keeps, and a snapshot made before it kept them tells its meshes as boxes. On every
engine, over Zenoh."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from support import snapshot
from support.urdf import ARM_URDF

from galton.client import Client, meshes, plane, spheres
from galton.client.fuzz.snapshots import open_blob, reseal, resealed_campaign
from galton.protocol import InvalidArgumentError
from galton.protocol.mesh import box_mesh, pack_faces

CAMPAIGN = 20


def _scene(sim: Client) -> bytes:
    sim.spawn(plane(), spheres(["a", "b"], [[0, 0, 0.5], [0.3, 0, 0.5]], 0.05))
    sim.call("load_model", {"format": "urdf", "text": ARM_URDF, "fixed_base": True,
                            "prefix": "r_"})
    sim.step(3)
    return bytes(sim.call("snapshot", {"blob": True})["blob"])


def _entity(body: dict[str, Any], name: str) -> dict[str, Any]:
    return next(e for e in body["entities"] if e["name"] == name)


EDITS: dict[str, Callable[[dict[str, Any]], None]] = {
    "renamed": lambda body: _entity(body, "a").update(name="z"),
    "shape 2": lambda body: _entity(body, "a").update(shape=2),
    "unknown shape": lambda body: _entity(body, "a").update(shape="torus"),
    "negative size": lambda body: _entity(body, "a").update(size=[-1.0]),
    "size of a box": lambda body: _entity(body, "a").update(size=[0.1, 0.1, 0.1]),
    "static flipped": lambda body: _entity(body, "a").update(static=True),
    "link of no model": lambda body: _entity(body, "r_arm").update(model="nobody"),
    "entity dropped": lambda body: body["entities"].pop(0),
}


@pytest.mark.parametrize("edit", list(EDITS))
def test_an_edited_resealed_snapshot_is_refused_and_changes_nothing(sim: Client,
                                                                    edit: str) -> None:
    body = open_blob(_scene(sim))
    EDITS[edit](body)
    before = snapshot(sim)
    with pytest.raises(InvalidArgumentError, match="snapshot"):
        sim.call("restore", {"blob": reseal(body)})
    snapshot(sim).assert_same(before)


def test_resealed_corrupt_snapshots_never_leave_an_inconsistent_world(sim: Client) -> None:
    _scene(sim)
    problems = resealed_campaign(sim, CAMPAIGN, np.random.default_rng(35),
                                 lambda: repr(snapshot(sim)))
    assert problems == []


def _mesh_scene(sim: Client) -> dict[str, Any]:
    if "mesh" not in sim.capabilities().body_shapes:
        pytest.skip("this engine spawns no mesh")
    vertices, faces = box_mesh((0.1, 0.05, 0.08))
    sim.spawn(meshes(["m"], [[0, 0, 0.5]], vertices, faces, static=True),
              spheres(["a"], [[0.3, 0, 0.5]], 0.05))
    return open_blob(bytes(sim.call("snapshot", {"blob": True})["blob"]))


MESH_EDITS: dict[str, Callable[[dict[str, Any]], None]] = {
    "given to a sphere": lambda body: body["meshes"][0]["names"].append("a"),
    "of no body": lambda body: body["meshes"][0].update(names=["nobody"]),
    "face out of range": lambda body: body["meshes"][0].update(
        faces=pack_faces(np.array([[0, 1, 9]]))),
    "no list": lambda body: body.update(meshes={"m": 1}),
}


def test_edited_mesh_triangles_are_refused_and_an_older_snapshot_tells_boxes(
        sim: Client) -> None:
    body = _mesh_scene(sim)
    before = snapshot(sim)
    for edit in MESH_EDITS.values():
        edited = open_blob(reseal(body))  # a fresh copy
        edit(edited)
        with pytest.raises(InvalidArgumentError, match="snapshot's meshes"):
            sim.call("restore", {"blob": reseal(edited)})
        snapshot(sim).assert_same(before)
    del body["meshes"]  # as a daemon that kept no triangles made it
    sim.call("restore", {"blob": reseal(body)})
    [mesh] = sim.get_shapes(["m"])["m"]
    assert mesh.boxed and mesh.size == pytest.approx((0.1, 0.05, 0.08))
