"""Optical-flow files: KITTI flow PNG and Middlebury ``.flo``.

KITTI flow PNG: 16-bit RGB, R = u * 64 + 2^15, G = v * 64 + 2^15, B = 1 where the pixel has
ground truth (0 elsewhere). Middlebury ``.flo``: the float32 magic 202021.25 (bytes "PIEH"),
int32 width and height, then H * W * 2 little-endian float32 (u, v) row by row; values above
1e9 mean "unknown". Both read to (H, W, 2) float32 with NaN where there is no value.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from twistslam.datasets.png16 import read_png16, write_png16

KITTI_FLOW_SCALE = 64.0  # px -> stored units
KITTI_FLOW_OFFSET = 2.0**15
FLO_MAGIC = 202021.25
FLO_UNKNOWN = 1e9  # Middlebury: |value| above this is "unknown"


def read_kitti_flow(path: str | Path) -> np.ndarray:
    """(H, W, 2) float32 flow of a KITTI flow PNG, NaN where the valid bit is 0.

    Raises
    ------
    ValueError naming the file when it is not a 16-bit RGB PNG or its data ends early.
    """
    raw = read_png16(path)
    if raw.ndim != 3:
        raise ValueError(f"{path}: a KITTI flow PNG is 16-bit RGB, got a grey image {raw.shape}")
    flow = (raw[..., :2].astype(np.float32) - KITTI_FLOW_OFFSET) / KITTI_FLOW_SCALE
    flow[raw[..., 2] == 0] = np.nan
    return flow


def write_kitti_flow(path: str | Path, flow: np.ndarray) -> None:
    """Write (H, W, 2) flow as a KITTI flow PNG; NaN pixels are stored as invalid. Values are
    rounded to 1/64 px and must lie within +-512 px (the format's range)."""
    flow = np.asarray(flow, dtype=np.float64)
    if flow.ndim != 3 or flow.shape[2] != 2:
        raise ValueError(f"{path}: flow must be (H, W, 2), got {flow.shape}")
    valid = np.isfinite(flow).all(axis=2)
    if np.any(np.abs(flow[valid]) >= KITTI_FLOW_OFFSET / KITTI_FLOW_SCALE):
        raise ValueError(f"{path}: flow beyond +-512 px cannot be stored in a KITTI flow PNG")
    stored = np.where(valid[..., None], np.rint(flow * KITTI_FLOW_SCALE + KITTI_FLOW_OFFSET), 0)
    write_png16(path, np.dstack([stored, valid]).astype(np.uint16))


def read_flo(path: str | Path) -> np.ndarray:
    """(H, W, 2) float32 flow of a Middlebury ``.flo`` file, NaN where it is unknown.

    Raises
    ------
    ValueError naming the file on a wrong magic number, a bad size or a truncated file.
    """
    data = Path(path).read_bytes()
    if len(data) < 12:
        raise ValueError(f"{path}: truncated .flo file ({len(data)} bytes, the header alone is 12)")
    magic = np.frombuffer(data, "<f4", 1)[0]
    if magic != np.float32(FLO_MAGIC):
        raise ValueError(f"{path}: not a .flo file (magic {data[:4]!r}, expected b'PIEH')")
    width, height = (int(v) for v in np.frombuffer(data, "<i4", 2, offset=4))
    if width <= 0 or height <= 0 or width * height > 100_000_000:
        raise ValueError(f"{path}: implausible .flo size {width}x{height}")
    expected = 12 + width * height * 8
    if len(data) != expected:
        kind = "truncated" if len(data) < expected else "too long"
        raise ValueError(f"{path}: {kind} .flo file: {len(data)} bytes, {width}x{height} needs {expected}")
    flow = np.frombuffer(data, "<f4", width * height * 2, offset=12).reshape(height, width, 2).copy()
    flow[(np.abs(flow) > FLO_UNKNOWN).any(axis=2)] = np.nan
    return flow


def write_flo(path: str | Path, flow: np.ndarray) -> None:
    """Write (H, W, 2) flow as a Middlebury ``.flo`` file; NaN pixels become "unknown" (1e10)."""
    flow = np.asarray(flow, dtype=np.float32)
    if flow.ndim != 3 or flow.shape[2] != 2:
        raise ValueError(f"{path}: flow must be (H, W, 2), got {flow.shape}")
    body = np.where(np.isfinite(flow), flow, np.float32(1e10)).astype("<f4")
    header = np.array([FLO_MAGIC], "<f4").tobytes() + np.array(flow.shape[1::-1], "<i4").tobytes()
    Path(path).write_bytes(header + body.tobytes())
