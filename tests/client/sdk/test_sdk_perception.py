"""The SDK's perception against real daemons: images come back as numpy arrays (raw or
PNG, the same pixels), one camera map or several, named cameras, rays from one row or many,
contacts; the camera() builder; the client's PNG reader against every row filter; and
client-side refusals that send nothing."""

from __future__ import annotations

import io
import zlib
from collections.abc import Iterator

import numpy as np
import pytest
from support.perception import ALL_OUTPUTS, known_scene, skip_without, top_camera

from galton.client import (
    Client,
    Contacts,
    Image,
    InvalidArgumentError,
    OperationFailedError,
    RayHits,
    boxes,
    camera,
    plane,
)
from galton.protocol.png import SIGNATURE, chunk, decode_png, encode_png

SEED = 26


@pytest.fixture
def scene(sim: Client) -> Iterator[Client]:
    known_scene(sim)
    yield sim


def test_camera_builds_a_camera_map() -> None:
    made = camera((0, 0, 2), np.zeros(3), up=(0, 1, 0), fov=30, size=(64, 48), near=0.1,
                  far=10, outputs="depth", attach="arm")
    assert made == {"eye": [0.0, 0.0, 2.0], "target": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
                    "width": 64, "height": 48, "fov": 30.0, "near": 0.1, "far": 10.0,
                    "outputs": ["depth"], "attach": "arm"}
    assert camera((1, 2, 3), (0, 0, 0)) == {"eye": [1.0, 2.0, 3.0], "target": [0.0] * 3}
    with pytest.raises(InvalidArgumentError, match="eye"):
        camera((0, 0), (0, 0, 0))


def test_render_returns_numpy_images(scene: Client) -> None:
    skip_without(scene, "render")
    (image,) = scene.render(top_camera())
    assert isinstance(image, Image)
    assert image.rgb is not None and image.rgb.shape == (48, 64, 3)
    assert image.rgb.dtype == np.uint8 and image.rgb.flags.writeable
    assert image.depth is not None and image.depth.dtype == np.float32
    assert image.segmentation is not None and image.segmentation.dtype == np.int32
    assert (image.step, image.sim_time) == (scene.status().step, scene.status().sim_time)
    assert image.mask("box").any() and not image.mask("nobody").any()
    row, column = np.argwhere(image.mask("ball"))[0]
    assert image.label_at(int(row), int(column)) == "ball"
    only_rgb = scene.render([camera((0, 0, 3), (0, 0, 0), up=(0, 1, 0), size=(8, 6))])[0]
    assert only_rgb.depth is None and only_rgb.segmentation is None
    with pytest.raises(OperationFailedError, match="segmentation"):
        only_rgb.label_at(0, 0)


def test_png_gives_the_raw_pixels(scene: Client) -> None:
    skip_without(scene, "render")
    raw, = scene.render(top_camera())
    png, = scene.render(top_camera(), format="png")
    assert png.rgb is not None and raw.depth is not None and png.depth is not None
    assert np.array_equal(png.rgb, raw.rgb) and png.rgb.dtype == np.uint8
    assert np.array_equal(png.segmentation, raw.segmentation)
    finite = np.isfinite(raw.depth)
    assert np.array_equal(np.isfinite(png.depth), finite)
    assert np.abs(png.depth[finite] - raw.depth[finite]).max() <= 0.5e-3 + 1e-6


def test_named_cameras_round_trip(scene: Client) -> None:
    skip_without(scene, "render")
    kept = scene.add_camera("top", camera((0, 0, 3), (0, 0, 0), up=(0, 1, 0)))
    assert (kept["width"], kept["height"], kept["fov"], kept["outputs"]) == (
        320, 240, 45.0, ["rgb"])
    assert scene.cameras() == {"top": kept}
    (image,) = scene.render({"camera": "top", "outputs": list(ALL_OUTPUTS)})
    assert image.depth is not None and (image.width, image.height) == (320, 240)
    scene.remove_camera("top")
    assert scene.cameras() == {}


def test_raycast_takes_one_row_or_many(scene: Client) -> None:
    skip_without(scene, "raycast")
    one = scene.raycast([0.5, 0, 1], directions=[0, 0, -1])
    assert isinstance(one, RayHits) and len(one) == 1 and one.entities == ["box"]
    rng = np.random.default_rng(SEED)
    origins = np.column_stack([rng.uniform(-2, 2, (50, 2)), np.full(50, 1.5)])
    many = scene.raycast(origins, ends=origins - [0, 0, 3])
    assert many.hits.all() and many.points.shape == (50, 3)
    assert many.distances == pytest.approx(1.5 - many.points[:, 2])


