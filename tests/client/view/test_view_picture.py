"""docs/img/view.png, the README's picture of the live view, is a real picture of it (made
by docs/make_view_png.py through the view's browser path): not blank, the balls drawn in
the scene and the operator's blue buttons in the panel, no notice over the scene; and the
script that makes it runs on the tests' browser driver, taking the picture only once it
shows what this test looks for."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from support.browser import Browser

ROOT = Path(__file__).resolve().parents[3]
PICTURE = ROOT / "docs" / "img" / "view.png"
MAKER = ROOT / "docs" / "make_view_png.py"
PANEL_LEFT = 0.7  # viser's panel covers the page right of this at 1200 px
MIN_BALL_PIXELS = 200
MIN_BUTTON_PIXELS = 2000  # five buttons of about 280 x 25 px
NOTICE_CORNER = (slice(0, 200), slice(0, 400))  # where viser's notices appear
MAX_NOTICE_PIXELS = 50  # the orange stripe of its "Software WebGL rendering detected"


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
    corner = picture[NOTICE_CORNER]
    red, green, blue = corner[..., 0], corner[..., 1], corner[..., 2]
    stripe = (red > 230) & (green > 100) & (green < 160) & (blue < 60)
    assert stripe.sum() < MAX_NOTICE_PIXELS, "a notice (software WebGL) hides the scene"


def _maker() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_view_png", MAKER)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_picture_is_made_on_the_tests_browser_once_scene_and_panel_are_drawn() -> None:
    """The script drives the browser the view's ten-load test drives (DevTools, one page)
    and keeps the first screenshot in which the balls and the panel's buttons are drawn:
    the picture here passes that check, a blank or panel-less page does not."""
    maker = _maker()
    assert maker.Browser is Browser
    picture = _picture()
    assert maker.drawn(picture)
    assert not maker.drawn(np.full_like(picture, 255))
    without_panel = picture.copy()
    without_panel[:, int(maker.PANEL_LEFT * picture.shape[1]):] = 255
    assert not maker.drawn(without_panel)


@pytest.mark.slow  # software WebGL: a minute or more (-m slow)
def test_the_script_makes_a_picture_that_passes(tmp_path: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "view.png"
    subprocess.run([sys.executable, str(MAKER), "--out", str(out)], check=True, timeout=900,
                   capture_output=True)
    monkeypatch.setattr(sys.modules[__name__], "PICTURE", out)
    test_the_view_picture_shows_the_scene_and_the_panel()
