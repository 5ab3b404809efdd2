"""The PyBullet engine's perception on a known scene: a plane at z = 0, a box and a sphere
at known places, a camera looking straight down from a known height; ray casts against
the same scene; the contacts of a box resting on the plane."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
from support.urdf import ARM_URDF

from galton.daemon.engines.base import (
    FEATURE_CONTACTS,
    FEATURE_RAYCAST,
    FEATURE_RENDER,
    IMAGE_OUTPUTS,
    CameraView,
)
from galton.daemon.engines.pybullet.engine import PybulletEngine
from galton.daemon.engines.pybullet.meshes import MESH_TOLERANCE
from galton.daemon.engines.pybullet.rays import BATCH
from galton.protocol import BodyGroup, NotFoundError

GRAVITY = 9.81
HEIGHT = 2.0  # the camera's height above the plane
FOV = 60.0
WIDTH, PIXELS_HIGH = 320, 240
HALF = 0.1  # the box's half size and the sphere's radius
BOX_AT = (0.5, 0.0)  # where the box stands (x, y), its top at 2 * HALF
BALL_AT = (-0.5, 0.4)  # the sphere, resting on the plane, higher in the picture (+y up)
BOX_MASS = 2.0
RED, BLUE, GREY = (1.0, 0.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0), (0.5, 0.5, 0.5, 1.0)
IDENTITY = (0.0, 0.0, 0.0, 1.0)


def group(shape: str, size: tuple[float, ...], name: str, at: tuple[float, float, float],
          rgba: tuple[float, float, float, float], **extra: object) -> BodyGroup:
    return BodyGroup(shape, size, [name], np.array([[*at, *IDENTITY]]), rgba=rgba,
                     **extra)  # type: ignore[arg-type]


@pytest.fixture
def scene() -> Iterator[PybulletEngine]:
    engine = PybulletEngine()
    engine.spawn([group("plane", (5.0, 5.0), "floor", (0.0, 0.0, 0.0), GREY, static=True),
                  group("box", (HALF,) * 3, "crate", (*BOX_AT, HALF), RED, mass=BOX_MASS),
                  group("sphere", (HALF,), "ball", (*BALL_AT, HALF), BLUE)])
    yield engine
    engine.close()


def down_camera(outputs: tuple[str, ...] = IMAGE_OUTPUTS) -> CameraView:
    return CameraView(eye=np.array([0.0, 0.0, HEIGHT]), target=np.zeros(3),
                      up=np.array([0.0, 1.0, 0.0]), fov_deg=FOV, width=WIDTH,
                      height=PIXELS_HIGH, near=0.1, far=10.0, outputs=outputs)


def pixel(x: float, y: float, z: float) -> tuple[int, int]:
    """The (row, column) where the down camera sees the world point (x, y, z)."""
    focal = PIXELS_HIGH / 2 / math.tan(math.radians(FOV / 2))
    scale = focal / (HEIGHT - z)
    return (int(PIXELS_HIGH / 2 - y * scale), int(WIDTH / 2 + x * scale))


def test_capabilities_list_perception(scene: PybulletEngine) -> None:
    caps = scene.capabilities()
    assert {FEATURE_RENDER, FEATURE_RAYCAST, FEATURE_CONTACTS} <= set(caps.features)
    assert caps.render_backend == "tinyrenderer"


def test_depth_is_metres_along_the_view_axis(scene: PybulletEngine) -> None:
    (images,), _ = scene.render([down_camera(("depth",))])
    depth = images["depth"]
    assert depth.shape == (PIXELS_HIGH, WIDTH) and depth.dtype == np.float32
    assert depth[PIXELS_HIGH // 2, WIDTH // 2] == pytest.approx(HEIGHT, abs=1e-4)
    assert depth[pixel(*BOX_AT, 2 * HALF)] == pytest.approx(HEIGHT - 2 * HALF, abs=1e-4)
    assert depth[pixel(*BALL_AT, 2 * HALF)] == pytest.approx(HEIGHT - 2 * HALF, abs=2e-3)
    # A corner pixel sees the plane off the axis: its z-depth is still the height.
    assert depth[0, 0] == pytest.approx(HEIGHT, abs=1e-4)


def test_segmentation_and_colours_name_the_entities(scene: PybulletEngine) -> None:
    (images,), labels = scene.render([down_camera()])
    seg, rgb = images["segmentation"], images["rgb"]
    assert seg.dtype == np.int32 and rgb.dtype == np.uint8 and rgb.shape == (
        PIXELS_HIGH, WIDTH, 3)
    assert sorted(labels) == ["ball", "crate", "floor"]
    box, ball = pixel(*BOX_AT, 2 * HALF), pixel(*BALL_AT, 2 * HALF)
    assert labels[seg[box]] == "crate" and labels[seg[ball]] == "ball"
    assert labels[seg[PIXELS_HIGH // 2, WIDTH // 2]] == "floor"
    assert ball[0] < PIXELS_HIGH // 2  # +y (the camera's up) is the top of the image
    red, blue = rgb[box].astype(int), rgb[ball].astype(int)
    assert red[0] > 150 and red[1] < 30 and red[2] < 30
    assert blue[2] > 150 and blue[0] < 30 and blue[1] < 30
    grey = rgb[PIXELS_HIGH // 2, WIDTH // 2].astype(int)
    assert abs(grey[0] - grey[1]) < 3 and abs(grey[1] - grey[2]) < 3


def test_nothing_in_view_is_inf_and_minus_one(scene: PybulletEngine) -> None:
    up = CameraView(eye=np.array([0.0, 0.0, 1.0]), target=np.array([0.0, 0.0, 2.0]),
                    up=np.array([0.0, 1.0, 0.0]), fov_deg=FOV, width=64, height=48,
                    near=0.1, far=10.0, outputs=("depth", "segmentation"))
    (images,), labels = scene.render([up])
    assert np.isinf(images["depth"]).all()
    assert (images["segmentation"] == -1).all() and not labels


def test_several_cameras_share_one_label_list(scene: PybulletEngine) -> None:
    small = CameraView(eye=np.array([*BOX_AT, 1.0]), target=np.array([*BOX_AT, 0.0]),
                       up=np.array([0.0, 1.0, 0.0]), fov_deg=10.0, width=32, height=24,
                       near=0.1, far=10.0, outputs=("segmentation",))
    (wide, narrow), labels = scene.render([down_camera(("segmentation",)), small])
    assert set(narrow) == {"segmentation"}
    assert labels[narrow["segmentation"][12, 16]] == "crate"
    assert {labels[k] for k in np.unique(wide["segmentation"])} == {"ball", "crate", "floor"}


def test_rays_hit_points_normals_distances(scene: PybulletEngine) -> None:
    origins = np.array([[*BOX_AT, HEIGHT], [*BALL_AT, HEIGHT], [3.0, 3.0, HEIGHT],
                        [0.0, 0.0, HEIGHT], [-2.0, BALL_AT[1] + 0.05, 0.13], [0.0, 0.0, 0.5]])
    directions = np.array([[0, 0, -1.0]] * 4 + [[1.0, 0, 0], [0, 0, 1.0]])
    hits, names, points, normals, distances = scene.raycast(origins, directions, 10.0)
    assert hits.tolist() == [True] * 5 + [False]
    assert names == ["crate", "ball", "floor", "floor", "ball", ""]
    np.testing.assert_allclose(distances[:4], [1.8, 1.8, 2.0, 2.0], atol=1e-9)
    np.testing.assert_allclose(normals[:4], [[0, 0, 1.0]] * 4, atol=1e-9)
    # Off-centre on the sphere: exact, not Bullet's convex cast (4e-4 m off there).
    offset = np.array([0.0, 0.05, 0.03])
    x = BALL_AT[0] - math.sqrt(HALF**2 - offset @ offset)
    np.testing.assert_allclose(points[4], [x, BALL_AT[1] + 0.05, 0.13], atol=1e-9)
    np.testing.assert_allclose(normals[4], (points[4] - [*BALL_AT, HALF]) / HALF, atol=1e-9)
    assert distances[4] == pytest.approx(x + 2.0, abs=1e-9)
    assert np.isnan(points[5]).all() and np.isnan(normals[5]).all() and np.isnan(distances[5])


def test_a_ray_bullet_grazes_goes_on_past_the_body(scene: PybulletEngine) -> None:
    """Bullet's sphere stands out, off its axes, by 5e-4 m and more: a ray 3e-4 m clear of
    the exact sphere hits it there, and the exact test sends it on to the floor."""
    off = (HALF + 3e-4) / math.sqrt(2)
    clear = (BALL_AT[0] + off, BALL_AT[1] + off, HEIGHT)
    bullet = scene._bc.rayTestBatch([clear], [(*clear[:2], -1.0)])[0]
    assert bullet[0] == scene.bodies["ball"].uid  # Bullet alone says: the ball
    hits, names, points, _, distances = scene.raycast(
        np.array([clear]), np.array([[0, 0, -1.0]]), 10.0)
    assert hits[0] and names == ["floor"] and distances[0] == pytest.approx(HEIGHT, abs=1e-9)
    np.testing.assert_allclose(points[0], [*clear[:2], 0.0], atol=1e-9)


def test_a_plane_is_seen_from_its_front_only(scene: PybulletEngine) -> None:
    """As MuJoCo's rays see it: from below, a ray goes through the floor to the ball."""
    hits, names, points, normals, distances = scene.raycast(
        np.array([[*BALL_AT, -1.0], [*BALL_AT, -1.0]]), np.array([[0, 0, 1.0], [0, 0, -1.0]]),
        10.0)
    assert names == ["ball", ""] and hits.tolist() == [True, False]
    assert distances[0] == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(points[0], [*BALL_AT, 0.0], atol=1e-9)
    np.testing.assert_allclose(normals[0], [0, 0, -1.0], atol=1e-9)


