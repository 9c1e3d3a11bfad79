"""Readers of the per-frame sensor files: images, LiDAR scans, timestamps."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ._parsing import PathLike, iter_lines, parse_error, to_floats


class MissingDataWarning(UserWarning):
    """A modality or a file of a sequence is missing, or data had to be dropped."""


#: pixels an image file may declare: 85x KITTI's 0.47 Mpx (its RGB array is 120 MB); a
#: decompression bomb (a small PNG declaring gigapixels) is refused before it is decoded
MAX_IMAGE_PIXELS = 40_000_000
#: Pillow modes of 16-bit grey images (``I``: Pillow versions that widen them to int32)
_SIXTEEN_BIT_MODES = ("I;16", "I;16L", "I;16B", "I;16N", "I")


def read_image(path: PathLike) -> np.ndarray:
    """Read an image as ``(H, W, 3)`` uint8 RGB (grey images are replicated to 3 channels).

    16-bit images are scaled to 8 bits (``round(v / 257)``; Pillow alone clips grey ones to
    255, all white). Raises ``ValueError`` naming the file for an image of more than
    :data:`MAX_IMAGE_PIXELS` pixels or of a kind that is not an 8- or 16-bit picture.
    An 8-bit colour PNG (KITTI's and the simulator's images) is decoded by the C++ core
    without the GIL (libdeflate, cpp/io/png_decoder.hpp: 5.5 ms per KITTI image against
    10.8 with OpenCV's libpng, about half Pillow's time in ``benchmarks/bench_images.py``, the
    same pixels); every other kind by Pillow.
    """
    if _is_rgb8_png(path):
        from .._core import io as _io  # the core only when such an image is read

        return _io.read_png_rgb8(str(path))
    return read_bounded_image(path, _rgb8)


#: a PNG file's first bytes: the signature, then the IHDR chunk's length and type
_PNG_HEAD = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR"


def _is_rgb8_png(path: PathLike) -> bool:
    """True for a PNG whose header declares 8-bit RGB (colour type 2) and at most
    :data:`MAX_IMAGE_PIXELS` pixels; a missing file raises FileNotFoundError naming it."""
    with open(path, "rb") as f:
        head = f.read(26)
    if len(head) < 26 or not head.startswith(_PNG_HEAD):
        return False
    width, height = int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")
    bit_depth, colour_type = head[24], head[25]
    return bit_depth == 8 and colour_type == 2 and 0 < width * height <= MAX_IMAGE_PIXELS


def read_bounded_image(path: PathLike, convert):
    """``convert(image, path)`` of the Pillow image at ``path``, after checking that it
    declares at most :data:`MAX_IMAGE_PIXELS` pixels (``ValueError`` naming the file: a
    decompression bomb is refused before it is decoded)."""
    from PIL import Image  # Pillow only when images are actually read

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(path) as image:
                width, height = image.size
                if width * height > MAX_IMAGE_PIXELS:
                    raise ValueError(f"{path}: {width}x{height} pixels, more than the "
                                     f"{MAX_IMAGE_PIXELS} an image may have")
                return convert(image, path)
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        raise ValueError(f"{path}: refused as a decompression bomb ({exc})") from None


def _rgb8(image, path: PathLike) -> np.ndarray:
    if image.mode in _SIXTEEN_BIT_MODES:
        values = np.asarray(image).astype(np.int64)
        if values.size and (values.min() < 0 or values.max() > 65535):
            raise ValueError(f"{path}: {image.mode} image with values outside 0..65535; "
                             "expected an 8- or 16-bit image")
        grey = ((values + 128) // 257).astype(np.uint8)
        return np.repeat(grey[..., None], 3, axis=2)
    if image.mode == "F":
        raise ValueError(f"{path}: floating-point image; expected an 8- or 16-bit image")
    if image.mode == "RGB":  # KITTI's and the simulator's colour PNGs: one copy, no convert
        return np.array(image, dtype=np.uint8)  # (1.1 ms less per 1242x375 image)
    return np.array(image.convert("RGB"), dtype=np.uint8)


def read_velodyne(path: PathLike) -> np.ndarray:
    """Read a KITTI LiDAR scan: float32 little-endian ``x y z intensity`` -> ``(N, 4)`` float32.

    Rows containing NaN or inf are dropped with a :class:`MissingDataWarning` naming the file
    (one corrupt point should not stop a run over a whole sequence).

    Raises
    ------
    ValueError
        If the file size is not a multiple of 16 bytes (4 float32 per point): the file is
        truncated or not a KITTI scan, and reshaping it would silently misalign every point.
    """
    path = Path(path)
    size = path.stat().st_size
    if size % 16 != 0:
        raise ValueError(
            f"{path}: size {size} bytes is not a multiple of 16 (4 float32 per point); "
            "truncated or not a KITTI velodyne scan"
        )
    points = np.fromfile(path, dtype="<f4").reshape(-1, 4)
    finite = np.isfinite(points).all(axis=1)
    if not finite.all():
        warnings.warn(
            f"{path}: dropped {int((~finite).sum())} of {len(points)} points with NaN/inf",
            MissingDataWarning,
            stacklevel=2,
        )
        points = points[finite]
    return points.astype(np.float32, copy=False)


def write_velodyne(path: PathLike, points: np.ndarray) -> None:
    """Write ``(N, 4)`` points as a KITTI velodyne ``.bin`` (float32 little-endian)."""
    points = np.asarray(points, dtype="<f4")
    if points.ndim != 2 or points.shape[1] != 4:
        raise ValueError(f"write_velodyne: expected (N, 4) points, got shape {points.shape}")
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    points.tofile(path)


def read_timestamps(path: PathLike) -> np.ndarray:
    """Read one time in seconds per line -> ``(N,)`` float64."""
    times = []
    for line_no, tokens in iter_lines(path):
        if len(tokens) != 1:
            raise parse_error(path, line_no, f"expected 1 value (seconds), got {len(tokens)}")
        times.append(to_floats(tokens, path, line_no, "timestamp")[0])
    return np.array(times, dtype=np.float64)


def scan_in_camera(points_velo: np.ndarray, T_c_velo: np.ndarray,
                   angle_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``(points_velo, points_c)``: the scan (N, C >= 3) with every return's elevation raised by
    ``angle_deg`` (KITTI's HDL-64 correction; intensity kept), and the same rows with (x, y, z)
    in the camera frame, ``X_c = T_c_velo X_velo``; both float32. One C++ pass (the numpy
    version took ~15 ms of a real KITTI frame's loading)."""
    from twistslam._core import lidar as _lidar

    return _lidar.scan_to_camera(points_velo, T_c_velo, angle_deg=angle_deg)
