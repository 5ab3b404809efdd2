"""The MuJoCo engine's perception on its own: camera images, ray casts, contacts.

A known scene: a grey plane at z = 0, a red box (half side 0.2) on it at the origin, a blue
ball (radius 0.3) at y = 1, a green static post (half sides 0.25) at x = 1; a camera 3 m
above the origin looks straight down with +y up, so +x is to the right.
"""

from __future__ import annotations

import gc
import math
import threading
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest

from galton.daemon.engines.base import FEATURE_CONTACTS, FEATURE_RAYCAST, FEATURE_RENDER, CameraView
from galton.daemon.engines.mujoco import rays as mujoco_sensing
from galton.daemon.engines.mujoco.engine import MujocoEngine
from galton.protocol import BodyGroup, NotFoundError

GRAVITY = 9.81
IDENTITY = (0.0, 0.0, 0.0, 1.0)
HEIGHT = 3.0  # the camera's
FOV = 60.0
WIDTH, ROWS = 640, 480
RED, BLUE, GREEN, GREY = (1, 0, 0, 1), (0, 0, 1, 1), (0, 1, 0, 1), (0.5, 0.5, 0.5, 1)


def body(shape: str, name: str, position: Sequence[float], size: Sequence[float],
         **options: Any) -> BodyGroup:
    return BodyGroup(shape=shape, size=tuple(size), names=[name],
                     poses=np.array([[*position, *IDENTITY]], dtype=float), **options)


def scene(engine: MujocoEngine) -> None:
    engine.spawn([body("plane", "ground", (0, 0, 0), (5, 5), static=True, rgba=GREY),
                  body("box", "box", (0, 0, 0.2), (0.2, 0.2, 0.2), rgba=RED),
                  body("sphere", "ball", (0, 1, 0.3), (0.3,), rgba=BLUE),
                  body("box", "post", (1, 0, 0.25), (0.25, 0.25, 0.25), static=True,
                       rgba=GREEN)])


def down(outputs: tuple[str, ...] = ("rgb", "depth", "segmentation"), *,
         eye: Sequence[float] = (0, 0, HEIGHT), far: float = 10.0, width: int = WIDTH,
         height: int = ROWS) -> CameraView:
    eye_ = np.array(eye, dtype=float)
    return CameraView(eye=eye_, target=eye_ - [0, 0, 1], up=np.array([0.0, 1.0, 0.0]),
                      fov_deg=FOV, width=width, height=height, near=0.1, far=far,
                      outputs=outputs)


def pixel(x: float, y: float, depth: float) -> tuple[int, int]:
    """(row, column) of the world point (x, y) seen ``depth`` below the camera."""
    scale = ROWS / 2 / math.tan(math.radians(FOV / 2)) / depth
    return int(ROWS / 2 - y * scale), int(WIDTH / 2 + x * scale)


@pytest.fixture
def engine() -> Any:
    engine = MujocoEngine()
    yield engine
    engine.close()


def test_the_engine_offers_perception(engine: MujocoEngine) -> None:
    caps = engine.capabilities()
    assert {FEATURE_RENDER, FEATURE_RAYCAST, FEATURE_CONTACTS} <= set(caps.features)
    assert caps.render_backend in ("egl", "osmesa")


def test_depth_segmentation_and_colour_of_a_known_scene(engine: MujocoEngine) -> None:
    scene(engine)
    (image,), labels = engine.render([down()])
    assert image["rgb"].shape == (ROWS, WIDTH, 3) and image["rgb"].dtype == np.uint8
    assert image["depth"].shape == (ROWS, WIDTH) and image["depth"].dtype == np.float32
    assert image["segmentation"].dtype == np.int32
    assert sorted(labels) == ["ball", "box", "ground", "post"]
    seen = {(HEIGHT - 0.4, "box", 0), (HEIGHT - 0.6, "ball", 2), (HEIGHT - 0.5, "post", 1)}
    for depth, name, channel in seen:
        x, y = {"box": (0, 0), "ball": (0, 1), "post": (1, 0)}[name]
        row, column = pixel(x, y, depth)  # the top of each: the ball's is above y = 1
        assert image["depth"][row, column] == pytest.approx(depth, abs=2e-3)
        assert labels[image["segmentation"][row, column]] == name
        rgb = image["rgb"][row, column].astype(int)
        assert rgb[channel] > 200 and np.delete(rgb, channel).max() < 30, (name, rgb)
    corner = (5, 5)
    assert image["depth"][corner] == pytest.approx(HEIGHT, abs=2e-3)  # z-depth, not range
    assert labels[image["segmentation"][corner]] == "ground"
    assert np.ptp(image["rgb"][corner].astype(int)) <= 2  # grey


