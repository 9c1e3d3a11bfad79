"""16-bit PNG files (grey or RGB), as KITTI's flow / disparity and panoptic id images use.

Pillow cannot write 16-bit RGB PNGs (and reads them as 8-bit), so this small codec writes
them with zlib (deterministic bytes for a given compression level) and reads any
non-interlaced 16-bit grey / RGB PNG, including ones other tools wrote with row filters.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def write_png16(path: str | Path, image: np.ndarray, level: int = 1) -> None:
    """Write (H, W) or (H, W, 3) uint16 values as a 16-bit grey or RGB PNG."""
    image = np.asarray(image)
    if image.dtype != np.uint16:
        raise ValueError(f"write_png16: expected uint16, got {image.dtype}")
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3):
        raise ValueError(f"write_png16: expected (H, W) or (H, W, 3), got {image.shape}")
    h, w = image.shape[:2]
    colour_type = 0 if image.ndim == 2 else 2
    rows = image.astype(">u2").reshape(h, -1).view(np.uint8)
    raw = np.concatenate([np.zeros((h, 1), np.uint8), rows], axis=1).tobytes()  # filter 0 per row
    header = struct.pack(">IIBBBBB", w, h, 16, colour_type, 0, 0, 0)
    data = (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(raw, level))
            + _chunk(b"IEND", b""))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)


def _paeth(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    p = a.astype(np.int32) + b - c
    pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
    return np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c)).astype(np.uint8)


def read_png16(path: str | Path) -> np.ndarray:
    """Read a 16-bit grey (H, W) or RGB (H, W, 3) PNG as uint16."""
    data = Path(path).read_bytes()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG file")
    pos, idat, header = 8, [], None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        pos += 12 + length
    w, h, depth, colour_type, _, _, interlace = header
    if depth != 16 or colour_type not in (0, 2) or interlace:
        raise ValueError(f"{path}: expected a non-interlaced 16-bit grey or RGB PNG")
    channels = 1 if colour_type == 0 else 3
    bpp, stride = 2 * channels, w * 2 * channels
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), np.uint8).reshape(h, stride + 1)
    out = np.zeros((h, stride), np.uint8)
    prev = np.zeros(stride, np.uint8)
    for y in range(h):
        kind, line = raw[y, 0], raw[y, 1:].copy()
        if kind == 2:
            line = line + prev
        elif kind in (1, 3, 4):  # filters that depend on the reconstructed left byte
            for x in range(stride):
                left = line[x - bpp] if x >= bpp else 0
                up, up_left = prev[x], (prev[x - bpp] if x >= bpp else 0)
                if kind == 1:
                    line[x] = (int(line[x]) + int(left)) & 255
                elif kind == 3:
                    line[x] = (int(line[x]) + (int(left) + int(up)) // 2) & 255
                else:
                    line[x] = (int(line[x]) + int(_paeth(np.uint8(left), np.uint8(up), np.uint8(up_left)))) & 255
        out[y] = line
        prev = line
    values = out.view(">u2").astype(np.uint16)
    return values.reshape(h, w) if channels == 1 else values.reshape(h, w, 3)
