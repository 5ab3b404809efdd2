"""The Galton board's materials as an engine's world defaults, for tests of the calibration.

A fresh world runs its engine's own contact defaults (tests/test_neutral_world.py); the
board brings its calibrated materials on its bodies (client/boards). Tests that measure
that calibration on hand-made scenes set it as the world's defaults with these.
"""

from __future__ import annotations

from typing import Any

from galton.analysis.board import BoardSpec


def board_defaults(engine: str) -> dict[str, Any]:
    """The paper board's settings on this engine, with its balls' surface as the moving
    bodies' default and its floor's as the static bodies'."""
    contacts = BoardSpec.load("paper").contacts[engine]
    ball, floor = contacts.bodies["ball"], contacts.bodies["floor"]
    return {**contacts.params, "default_friction": ball.friction,
            "default_restitution": ball.restitution, "default_static_friction": floor.friction,
            "default_static_restitution": floor.restitution}