def test_nothing_within_far_is_inf_and_unlabelled(engine: MujocoEngine) -> None:
    scene(engine)
    up = CameraView(eye=np.array([0.0, 0, HEIGHT]), target=np.array([0.0, 0, 4]),
                    up=np.array([0.0, 1, 0]), fov_deg=FOV, width=64, height=48, near=0.1,
                    far=10.0, outputs=("depth", "segmentation"))
    short = down(("depth", "segmentation"), far=2.0, width=64, height=48)
    images, labels = engine.render([up, short])
    assert labels == []
    for image in images:
        assert np.isinf(image["depth"]).all() and (image["segmentation"] == -1).all()
        assert "rgb" not in image


def test_images_of_several_sizes_and_a_moved_body(engine: MujocoEngine) -> None:
    scene(engine)
    small, large = down(("depth",), width=32, height=24), down(("depth",), width=800,
                                                                   height=600)
    images, _ = engine.render([small, large, small])
    assert [im["depth"].shape for im in images] == [(24, 32), (600, 800), (24, 32)]
    np.testing.assert_array_equal(images[0]["depth"], images[2]["depth"])
    engine.set_states(["box"], np.array([[0, 0, 1.2, *IDENTITY]]), None)  # no step taken
    (image,), _ = engine.render([down(("depth",))])
    assert image["depth"][ROWS // 2, WIDTH // 2] == pytest.approx(HEIGHT - 1.4, abs=2e-3)


def test_rays_hit_where_the_geometry_is(engine: MujocoEngine) -> None:
    scene(engine)
    origins = np.array([[0, 0, 3], [1, 0, 3], [3, 3, 3], [0, 3, 0.3], [0, 0, 3],
                        [4, -4, 3]], dtype=float)
    directions = np.array([[0, 0, -1], [0, 0, -1], [0, 0, -1], [0, -1, 0], [0, 0, 1],
                           [0, 0, -1]], dtype=float)
    hit, names, points, normals, distances = engine.raycast(origins, directions, 2.9)
    assert hit.tolist() == [True, True, False, True, False, False]  # 3 m to the ground
    assert names == ["box", "post", "", "ball", "", ""]
    want = [[0, 0, 0.4], [1, 0, 0.5], [0, 1.3, 0.3]]
    np.testing.assert_allclose(points[hit], want, atol=1e-6)
    np.testing.assert_allclose(normals[hit], [[0, 0, 1], [0, 0, 1], [0, 1, 0]], atol=1e-6)
    np.testing.assert_allclose(distances[hit], [2.6, 2.5, 1.7], atol=1e-6)
    assert np.isnan(points[~hit]).all() and np.isnan(normals[~hit]).all()
    assert np.isnan(distances[~hit]).all()
    hit, names, points, _, _ = engine.raycast(origins[2:3], directions[2:3], 100.0)
    assert names == ["ground"]
    np.testing.assert_allclose(points, [[3, 3, 0]], atol=1e-6)


def test_rays_from_one_origin_answer_as_rays_one_by_one(engine: MujocoEngine) -> None:
    scene(engine)
    rng = np.random.default_rng(7)
    count = 4 * mujoco_sensing.MULTI_RAY_MIN
    directions = rng.normal(size=(count, 3)) - [0, 0, 2]
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    origins = np.tile([0.3, 0.4, 2.0], (count, 1))
    together = engine.raycast(origins, directions, 50.0)
    assert together[0].sum() > count // 2
    for i in range(count):
        alone = engine.raycast(origins[i:i + 1], directions[i:i + 1], 50.0)
        assert alone[1][0] == together[1][i]
        for got, want in zip(alone[2:], together[2:], strict=True):
            np.testing.assert_allclose(got[0], want[i], atol=1e-9)


def test_a_moved_static_body_is_where_rays_find_it(engine: MujocoEngine) -> None:
    scene(engine)
    engine.set_states(["post"], np.array([[-2, 0, 0.25, *IDENTITY]]), None)
    _, names, points, _, _ = engine.raycast(np.array([[-2.0, 0, 3]]),
                                              np.array([[0.0, 0, -1]]), 10.0)
    assert names == ["post"]
    np.testing.assert_allclose(points, [[-2, 0, 0.5]], atol=1e-6)
    engine.set_states(["ball"], np.array([[-2, 0, 1.0, *IDENTITY]]), None)
    engine.step(1000)  # and the physics finds it there too
    assert engine.get_states(["ball"])[0][0, 2] == pytest.approx(0.8, abs=1e-3)


def test_parked_bodies_are_not_seen_hit_or_touched(engine: MujocoEngine) -> None:
    scene(engine)
    engine.delete(["ball"])
    assert len(engine.parked) > 0  # its body waits, parked, far below the world
    below = (0.0, 0.0, -990.0)
    hit, _, _, _, _ = engine.raycast(np.array([below]), np.array([[0.0, 0, -1]]), 100.0)
    assert not hit.any()
    (image,), labels = engine.render([down(("depth", "segmentation"), eye=below, width=64,
                                           height=48)])
    assert labels == [] and np.isinf(image["depth"]).all()
    engine.step(10)
    a, b, *_ = engine.contacts(None)
    assert set(a) | set(b) <= {"ground", "box", "post"}


@pytest.mark.parametrize("sleep_tolerance", [0.0, 0.005], ids=["awake", "may-sleep"])
def test_a_box_resting_on_the_plane_pushes_with_its_weight(
        engine: MujocoEngine, sleep_tolerance: float) -> None:
    engine.set_params({"mujoco.sleep_tolerance": sleep_tolerance})
    engine.spawn([body("plane", "ground", (0, 0, 0), (5, 5), static=True, restitution=0.0),
                  body("box", "box", (0, 0, 0.1), (0.1, 0.1, 0.1), mass=2.0,
                       restitution=0.0),
                  body("sphere", "far", (3, 0, 2), (0.1,), static=True)])
    engine.step(1000)
    a, b, positions, normals, forces, depths = engine.contacts(["box"])
    assert len(a) == 4
    assert {(x, y) for x, y in zip(a, b, strict=True)} <= {("ground", "box"),
                                                           ("box", "ground")}
    up = np.where(np.array(a) == "ground", 1.0, -1.0)  # from the first to the second
    np.testing.assert_allclose(normals, up[:, None] * [0, 0, 1], atol=1e-9)
    np.testing.assert_allclose(np.abs(positions[:, :2]), 0.1, atol=1e-6)
    # A body asleep keeps the forces of the step it fell asleep at: MuJoCo sleeps a tree
    # slower than the tolerance for 10 steps, with its own impedance (dmin 0.9) while the
    # contact still slows it by 1.6 % of g (docs/PHYSICS.md, known limits).
    assert forces.sum() == pytest.approx(2.0 * GRAVITY, rel=0.01 if sleep_tolerance == 0 else
                                         0.02)
    assert (depths >= 0).all() and depths.max() < 1e-3
    assert engine.contacts(["far"])[0] == []  # a ball hung in the air touches nothing
    with pytest.raises(NotFoundError):
        engine.contacts(["nobody"])


def test_looking_changes_nothing_that_comes_after(engine: MujocoEngine) -> None:
    scene(engine)
    engine.set_states(["ball"], np.array([[0, 1, 1.5, *IDENTITY]]), None)
    twin = engine.clone()
    try:
        for _ in range(5):
            engine.step(40)
            twin.step(40)
            engine.render([down(width=64, height=48)])
            engine.raycast(np.array([[0.0, 1, 3]]), np.array([[0.0, 0, -1]]), 10.0)
            engine.contacts(None)
        for got, want in zip(engine.get_states(["box", "ball"]),
                             twin.get_states(["box", "ball"]), strict=True):
            np.testing.assert_array_equal(got, want)
    finally:
        twin.close()


def test_a_loaded_model_is_seen_link_by_link(engine: MujocoEngine) -> None:
    model = """<mujoco><worldbody><body name="base" pos="0 0 0.5">
      <geom type="box" size=".1 .1 .1"/>
      <body name="arm" pos=".5 0 0"><geom type="box" size=".1 .1 .1"/></body>
    </body></worldbody></mujoco>"""
    engine.load_model("mjcf", model, None, "r.")
    (image,), labels = engine.render([down(("segmentation",))])
    for name, x in (("r.base", 0.0), ("r.arm", 0.5)):
        assert labels[image["segmentation"][pixel(x, 0, HEIGHT - 0.6)]] == name
    _, names, _, _, _ = engine.raycast(np.array([[0.5, 0, 3]]), np.array([[0.0, 0, -1]]),
                                       10.0)
    assert names == ["r.arm"]


def test_engines_render_side_by_side_from_any_thread(engine: MujocoEngine) -> None:
    scene(engine)
    view = down(("depth",), width=64, height=48)
    twin = engine.clone()
    try:
        depths = [e.render([view])[0][0]["depth"] for e in (engine, twin)]
        dropped = engine.clone()
        dropped.render([view])
        del dropped  # unclosed: its GL objects go with it, not the others'
        gc.collect()
        depths += [e.render([view])[0][0]["depth"] for e in (engine, twin)]
        results: list[np.ndarray] = []
        worker = threading.Thread(target=lambda: results.append(
            twin.render([view])[0][0]["depth"]))
        worker.start()
        worker.join(timeout=60)
        for depth in [*depths, *results]:
            assert depth[24, 32] == pytest.approx(HEIGHT - 0.4, abs=2e-3)
        assert len(results) == 1
    finally:
        twin.close()
