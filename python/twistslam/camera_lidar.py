"""The stereo pair's disparity offset, estimated from a frame's LiDAR scan.

Real KITTI colour pairs measure disparities about 0.6 px shorter than the LiDAR geometry
implies, at every range (docs/camera_scale.md): uncorrected, stereo depth is 2-7 % too long
and so is the camera's path. With a scan, the offset is the median over the frame's stereo
keypoints of ``fx b / z_lidar - (u_left - u_right)`` (cpp/lidar/disparity_offset.hpp), the
LiDAR depth taken from a local plane of returns around each keypoint.

>>> camera = seq.calib.stereo_camera(W, H)                           # doctest: +SKIP
>>> est = estimate_offset(frame, camera, Config())                   # doctest: +SKIP
>>> camera = camera.with_disparity_offset(est.offset_px)             # doctest: +SKIP
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .config import Config
from .datasets import Frame


@dataclass
class OffsetEstimate:
    """``offset_px`` (0 when not ``valid``), its MAD and the keypoints it rests on."""

    valid: bool
    offset_px: float
    mad_px: float
    num_samples: int
    reason: str = ""  # why it is not valid


def lidar_depth_options(config: Config) -> dict:
    """The C++ ``LidarDepthOptions`` of ``config.lidar`` (cpp/lidar)."""
    from .config_lidar import PYTHON_ONLY

    return {k: v for k, v in config.lidar.__dict__.items() if k not in PYTHON_ONLY + ("use_depth",)}


def estimate_offset(frame: Frame, camera, config: Config,
                    labels: np.ndarray | None = None) -> OffsetEstimate:
    """The disparity offset of ``camera`` (its own offset ignored) from one stereo frame and
    its scan ``frame.points_c``; returns on ``config.tracking.dynamic_class_ids`` (per
    ``labels``) are not used. Not ``valid`` without a scan or with fewer than
    ``config.lidar.offset_min_samples`` keypoints having both depths, nor when the median is
    within ``config.lidar.offset_min_significance`` standard errors or
    ``config.lidar.offset_min_abs_px`` of 0 (the calibration is then trusted)."""
    from twistslam import features
    from twistslam._core import lidar as _lidar

    if frame.points_c is None or len(frame.points_c) == 0:
        return OffsetEstimate(False, 0.0, 0.0, 0, "the frame has no LiDAR scan")
    camera = camera.with_disparity_offset(0.0)
    options = {**config.orb.__dict__, **config.stereo.__dict__}
    stereo = features.match_stereo(frame.image_left, frame.image_right, camera, options)
    matched = stereo["matched"]
    keypoints = np.asarray(stereo["keypoints"], dtype=np.float64)[matched]
    disparity = keypoints[:, 0] - np.asarray(stereo["u_right"])[matched]
    mask = None
    if labels is not None and config.tracking.dynamic_class_ids:
        mask = np.where(np.isin(labels, config.tracking.dynamic_class_ids), 0, 255).astype(np.uint8)
    scan = _lidar.project_scan(np.ascontiguousarray(frame.points_c[:, :3], dtype=np.float64),
                               camera, mask=mask, options=lidar_depth_options(config))
    depth = _lidar.lidar_depth_at(keypoints, scan, options=lidar_depth_options(config))
    z = np.where(depth["valid"], depth["depth"], np.nan)
    out = _lidar.estimate_disparity_offset(disparity, z, camera.fx * camera.baseline,
                                           min_samples=config.lidar.offset_min_samples)
    valid, offset, mad, n = (bool(out["valid"]), float(out["offset_px"]), float(out["mad_px"]),
                             int(out["num_samples"]))
    if not valid:
        return OffsetEstimate(False, 0.0, mad, n, f"{n} keypoints with a stereo and a LiDAR "
                              f"depth, {config.lidar.offset_min_samples} needed")
    standard_error = median_standard_error(mad, n)
    if abs(offset) < config.lidar.offset_min_significance * standard_error:
        return OffsetEstimate(False, 0.0, mad, n, f"{offset:+.3f} px is within "
                              f"{config.lidar.offset_min_significance:g} standard errors "
                              f"({standard_error:.3f} px) of 0")
    if abs(offset) < config.lidar.offset_min_abs_px:
        return OffsetEstimate(False, 0.0, mad, n, f"{offset:+.3f} px is below "
                              f"{config.lidar.offset_min_abs_px:g} px, the estimator's own bias")
    return OffsetEstimate(True, offset, mad, n)


def median_standard_error(mad: float, n: int) -> float:
    """Standard error of the median of ``n`` samples with this median absolute deviation
    (normal errors: sigma = 1.4826 MAD, SE = 1.2533 sigma / sqrt(n))."""
    return 1.2533 * 1.4826 * mad / max(n, 1) ** 0.5
