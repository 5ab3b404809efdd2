"""docs/img/view.png, the README's picture of the live view, is a real picture of it (made
by docs/make_view_png.py through the view's browser path): not blank, the balls drawn in
the scene and the operator's blue buttons in the panel."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

PICTURE = Path(__file__).resolve().parents[3] / "docs" / "img" / "view.png"
PANEL_LEFT = 0.7  # viser's panel covers the page right of this at 1200 px
MIN_BALL_PIXELS = 200
MIN_BUTTON_PIXELS = 2000  # five buttons of about 280 x 25 px


def _picture() -> np.ndarray:
    image = pytest.importorskip("PIL.Image")
    return np.asarray(image.open(PICTURE).convert("RGB")).astype(int)


def test_the_view_picture_shows_the_scene_and_the_panel() -> None:
    picture = _picture()
    assert picture.shape == (800, 1200, 3)
    assert picture.std() > 10, "docs/img/view.png is blank"
    split = int(PANEL_LEFT * picture.shape[1])
    scene, panel = picture[:, :split], picture[:, split:]
    red, green, blue = scene[..., 0], scene[..., 1], scene[..., 2]
    balls = (red > 120) & (green < 90) & (blue < 90)
    assert balls.sum() > MIN_BALL_PIXELS, "no balls drawn in the scene"
    red, green, blue = panel[..., 0], panel[..., 1], panel[..., 2]
    buttons = (blue > 180) & (red < 80) & (green > 100) & (green < 170)
    assert buttons.sum() > MIN_BUTTON_PIXELS, "no operator buttons drawn in the panel"
