"""The PNG images of the wire protocol (``render`` with ``format="png"``): a small reader and
writer on zlib from the standard library (8-bit RGB and 16-bit greyscale, non-interlaced,
every row filter on reading). The daemon writes them, the SDK reads them, and the CLI and
the bench write pictures, so neither side needs an imaging library."""

from __future__ import annotations

import struct
import zlib

import numpy as np

from galton.protocol.errors import OperationFailedError

SIGNATURE = b"\x89PNG\r\n\x1a\n"
# colour type -> channels: 0 greyscale, 2 RGB, 4 grey + alpha, 6 RGBA
_CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}


def decode_png(data: bytes) -> np.ndarray:
    """The image a PNG holds: (h, w) for greyscale, (h, w, c) otherwise; uint8 or uint16."""
    if not data.startswith(SIGNATURE):
        raise OperationFailedError("not a PNG: the signature is missing")
    header, idat = _chunks(data)
    width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", header)
    if depth not in (8, 16) or colour not in _CHANNELS or interlace:
        raise OperationFailedError(f"cannot read a PNG of bit depth {depth}, colour type "
                                   f"{colour}, interlace {interlace}")
    channels = _CHANNELS[colour]
    pixel_bytes = channels * depth // 8
    rows = _unfilter(zlib.decompress(idat), height, width * pixel_bytes, pixel_bytes)
    dtype = np.dtype(np.uint8) if depth == 8 else np.dtype(">u2")
    image = rows.view(dtype).astype(dtype.newbyteorder("=")).reshape(height, width, channels)
    return image[:, :, 0] if channels == 1 else image


def _chunks(data: bytes) -> tuple[bytes, bytes]:
    """The IHDR payload and every IDAT payload joined."""
    at, header, idat = len(SIGNATURE), b"", bytearray()
    while at + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        payload = data[at + 8:at + 8 + length]
        if kind == b"IHDR":
            header = payload
        elif kind == b"IDAT":
            idat += payload
        elif kind == b"IEND":
            break
        at += 12 + length
    if len(header) != 13:
        raise OperationFailedError("not a PNG: no IHDR chunk")
    return header, bytes(idat)


def _unfilter(raw: bytes, height: int, stride: int, bpp: int) -> np.ndarray:
    """Undo each row's filter (None, Sub, Up, Average, Paeth)."""
    lines = np.frombuffer(raw, np.uint8)
    if lines.size != height * (stride + 1):
        raise OperationFailedError(f"a PNG's data holds {lines.size} bytes, expected "
                                   f"{height * (stride + 1)}")
    lines = lines.reshape(height, stride + 1)
    out = np.zeros((height, stride), np.uint8)
    previous = np.zeros(stride, np.uint8)
    for y in range(height):
        out[y] = _row(int(lines[y, 0]), lines[y, 1:], previous, bpp)
        previous = out[y]
    return out


def _row(kind: int, line: np.ndarray, up: np.ndarray, bpp: int) -> np.ndarray:
    if kind == 0:
        return line
    if kind == 2:
        summed: np.ndarray = line + up  # uint8 arithmetic wraps, as the filter means
        return summed
    if kind == 1:  # Sub: a running sum per byte of a pixel
        width = line.size // bpp
        sums = np.cumsum(line.reshape(width, bpp).astype(np.int64), axis=0) % 256
        return sums.astype(np.uint8).reshape(-1)
    out = np.zeros_like(line)
    for x in range(line.size):
        left = int(out[x - bpp]) if x >= bpp else 0
        above, corner = int(up[x]), int(up[x - bpp]) if x >= bpp else 0
        guess = (left + above) // 2 if kind == 3 else _paeth(left, above, corner)
        out[x] = (int(line[x]) + guess) & 0xFF
    return out


def _paeth(a: int, b: int, c: int) -> int:
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def chunk(kind: bytes, data: bytes) -> bytes:
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def encode_png(image: np.ndarray) -> bytes:
    """(h, w, 3) uint8 as 8-bit RGB, or (h, w) uint16 as 16-bit greyscale, top row first
    (rows unfiltered: what the CLI and the bench write to files)."""
    if image.ndim == 3 and image.dtype == np.uint8 and image.shape[2] == 3:
        depth, colour, rows = 8, 2, image
    elif image.ndim == 2 and image.dtype == np.uint16:
        depth, colour, rows = 16, 0, image.astype(">u2")
    else:
        raise OperationFailedError(f"cannot write a PNG of {image.dtype} {image.shape}")
    height, width = image.shape[:2]
    raw = np.ascontiguousarray(rows).reshape(height, -1).view(np.uint8)
    filtered = np.hstack([np.zeros((height, 1), np.uint8), raw]).tobytes()
    header = struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, 0)
    return (SIGNATURE + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(filtered, 6))
            + chunk(b"IEND", b""))


def depth_png(depth: np.ndarray) -> bytes:
    """Depth in metres as a 16-bit PNG of millimetres (0: nothing, or past 65.535 m), as a
    daemon sends it."""
    millimetres = np.where(np.isfinite(depth), np.asarray(depth, np.float64) * 1000.0, 0.0)
    return encode_png(np.clip(np.round(millimetres), 0, 65535).astype(np.uint16))


def segmentation_png(segmentation: np.ndarray) -> bytes:
    """Segmentation indices as a 16-bit PNG of index + 1 (0: nothing), as a daemon sends
    it."""
    return encode_png(np.clip(np.asarray(segmentation) + 1, 0, 65535).astype(np.uint16))
