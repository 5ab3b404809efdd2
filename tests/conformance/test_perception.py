"""Perception conformance, every engine through a real daemon: a known scene (ground, a red
box, a blue ball) rendered straight down gives the depth, segmentation and colours computed
by hand; rays hit where geometry says, the same on both engines; a resting box's contacts
carry its weight; an attached camera follows its body; bad input is refused, changing
nothing."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from support.daemons import start_daemon
from support.perception import (
    BALL_CENTRE,
    BALL_RADIUS,
    BOX_CENTRE,
    BOX_HALF,
    HEIGHT,
    ROWS,
    WIDTH,
    Pixel,
    expected_depth,
    known_scene,
    pixel_of,
    top_camera,
)

from galton.client import (
    Client,
    EmbeddedDaemon,
    FeatureUnsupportedError,
    Image,
    InvalidArgumentError,
    NotFoundError,
    ResourceLimitError,
    boxes,
    camera,
    plane,
    spheres,
    wait_for_daemon,
)
from galton.daemon.core.limits import DEFAULT_LIMITS
from galton.daemon.engines import create_engine

PLANE_DEPTH_TOL = 2e-3  # m: a flat surface's depth, float32 and the depth buffer's precision
# m: a rendered sphere is a tessellated mesh, its facets inside the sphere (5-7 mm near the
# top of this 0.2 m ball on both engines)
BALL_DEPTH_TOL = 0.05 * BALL_RADIUS
SAME_LABELS = 0.97  # share of pixels whose entity agrees with the hand computation (edges)
RAY_TOL = 1e-9  # m: ray answers against exact geometry
AGREE_TOL = 1e-6  # m: the two engines' answers for the same rays
SEED = 26
MASS = 2.0
G = 9.81


# Tests that need an engine feature; an engine that does not list it (DART: no ray casts,
# no headless renderer) skips them and refuses the request instead (the last test here).
NEEDS = {"test_depth_and_labels_at_known_pixels": "render",
         "test_segmentation_agrees_with_geometry_nearly_everywhere": "render",
         "test_rgb_shows_each_entitys_colour": "render",
         "test_png_carries_the_same_images": "render",
         "test_nothing_within_far_is_inf_and_unlabelled": "render",
         "test_several_cameras_in_one_request": "render",
         "test_named_cameras_persist_and_render": "render",
         "test_an_attached_camera_moves_with_its_body": "render",
         "test_rays_hit_where_the_geometry_is": "raycast",
         "test_rays_stop_at_their_ends_and_max_length": "raycast",
         "test_too_many_rays_is_refused_with_the_limit_named": "raycast",
         "test_a_ray_does_not_see_the_shape_it_starts_in": "raycast",
         "test_huge_and_tiny_ray_vectors_are_directions_or_refused": "raycast"}


def features(engine: str) -> tuple[str, ...]:
    made = create_engine(engine)
    try:
        return made.capabilities().features
    finally:
        made.close()


@pytest.fixture(autouse=True)
def needed_feature(request: pytest.FixtureRequest) -> None:
    feature = NEEDS.get(request.node.originalname)
    engine = getattr(request.node, "callspec", None) and request.node.callspec.params.get(
        "engine")
    if feature and engine and feature not in features(engine):
        pytest.skip(f"the {engine} engine lists no {feature!r} feature")


def test_an_engine_without_a_feature_refuses_it_and_keeps_serving(sim: Client) -> None:
    listed = sim.capabilities().features
    calls = {"render": lambda: sim.render(top_camera()),
             "raycast": lambda: sim.raycast([[0, 0, 1]], directions=[[0, 0, -1]])}
    missing = [f for f in calls if f not in listed]
    if not missing:
        pytest.skip("the engine lists every perception feature")
    for feature in missing:
        with pytest.raises(FeatureUnsupportedError):
            calls[feature]()
    assert sim.status().engine


@pytest.fixture
def scene(sim: Client) -> Iterator[Client]:
    known_scene(sim)
    yield sim


def rendered(sim: Client, **options: Any) -> Image:
    (image,) = sim.render(top_camera(**options))
    return image


def grown(mask: np.ndarray) -> np.ndarray:
    """The mask and its 8 neighbouring pixels."""
    out = mask.copy()
    padded = np.pad(mask, 1)
    for dr in (0, 1, 2):
        for dc in (0, 1, 2):
            out |= padded[dr:dr + mask.shape[0], dc:dc + mask.shape[1]]
    return out


# -- render ---------------------------------------------------------------------------------
def test_depth_and_labels_at_known_pixels(scene: Client) -> None:
    image = rendered(scene)
    assert image.depth is not None and image.segmentation is not None
    assert (image.width, image.height) == (WIDTH, ROWS)
    assert image.depth.shape == (ROWS, WIDTH) and image.depth.dtype == np.float32
    assert sorted(image.labels) == ["ball", "box", "ground"]
    for point in (np.add(BOX_CENTRE, [0, 0, BOX_HALF]), np.add(BALL_CENTRE, [0, 0, BALL_RADIUS]),
                  np.array([1.2, 0.8, 0.0]), np.array([-1.0, -0.6, 0.0])):
        pixel = pixel_of(point)
        name, depth = expected_depth(pixel)
        assert image.label_at(pixel.row, pixel.column) == name
        seen = float(image.depth[pixel.row, pixel.column])
        if name == "ball":
            assert depth - PLANE_DEPTH_TOL <= seen <= depth + BALL_DEPTH_TOL
        else:
            assert seen == pytest.approx(depth, abs=PLANE_DEPTH_TOL)


def test_segmentation_agrees_with_geometry_nearly_everywhere(scene: Client) -> None:
    image = rendered(scene)
    expected = np.array([[expected_depth(Pixel(r, c))[0] for c in range(WIDTH)]
                         for r in range(ROWS)])
    seen = np.array([[image.label_at(r, c) for c in range(WIDTH)] for r in range(ROWS)])
    assert np.mean(seen == expected) >= SAME_LABELS


def test_rgb_shows_each_entitys_colour(scene: Client) -> None:
    image = rendered(scene)
    assert image.rgb is not None and image.rgb.shape == (ROWS, WIDTH, 3)
    assert image.rgb.dtype == np.uint8
    box = image.rgb[image.mask("box")].mean(axis=0)
    ball = image.rgb[image.mask("ball")].mean(axis=0)
    ground = image.rgb[image.mask("ground")].mean(axis=0)
    assert box[0] > 100 and box[0] > 3 * max(box[1], box[2]), box
    assert ball[2] > 100 and ball[2] > 3 * max(ball[0], ball[1]), ball
    assert np.ptp(ground) < 10 and ground.mean() > 30, ground


def test_png_carries_the_same_images(scene: Client) -> None:
    raw = rendered(scene)
    (png,) = scene.render(top_camera(), format="png")
    assert raw.depth is not None and png.depth is not None
    assert np.array_equal(png.rgb, raw.rgb)
    assert np.array_equal(png.segmentation, raw.segmentation)
    assert np.allclose(png.depth, raw.depth, atol=0.5e-3 + 1e-6)


def test_nothing_within_far_is_inf_and_unlabelled(scene: Client) -> None:
    sky = scene.render(camera((0, 0, 1), (0, 0, 2), up=(0, 1, 0), size=(8, 6),
                              outputs=("depth", "segmentation")))[0]
    assert sky.rgb is None and sky.depth is not None and sky.segmentation is not None
    assert np.isinf(sky.depth).all() and (sky.segmentation == -1).all()
    near_only = rendered(scene, far=HEIGHT - 0.3)  # the ball's top (2.6 m) only
    assert near_only.depth is not None
    assert set(near_only.labels[i] for i in np.unique(near_only.segmentation) if i >= 0) \
        == {"ball"}
    # MuJoCo's depth and labels may differ on the silhouette's pixels
    assert np.isinf(near_only.depth[~grown(near_only.mask("ball"))]).all()


def test_several_cameras_in_one_request(scene: Client) -> None:
    small = camera((0, 0, HEIGHT), (0, 0, 0), up=(0, 1, 0), size=(16, 12), outputs="depth")
    first, second = scene.render([top_camera(), small])
    assert (second.width, second.height) == (16, 12) and second.rgb is None
    assert first.step == second.step


# -- named and attached cameras -------------------------------------------------------------
def test_named_cameras_persist_and_render(scene: Client) -> None:
    kept = scene.add_camera("top", top_camera())
    assert kept["width"] == WIDTH and kept["attach"] is None
    assert list(scene.cameras()) == ["top"]
    (image,) = scene.render({"camera": "top", "outputs": ["depth"]})
    assert image.rgb is None and image.depth is not None
    scene.remove_camera("top")
    assert scene.cameras() == {}
    with pytest.raises(NotFoundError, match="top"):
        scene.render({"camera": "top"})
    with pytest.raises(NotFoundError):
        scene.remove_camera("top")


def test_an_attached_camera_moves_with_its_body(sim: Client) -> None:
    sim.spawn(plane())
    sim.spawn(boxes(["cart"], [[0, 0, 0.05]], [0.05] * 3, restitution=0.0))
    looking_down = camera((0, 0, 0.5), (0, 0, 0), up=(0, 1, 0), size=(9, 9), fov=20,
                          outputs=("depth", "segmentation"), attach="cart")
    sim.add_camera("rider", looking_down)
    world_fixed = camera((0, 0, 0.55), (0, 0, 0), up=(0, 1, 0), size=(9, 9), fov=20,
                         outputs=("segmentation",))
    before = sim.render({"camera": "rider"})[0]
    assert before.label_at(4, 4) == "cart"
    poses = sim.get_states(["cart"]).poses
    poses[0, :2] = [2.0, -1.0]
    sim.set_states(["cart"], poses)
    after, fixed = sim.render([{"camera": "rider"}, world_fixed])
    assert after.label_at(4, 4) == "cart" and fixed.label_at(4, 4) == "ground"
    assert after.depth is not None and before.depth is not None
    assert after.depth[4, 4] == pytest.approx(before.depth[4, 4], abs=PLANE_DEPTH_TOL)
    assert sim.cameras()["rider"]["attach"] == "cart"


# -- raycast --------------------------------------------------------------------------------
# origin, direction, then the expected entity, point, normal (None: a miss)
RAYS: list[tuple[list[float], list[float], str | None, list[float], list[float]]] = [
    ([0.5, 0.0, 1.0], [0, 0, -1], "box", [0.5, 0.0, 0.2], [0, 0, 1]),
    ([0.0, 0.0, 0.1], [1, 0, 0], "box", [0.4, 0.0, 0.1], [-1, 0, 0]),
    ([-0.5, 0.0, 1.0], [0, 0, -2], "ball", [-0.5, 0.0, 0.4], [0, 0, 1]),
    ([-1.5, 0.0, 0.2], [1, 0, 0], "ball", [-0.7, 0.0, 0.2], [-1, 0, 0]),
    ([2.0, 1.0, 1.0], [0, 0, -1], "ground", [2.0, 1.0, 0.0], [0, 0, 1]),
    ([0.0, 0.0, 1.0], [0, 0, 1], None, [], []),
]


def test_rays_hit_where_the_geometry_is(scene: Client) -> None:
    hits = scene.raycast([r[0] for r in RAYS], directions=[r[1] for r in RAYS])
    assert len(hits) == len(RAYS)
    for i, (origin, _, entity, point, normal) in enumerate(RAYS):
        if entity is None:
            assert not hits.hits[i] and hits.entities[i] == ""
            assert np.isnan(hits.points[i]).all() and np.isnan(hits.distances[i])
            continue
        assert hits.hits[i] and hits.entities[i] == entity
        assert hits.points[i] == pytest.approx(point, abs=RAY_TOL)
        assert hits.normals[i] == pytest.approx(normal, abs=RAY_TOL)
        assert hits.distances[i] == pytest.approx(math.dist(origin, point), abs=RAY_TOL)


def test_a_ray_does_not_see_the_shape_it_starts_in(scene: Client) -> None:
    """From inside the ball it goes on to the box; from inside the box, to nothing."""
    inside_ball = BALL_CENTRE - np.array([0, 0, BALL_RADIUS / 2])  # level with the box's middle
    hits = scene.raycast([inside_ball, BOX_CENTRE], directions=[[1, 0, 0], [0, 0, 1]])
    assert hits.entities == ["box", ""]
    face = BOX_CENTRE[0] - BOX_HALF
    assert hits.distances[0] == pytest.approx(face - inside_ball[0], abs=RAY_TOL)
    assert hits.normals[0] == pytest.approx([-1, 0, 0], abs=RAY_TOL)
    pip = BALL_CENTRE + np.array([0.1, 0, 0])  # a bead inside the ball is seen from in there
    scene.spawn(spheres(["pip"], [pip], 0.03, static=True))
    starts = BALL_CENTRE + np.random.default_rng(SEED).uniform(-0.05, 0.05, (20, 3))
    nested = scene.raycast(starts, directions=pip - starts)
    assert nested.entities == ["pip"] * 20
    np.testing.assert_allclose(nested.distances, np.linalg.norm(pip - starts, axis=1) - 0.03,
                               atol=RAY_TOL)


def test_rays_stop_at_their_ends_and_max_length(scene: Client) -> None:
    short = scene.raycast([[2, 0, 1]], directions=[[0, 0, -1]], max_length=0.5)
    assert not short.hits[0]
    ends = scene.raycast([[2, 0, 1], [2, 0, 1]], ends=[[2, 0, 0.5], [2, 0, -1]])
    assert ends.hits.tolist() == [False, True]
    assert ends.distances[1] == pytest.approx(1.0, abs=RAY_TOL)


def random_rays(count: int) -> tuple[np.ndarray, np.ndarray]:
    """Seeded rays from above the scene towards points about its bodies."""
    rng = np.random.default_rng(SEED)
    origins = rng.uniform([-1.5, -1.0, 0.5], [1.5, 1.0, 2.0], (count, 3))
    targets = rng.uniform([-1.0, -0.4, -0.1], [1.0, 0.4, 0.4], (count, 3))
    return origins, targets - origins


def test_both_engines_answer_the_same_rays(daemons: dict[str, EmbeddedDaemon]) -> None:
    origins, directions = random_rays(500)
    answers = []
    for engine in ("mujoco", "pybullet"):
        daemon = start_daemon(daemons, engine)
        with Client(daemon.instance, daemon.endpoint, timeout=20.0) as sim:
            sim.load_world(engine)
            known_scene(sim)
            answers.append(sim.raycast(origins, directions=directions))
    first, second = answers
    assert first.entities == second.entities
    assert np.array_equal(first.hits, second.hits) and first.hits.sum() > 400
    hit = first.hits
    assert np.abs(first.points[hit] - second.points[hit]).max() <= AGREE_TOL
    assert np.abs(first.distances[hit] - second.distances[hit]).max() <= AGREE_TOL
    assert np.abs(first.normals[hit] - second.normals[hit]).max() <= AGREE_TOL


# -- contacts -------------------------------------------------------------------------------
def test_a_resting_box_rests_on_its_contacts(sim: Client) -> None:
    params = sim.capabilities().params
    if "ode.auto_disable" in params:  # a sleeping body has no contacts
        sim.set_params({"ode.auto_disable": False})
    if "mujoco.sleep_tolerance" in params:  # ... or the forces of the step it fell asleep at
        sim.set_params({"mujoco.sleep_tolerance": 0.0})
    sim.spawn(plane(restitution=0.0))
    sim.spawn(boxes(["box"], [[0, 0, 0.1]], [0.1] * 3, mass=MASS, restitution=0.0))
    sim.spawn(boxes(["other"], [[1, 0, 0.1]], [0.1] * 3, restitution=0.0))
    sim.step(500)
    found = sim.contacts(["box"])
    assert len(found) >= 3 and set(found.a + found.b) == {"box", "ground"}
    assert found.forces.sum() == pytest.approx(MASS * G, rel=0.01)
    up = np.array([0.0, 0.0, 1.0])
    for a, normal, position in zip(found.a, found.normals, found.positions, strict=True):
        assert normal @ (up if a == "ground" else -up) == pytest.approx(1.0, abs=1e-6)
        assert abs(position[2]) < 1e-3
    assert (found.penetrations >= 0).all() and (found.penetrations < 1e-3).all()
    assert len(sim.contacts()) > len(found)
    with pytest.raises(NotFoundError):
        sim.contacts(["nobody"])


# -- bad input: typed errors, nothing changed ------------------------------------------------
BAD_CAMERAS: list[tuple[Callable[[dict[str, Any]], None], str]] = [
    (lambda c: c.update(width=0), "width"),
    (lambda c: c.update(height=9000), "height"),
    (lambda c: c.update(eye=[math.nan, 0, 3]), "eye"),
    (lambda c: c.update(target=[0, math.inf, 0]), "target"),
    (lambda c: c.update(fov=0.0), "fov"),
    (lambda c: c.update(fov=200.0), "fov"),
    (lambda c: c.update(near=2.0, far=1.0), "far"),
    (lambda c: c.update(up=[0, 0, 1]), "up"),
    (lambda c: c.update(outputs=["infrared"]), "outputs"),
    (lambda c: c.update(attach="nobody"), "nobody"),
]


@pytest.mark.parametrize(("spoil", "named"), BAD_CAMERAS, ids=[b[1] for b in BAD_CAMERAS])
def test_a_bad_camera_is_refused_naming_its_field(
        scene: Client, spoil: Callable[[dict[str, Any]], None], named: str) -> None:
    bad = top_camera()
    spoil(bad)
    before = scene.status().step
    error = NotFoundError if named == "nobody" else InvalidArgumentError
    with pytest.raises(error, match=named):
        scene.render(bad)
    with pytest.raises(error, match=named):
        scene.add_camera("bad", bad)
    assert scene.cameras() == {} and scene.status().step == before


def test_too_many_pixels_is_a_resource_limit(scene: Client) -> None:
    huge = camera((0, 0, 3), (0, 0, 0), up=(0, 1, 0), size=(4096, 4096))
    with pytest.raises(ResourceLimitError, match="pixels") as refused:
        scene.render([huge, huge])
    assert refused.value.details["limit"] == "max_pixels"
    assert refused.value.details["max"] == DEFAULT_LIMITS.max_pixels


def test_a_render_that_would_hold_the_physics_thread_too_long_is_refused_saying_what_fits(
        scene: Client) -> None:
    """Issue 46: one render at max_pixels held a playing world 2.6-9.4 s. In a fresh world
    a render is costed at 10 Mpixel/s until one is measured: a full-HD frame (about 0.2 s)
    is refused naming the pixels that fit max_render_seconds, and that many render."""
    if "render" not in scene.capabilities().features:
        pytest.skip("this engine does not render")
    frame = camera((0, 0, 3), (0, 0, 0), up=(0, 1, 0), size=(1920, 1080))
    before = scene.status().step
    with pytest.raises(ResourceLimitError, match="max_render_seconds") as refused:
        scene.render(frame)
    details = refused.value.details
    assert details["limit"] == "max_render_seconds"
    assert details["max"] == DEFAULT_LIMITS.max_render_seconds
    fits = details["pixels"]
    assert 65_536 <= fits < 1920 * 1080
    side = math.isqrt(fits)
    (image,) = scene.render(camera((0, 0, 3), (0, 0, 0), up=(0, 1, 0), size=(side, side)))
    assert image.rgb is not None and image.rgb.shape[:2] == (side, side)
    assert scene.status().step == before


def test_bad_rays_are_refused(scene: Client) -> None:
    with pytest.raises(InvalidArgumentError, match="zero"):
        scene.raycast([[0, 0, 1]], directions=[[0, 0, 0]])
    with pytest.raises(InvalidArgumentError, match="origins"):
        scene.raycast([[0, math.nan, 1]], directions=[[0, 0, -1]])
    with pytest.raises(InvalidArgumentError, match="max_length"):
        scene.raycast([[0, 0, 1]], directions=[[0, 0, -1]], max_length=-1.0)
    with pytest.raises(InvalidArgumentError, match="exactly one"):
        scene.call("raycast", {"origins": np.zeros(3).tobytes()}).raise_for_code()


FAR = r"too far from its origin|position limit"


def test_huge_and_tiny_ray_vectors_are_directions_or_refused(scene: Client) -> None:
    """A direction's length does not matter, however far from 1: its norm once overflowed
    to inf, the ray became zero, and MuJoCo's mj_ray aborted the daemon."""
    origins = [[2.0, 0.0, 1.0]] * 3
    down = scene.raycast(origins, directions=[[0, 0, -1]] * 3)
    scaled = scene.raycast(origins, directions=[[0, 0, -1e300], [1e-300, 0, -1e300],
                                                [0, 0, -1e-6]])
    np.testing.assert_array_equal(scaled.hits, down.hits)
    np.testing.assert_allclose(scaled.distances, down.distances, atol=RAY_TOL)
    with pytest.raises(InvalidArgumentError, match="zero direction"):
        scene.raycast([[0, 0, 1]], directions=[[0, 0, -1e-200]])  # shorter than 1e-12
    # Ends past the protocol's bound on coordinates (docs/protocol.md, "Bounds").
    with pytest.raises(InvalidArgumentError, match=FAR):
        scene.raycast([[0, 0, -1e308]], ends=[[0, 0, 1e308]])
    with pytest.raises(InvalidArgumentError, match=FAR):
        scene.raycast([[0, 0, 0]], ends=[[1.5e308, 1.5e308, 1.5e308]])  # its length: inf
    assert scene.status().entity_count == 3 and not scene.status().faulted  # still serving


def test_too_many_rays_is_refused_with_the_limit_named(engine: str) -> None:
    with EmbeddedDaemon(engine, instance=f"test-{engine}-rays",
                        extra_args=["--limit", "max_rays=100"]) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=20.0) as sim:
        wait_for_daemon(sim.session, daemon.instance, 60.0)
        known_scene(sim)
        down = np.tile([0.0, 0.0, -1.0], (101, 1))
        starts = np.tile([2.0, 0.0, 1.0], (101, 1))
        assert sim.raycast(starts[:100], directions=down[:100]).hits.all()
        with pytest.raises(ResourceLimitError, match="at most 100") as refused:
            sim.raycast(starts, directions=down)
        assert refused.value.details == {"limit": "max_rays", "max": 100}
