"""A minimal PNG writer (zlib from the standard library): images go out compressed on
request without the daemon needing an imaging library."""

from __future__ import annotations

import struct
import zlib

import numpy as np

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def encode_png(image: np.ndarray) -> bytes:
    """(h, w, 3) uint8 as 8-bit RGB, or (h, w) uint16 as 16-bit greyscale, top row first."""
    if image.ndim == 3 and image.dtype == np.uint8 and image.shape[2] == 3:
        depth, colour, rows = 8, 2, image
    elif image.ndim == 2 and image.dtype == np.uint16:
        depth, colour, rows = 16, 0, image.astype(">u2")
    else:
        raise ValueError(f"cannot write a PNG of {image.dtype} {image.shape}")
    height, width = image.shape[:2]
    raw = np.ascontiguousarray(rows).reshape(height, -1).view(np.uint8)
    filtered = np.hstack([np.zeros((height, 1), np.uint8), raw]).tobytes()
    header = struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0)
    return (SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(filtered, 6))
            + _chunk(b"IEND", b""))
