"""Colours of bodies by tag: a tag that names a colour is that colour, any other tag a
stable colour of its own, and an untagged body the default (static ones grey)."""

from __future__ import annotations

import zlib
from collections.abc import Sequence

Rgb = tuple[int, int, int]

NAMED: dict[str, Rgb] = {
    "red": (220, 30, 30), "green": (40, 170, 60), "blue": (40, 90, 220),
    "yellow": (235, 200, 30), "orange": (240, 130, 20), "purple": (140, 60, 190),
    "cyan": (30, 190, 200), "magenta": (210, 40, 170), "white": (240, 240, 240),
    "black": (30, 30, 30), "grey": (150, 150, 150), "gray": (150, 150, 150),
    "ball": (220, 30, 30),  # the bench's balls, red as in its pictures
}
# Tags with no colour name get one of these, by a hash of the tag (the same every run).
CYCLE: tuple[Rgb, ...] = ((31, 119, 180), (255, 127, 14), (44, 160, 44), (148, 103, 189),
                          (140, 86, 75), (227, 119, 194), (188, 189, 34), (23, 190, 207))
DYNAMIC: Rgb = (90, 140, 200)
STATIC: Rgb = (170, 170, 175)


def colour_of(tags: Sequence[str], static: bool) -> Rgb:
    """The first tag that names a colour, else the first tag's hashed colour, else the
    default for a static or a moving body."""
    for tag in tags:
        if tag.lower() in NAMED:
            return NAMED[tag.lower()]
    if tags:
        return CYCLE[zlib.crc32(tags[0].encode()) % len(CYCLE)]
    return STATIC if static else DYNAMIC


GLASS_TAGS = frozenset({"glass"})  # the board's front pane: seen through, as in its pictures
GLASS_OPACITY = 0.15


def opacity_of(tags: Sequence[str]) -> float | None:
    """How opaque a body is drawn: a glass one faintly, any other fully (None)."""
    return GLASS_OPACITY if GLASS_TAGS.intersection(tags) else None
