"""A known scene for perception tests, and where its surfaces are, computed by hand: a grey
ground plane at z = 0, a static red box and a static blue ball at known places, and a
camera straight down from a known height whose pixels' rays are intersected analytically."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from galton.client import Client, boxes, camera, plane, spheres

GREY = (0.5, 0.5, 0.5, 1.0)
RED = (1.0, 0.0, 0.0, 1.0)
BLUE = (0.0, 0.0, 1.0, 1.0)
BOX_CENTRE = np.array([0.5, 0.0, 0.1])
BOX_HALF = 0.1
BALL_CENTRE = np.array([-0.5, 0.0, 0.2])
BALL_RADIUS = 0.2
HEIGHT = 3.0  # the top camera's eye, straight above the origin
WIDTH, ROWS, FOV = 64, 48, 60.0
ALL_OUTPUTS = ("rgb", "depth", "segmentation")


def known_scene(sim: Client) -> None:
    sim.spawn(plane(rgba=GREY))
    sim.spawn(boxes(["box"], [BOX_CENTRE], [BOX_HALF] * 3, static=True, rgba=RED))
    sim.spawn(spheres(["ball"], [BALL_CENTRE], BALL_RADIUS, static=True, rgba=BLUE))


def top_camera(**options: object) -> dict[str, object]:
    """Straight down from HEIGHT: +x is to the right of the image, +y up (towards row 0)."""
    return camera((0, 0, HEIGHT), (0, 0, 0), up=(0, 1, 0), fov=FOV, size=(WIDTH, ROWS),
                  outputs=ALL_OUTPUTS, **options)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Pixel:
    row: int
    column: int

    def ray(self) -> np.ndarray:
        """The unit direction of the top camera's ray through this pixel's centre."""
        focal = (ROWS / 2) / math.tan(math.radians(FOV / 2))
        x = (self.column + 0.5 - WIDTH / 2) / focal
        y = (ROWS / 2 - self.row - 0.5) / focal
        direction = np.array([x, y, -1.0])
        unit: np.ndarray = direction / np.linalg.norm(direction)
        return unit


def pixel_of(point: np.ndarray) -> Pixel:
    """The top camera's pixel that sees a world point."""
    focal = (ROWS / 2) / math.tan(math.radians(FOV / 2))
    scale = focal / (HEIGHT - point[2])
    return Pixel(int(ROWS / 2 - point[1] * scale), int(WIDTH / 2 + point[0] * scale))


def expected_depth(pixel: Pixel) -> tuple[str, float]:
    """What the pixel sees first and its depth along the view axis (-z), by hand."""
    eye, ray = np.array([0.0, 0.0, HEIGHT]), pixel.ray()
    found = [("ground", HEIGHT / -ray[2])]
    top = (HEIGHT - 2 * BOX_HALF) / -ray[2]
    hit = eye + top * ray
    if np.all(np.abs(hit[:2] - BOX_CENTRE[:2]) <= BOX_HALF):
        found.append(("box", top))
    offset = eye - BALL_CENTRE
    b, c = float(offset @ ray), float(offset @ offset) - BALL_RADIUS ** 2
    if b * b - c >= 0:
        found.append(("ball", -b - math.sqrt(b * b - c)))
    name, distance = min(found, key=lambda item: item[1])
    return name, distance * -ray[2]


def skip_without(sim: Client, feature: str) -> None:
    """Skip a test of ``feature`` on an engine that does not list it (DART has no ray casts
    and no headless renderer; tests/conformance/test_perception.py checks the refusal)."""
    if feature not in sim.capabilities().features:
        pytest.skip(f"the {sim.status().engine} engine lists no {feature!r} feature")
