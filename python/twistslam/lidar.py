"""LiDAR depth for image keypoints (C++ core, ``twistslam._core.lidar``). See ``docs/lidar.md``.

A scan in the rectified camera frame is projected once per frame into the left image; each
keypoint then gets the depth of a local plane through the returns around it, or none (too few
returns, outside the scan's support, at a depth edge, no plane). Returns on a-priori dynamic
classes (``mask == 0``) are never used.

>>> from twistslam import lidar                                              # doctest: +SKIP
>>> scan = lidar.project_scan(frame.points_c, camera, mask=static_mask)      # doctest: +SKIP
>>> out = lidar.lidar_depth_at(keypoints_uv, scan)                            # doctest: +SKIP
>>> out["depth"][out["valid"]]                                                # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

import numpy as np

from twistslam._core import lidar as _l

ScanProjection = _l.ScanProjection
STATUS_NAMES: dict[int, str] = dict(_l.STATUS_NAMES)
#: The KITTI HDL-64 vertical-angle correction (deg, upward), as KISS-ICP's KITTI reader.
KITTI_VERTICAL_ANGLE_OFFSET_DEG = 0.205


def default_options() -> dict[str, Any]:
    """Every LiDAR depth option with its default (units and reasons in ``docs/lidar.md``)."""
    return dict(_l.default_options())


def project_scan(points_c: np.ndarray, camera: Any, mask: np.ndarray | None = None,
                 options: dict[str, Any] | None = None, **kwargs: Any) -> ScanProjection:
    """Project ``points_c`` ((N, >=3), frame c) into the left image of ``camera``.

    ``mask``: optional (H, W) bool / uint8, 0 = dynamic class (those returns are dropped).
    NaN / Inf points are dropped and counted in ``num_non_finite``."""
    return _l.project_scan(points_c, camera, mask, options, **kwargs)


def lidar_depth_at(keypoints: np.ndarray, scan: ScanProjection,
                   options: dict[str, Any] | None = None, **kwargs: Any) -> dict[str, np.ndarray]:
    """Depth (m, left optical axis) of (K, 2) keypoints: ``depth`` (NaN where invalid),
    ``valid``, ``num_returns``, ``status`` (see ``STATUS_NAMES``), ``rms_relative``."""
    return _l.lidar_depth_at(keypoints, scan, options, **kwargs)


def correct_kitti_scan(points_velo: np.ndarray,
                       angle_deg: float = KITTI_VERTICAL_ANGLE_OFFSET_DEG) -> np.ndarray:
    """Raw Velodyne points (N, >=3) rotated up by ``angle_deg`` about p x z (float64 copy;
    extra columns such as intensity unchanged)."""
    return _l.correct_kitti_scan(points_velo, angle_deg)


def estimate_disparity_offset(disparities: np.ndarray, lidar_depths: np.ndarray,
                              fx_baseline: float, min_samples: int = 30,
                              max_abs_residual_px: float = 3.0) -> dict[str, Any]:
    """Median of ``fx_baseline / lidar_depth - disparity`` (px) with its MAD and sample count;
    ``valid`` is False (offset 0) below ``min_samples`` usable pairs."""
    return dict(_l.estimate_disparity_offset(disparities, lidar_depths, fx_baseline,
                                             min_samples, max_abs_residual_px))


__all__ = [
    "KITTI_VERTICAL_ANGLE_OFFSET_DEG", "STATUS_NAMES", "ScanProjection", "correct_kitti_scan",
    "default_options", "estimate_disparity_offset", "lidar_depth_at", "project_scan",
]