def test_rays_stop_at_max_length(scene: PybulletEngine) -> None:
    hits, names, _, _, distances = scene.raycast(
        np.array([[*BOX_AT, HEIGHT]]), np.array([[0, 0, -1.0]]), 1.5)
    assert not hits[0] and names == [""] and np.isnan(distances[0])


def test_rays_on_the_box_sides_and_across_every_primitive() -> None:
    engine = PybulletEngine()
    try:
        engine.spawn([group("cylinder", (0.1, 0.2), "can", (0.0, 0.0, 1.0), RED, static=True),
                      group("capsule", (0.1, 0.2), "pill", (1.0, 0.0, 1.0), BLUE, static=True)])
        origins = np.array([[0.0, 0.0, 3.0], [-1.0, 0.05, 1.1], [1.0, 0.0, 3.0],
                            [0.0, 0.05, 1.25]])
        directions = np.array([[0, 0, -1.0], [1.0, 0, 0], [0, 0, -1.0], [1.0, 0, 0]])
        hits, names, points, normals, distances = engine.raycast(origins, directions, 10.0)
        assert names == ["can", "can", "pill", "pill"]
        side = -math.sqrt(0.1**2 - 0.05**2)
        np.testing.assert_allclose(points[:3], [[0, 0, 1.2], [side, 0.05, 1.1],
                                                [1.0, 0, 1.3]], atol=1e-9)
        np.testing.assert_allclose(normals[1], [side / 0.1, 0.5, 0.0], atol=1e-9)
        # Into the capsule's upper cap from the side: its sphere round (1, 0, 1.2).
        rel = np.array([0.0, 0.05, 0.05])
        x = 1.0 - math.sqrt(0.1**2 - rel @ rel)
        np.testing.assert_allclose(points[3], [x, 0.05, 1.25], atol=1e-9)
        np.testing.assert_allclose(normals[3], (points[3] - [1.0, 0, 1.2]) / 0.1, atol=1e-9)
        assert distances[3] == pytest.approx(x, abs=1e-9) and hits.all()
    finally:
        engine.close()


