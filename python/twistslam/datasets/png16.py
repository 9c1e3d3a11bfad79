"""16-bit PNG files (grey or RGB), as KITTI's flow / disparity and panoptic id images use, and
fast 8-bit colour PNGs.

Pillow cannot write 16-bit RGB PNGs (and reads them as 8-bit), so this small codec writes
them with zlib (deterministic bytes for a given compression level) and reads any
non-interlaced 16-bit grey / RGB PNG, including ones other tools wrote with row filters. The
simulator also writes its 8-bit colour images with it: a fixed row filter and zlib's
Huffman-only strategy encode them several times faster than Pillow does.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from .sensors import MAX_IMAGE_PIXELS


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def encode_png(image: np.ndarray, level: int = 1) -> bytes:
    """PNG file bytes of (H, W) or (H, W, 3) uint8 or uint16 values (grey or RGB).

    One fixed row filter per kind, chosen for speed and size (deterministic bytes for a given
    zlib level): 8-bit colour uses Sub (difference to the pixel on the left) with zlib's
    Huffman-only strategy -- camera noise leaves few long matches for deflate to find, and
    this is ~4x faster than Pillow's adaptive filtering at level 1, and smaller; 16-bit images use
    Up (difference to the row above: flow and disparity vary smoothly, so the high bytes become
    runs of zeros), which halves flow files and encoding time compared with no filter."""
    image = np.asarray(image)
    if image.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"encode_png: expected uint8 or uint16, got {image.dtype}")
    if image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3):
        raise ValueError(f"encode_png: expected (H, W) or (H, W, 3), got {image.shape}")
    h, w = image.shape[:2]
    colour_type = 0 if image.ndim == 2 else 2
    rows = np.ascontiguousarray(image, dtype=">u2" if image.dtype == np.uint16 else np.uint8).reshape(h, -1)
    rows = rows.view(np.uint8)
    body = rows.copy()  # uint8 differences wrap modulo 256, as PNG filters do
    if image.dtype == np.uint8:
        bpp = 1 if image.ndim == 2 else 3
        body[:, bpp:] -= rows[:, :-bpp]
        kind, strategy = 1, zlib.Z_HUFFMAN_ONLY
    else:
        body[1:] -= rows[:-1]
        kind, strategy = 2, zlib.Z_DEFAULT_STRATEGY
    raw = np.concatenate([np.full((h, 1), kind, np.uint8), body], axis=1).tobytes()
    deflate = zlib.compressobj(level, zlib.DEFLATED, zlib.MAX_WBITS, zlib.DEF_MEM_LEVEL, strategy)
    header = struct.pack(">IIBBBBB", w, h, 8 * image.itemsize, colour_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", header) + _chunk(b"IDAT", deflate.compress(raw) + deflate.flush())
            + _chunk(b"IEND", b""))


def write_png(path: str | Path, image: np.ndarray, level: int = 1) -> None:
    """Write (H, W) or (H, W, 3) uint8 or uint16 values as a PNG (see :func:`encode_png`)."""
    data = encode_png(image, level)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)


def write_png16(path: str | Path, image: np.ndarray, level: int = 1) -> None:
    """Write (H, W) or (H, W, 3) uint16 values as a 16-bit grey or RGB PNG."""
    image = np.asarray(image)
    if image.dtype != np.uint16:
        raise ValueError(f"write_png16: expected uint16, got {image.dtype}")
    write_png(path, image, level)


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
    if header is None:
        raise ValueError(f"{path}: PNG without an IHDR chunk")
    w, h, depth, colour_type, _, _, interlace = header
    if depth != 16 or colour_type not in (0, 2) or interlace:
        raise ValueError(f"{path}: expected a non-interlaced 16-bit grey or RGB PNG")
    if w * h > MAX_IMAGE_PIXELS:
        raise ValueError(f"{path}: {w}x{h} pixels, more than the {MAX_IMAGE_PIXELS} an image "
                         "may have")
    channels = 1 if colour_type == 0 else 3
    bpp, stride = 2 * channels, w * 2 * channels
    # never more than the header's size: a decompression bomb stops there
    data = zlib.decompressobj().decompress(b"".join(idat), h * (stride + 1))
    if len(data) != h * (stride + 1):
        raise ValueError(f"{path}: image data ends early ({len(data)} of {h * (stride + 1)} bytes)")
    raw = np.frombuffer(data, np.uint8).reshape(h, stride + 1)
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