def test_contacts_are_arrays(sim: Client) -> None:
    sim.spawn(plane(restitution=0.0))
    sim.spawn(boxes(["box"], [[0, 0, 0.1]], [0.1] * 3, restitution=0.0))
    assert len(sim.contacts()) == 0  # nothing stepped yet
    sim.step(50)
    found = sim.contacts("box")
    assert isinstance(found, Contacts) and len(found) > 0
    assert found.positions.shape == found.normals.shape == (len(found), 3)
    assert found.between("box", "ground").all() and not found.between("box", "box").any()


@pytest.mark.parametrize(("call", "message"), [
    (lambda c: c.render(top_camera(), format="jpeg"), "render.format .jpeg. is not one of"),
    (lambda c: c.raycast([0, 0, 1]), "exactly one"),
    (lambda c: c.raycast([0, 0, 1], directions=[0, 0, 1], ends=[0, 0, 2]), "exactly one"),
    (lambda c: c.raycast([[0, 0]], directions=[[0, 0, 1]]), "origins"),
    (lambda c: c.raycast([0, 0, 1], directions=np.zeros((1, 2, 3))), "directions"),
])
def test_client_side_refusals_send_nothing(mujoco_sim: Client, call: object,
                                           message: str) -> None:
    before = mujoco_sim.status().step
    with pytest.raises(InvalidArgumentError, match=message):
        call(mujoco_sim)  # type: ignore[operator]
    assert mujoco_sim.status().step == before


# -- the PNG reader -----------------------------------------------------------------------
def filtered_png(image: np.ndarray, filters: list[int]) -> bytes:
    """A PNG of ``image`` whose row i uses row filter ``filters[i]`` (written by hand)."""
    grey = image.ndim == 2
    rows = (image.astype(">u2") if grey else image).reshape(image.shape[0], -1).view(np.uint8)
    bpp = 2 if grey else 3
    lines, previous = [], np.zeros(rows.shape[1], np.int64)
    for kind, row in zip(filters, rows.astype(np.int64), strict=True):
        left = np.concatenate([np.zeros(bpp, np.int64), row[:-bpp]])
        corner = np.concatenate([np.zeros(bpp, np.int64), previous[:-bpp]])
        guess = [np.zeros_like(row), left, previous, (left + previous) // 2,
                 paeth(left, previous, corner)][kind]
        lines.append(bytes([kind]) + ((row - guess) % 256).astype(np.uint8).tobytes())
        previous = row
    header = np.array([image.shape[1], image.shape[0]], ">u4").tobytes() + bytes(
        [16 if grey else 8, 0 if grey else 2, 0, 0, 0])
    return (SIGNATURE + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(b"".join(lines))) + chunk(b"IEND", b""))


def paeth(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    p = a + b - c
    pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
    return np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))


@pytest.mark.parametrize("grey", [False, True], ids=["rgb8", "grey16"])
def test_the_png_reader_undoes_every_row_filter(grey: bool) -> None:
    rng = np.random.default_rng(SEED)
    image = (rng.integers(0, 65536, (10, 7), dtype=np.uint16) if grey
             else rng.integers(0, 256, (10, 7, 3), dtype=np.uint8))
    decoded = decode_png(filtered_png(image, [0, 1, 2, 3, 4, 4, 3, 2, 1, 0]))
    assert decoded.dtype == image.dtype and np.array_equal(decoded, image)
    assert np.array_equal(decode_png(encode_png(image)), image)


def test_the_png_writer_is_read_by_an_imaging_library() -> None:
    pil = pytest.importorskip("PIL.Image")
    rng = np.random.default_rng(SEED)
    image = rng.integers(0, 256, (9, 11, 3), dtype=np.uint8)
    assert np.array_equal(np.asarray(pil.open(io.BytesIO(encode_png(image)))), image)
    out = io.BytesIO()
    pil.fromarray(image).save(out, format="PNG", optimize=True)
    assert np.array_equal(decode_png(out.getvalue()), image)


def test_the_png_reader_refuses_what_is_not_a_png() -> None:
    with pytest.raises(OperationFailedError, match="signature"):
        decode_png(b"GIF89a")