def test_more_rays_than_one_batch(scene: PybulletEngine) -> None:
    rng = np.random.default_rng(26)
    n = BATCH + 100
    origins = np.column_stack([rng.uniform(-1, 1, (n, 2)), np.full(n, HEIGHT)])
    directions = np.tile([0.0, 0.0, -1.0], (n, 1))
    hits, names, points, _, distances = scene.raycast(origins, directions, 10.0)
    assert hits.all() and len(names) == n
    np.testing.assert_allclose(distances, HEIGHT - points[:, 2], atol=1e-9)
    on_floor = np.array([name == "floor" for name in names])
    np.testing.assert_allclose(points[on_floor, 2], 0.0, atol=1e-9)


def test_resting_box_contacts_carry_its_weight(scene: PybulletEngine) -> None:
    scene.step(240)
    firsts, seconds, positions, normals, forces, penetrations = scene.contacts(["crate"])
    assert len(firsts) == 4
    assert all({a, b} == {"crate", "floor"} for a, b in zip(firsts, seconds, strict=True))
    assert forces.sum() == pytest.approx(BOX_MASS * GRAVITY, rel=0.01)
    assert (forces >= 0).all() and (penetrations >= 0).all() and penetrations.max() < 1e-3
    for a, normal in zip(firsts, normals, strict=True):  # from the first to the second
        np.testing.assert_allclose(normal, [0, 0, -1.0] if a == "crate" else [0, 0, 1.0],
                                   atol=1e-6)
    np.testing.assert_allclose(np.sort(np.abs(positions[:, 0] - BOX_AT[0])), [HALF] * 4,
                               atol=1e-3)
    everyone = scene.contacts(None)
    assert len(everyone[0]) == 5  # and the ball's one point
    with pytest.raises(NotFoundError, match="did you mean"):
        scene.contacts(["crates"])


def test_links_by_name_in_pictures_rays_and_contacts() -> None:
    engine = PybulletEngine()
    try:
        entities = engine.load_model("urdf", ARM_URDF, None, "r_")
        assert [e.name for e in entities] == ["r_base", "r_arm"]
        hits, names, points, _, _ = engine.raycast(
            np.array([[0.0, 0.0, HEIGHT], [-1.0, 0.0, 0.0]]),
            np.array([[0, 0, -1.0], [1.0, 0, 0]]), 10.0)
        assert names == ["r_arm", "r_base"] and hits.all()
        np.testing.assert_allclose(points, [[0, 0, 0.4], [-0.1, 0, 0]], atol=1e-6)
        (images,), labels = engine.render([down_camera(("segmentation",))])
        seen = {labels[k] for k in np.unique(images["segmentation"]) if k >= 0}
        assert seen == {"r_arm", "r_base"}
        assert labels[images["segmentation"][PIXELS_HIGH // 2, WIDTH // 2]] == "r_arm"
        engine.step(10)
        assert engine.contacts(["r_arm"])[0] == []
    finally:
        engine.close()


def test_a_rendered_sphere_is_within_the_mesh_tolerance() -> None:
    """The visual mesh has segments enough (pybullet_meshes.segments): over the cap a camera
    above sees face on (normals within 30 degrees of the view), the depth is the sphere's
    within a few times MESH_TOLERANCE, float32 and the rasteriser included."""
    radius, size = 0.2, 120
    engine = PybulletEngine()
    try:
        engine.spawn([group("sphere", (radius,), "ball", (0.0, 0.0, 0.0), BLUE, static=True)])
        eye = np.array([0.0, 0.0, 4 * radius])
        view = CameraView(eye=eye, target=np.zeros(3), up=np.array([0.0, 1.0, 0.0]),
                          fov_deg=FOV, width=size, height=size, near=0.01, far=10.0,
                          outputs=("depth",))
        (images,), _ = engine.render([view])
    finally:
        engine.close()
    focal = size / 2 / math.tan(math.radians(FOV / 2))
    columns, rows = np.meshgrid(np.arange(size) + 0.5 - size / 2, size / 2 - np.arange(size)
                                - 0.5)
    rays = np.stack([columns / focal, rows / focal, -np.ones((size, size))], axis=-1)
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    b, c = rays @ eye, eye @ eye - radius**2
    face_on = b * b - c > (radius * math.cos(math.radians(30))) ** 2
    along = (-b - np.sqrt(np.maximum(b * b - c, 0.0))) * -rays[..., 2]
    error = images["depth"][face_on] - along[face_on]
    assert face_on.sum() > 500
    assert np.abs(error).max() < 2.5 * MESH_TOLERANCE


def test_looking_changes_nothing_that_comes_after(scene: PybulletEngine) -> None:
    """Pictures, rays and contact queries between steps leave the simulation bit for bit as
    it goes on without them."""
    twin = PybulletEngine()
    try:
        twin.spawn([group("plane", (5.0, 5.0), "floor", (0.0, 0.0, 0.0), GREY, static=True),
                    group("box", (HALF,) * 3, "crate", (*BOX_AT, HALF), RED, mass=BOX_MASS),
                    group("sphere", (HALF,), "ball", (*BALL_AT, HALF), BLUE)])
        names = ["crate", "ball"]
        scene.set_states(names, None, np.array([[0.3, 0, 2.0, 1.0, 2.0, 0.5]] * 2))
        twin.set_states(names, None, np.array([[0.3, 0, 2.0, 1.0, 2.0, 0.5]] * 2))
        for _ in range(20):
            scene.render([down_camera()])
            scene.raycast(np.array([[0.0, 0.0, HEIGHT]]), np.array([[0, 0, -1.0]]), 10.0)
            scene.contacts(None)
            scene.step(5)
            twin.step(5)
        for mine, theirs in zip(scene.get_states(names), twin.get_states(names), strict=True):
            np.testing.assert_array_equal(mine, theirs)
    finally:
        twin.close()


def test_names_follow_rebuilds_and_deletes(scene: PybulletEngine) -> None:
    """A rebuild gives every body a new PyBullet id; what is seen is still named right."""
    scene.reset_dynamics()
    scene.delete(["crate"])
    (images,), labels = scene.render([down_camera(("segmentation",))])
    assert sorted(labels) == ["ball", "floor"]
    assert labels[images["segmentation"][pixel(*BALL_AT, 2 * HALF)]] == "ball"
    _, names, _, _, _ = scene.raycast(np.array([[*BALL_AT, HEIGHT], [*BOX_AT, HEIGHT]]),
                                      np.array([[0, 0, -1.0]] * 2), 10.0)
    assert names == ["ball", "floor"]
