"""The ``lidar`` section of :class:`twistslam.Config`: what the camera takes from the LiDAR.

Two things, both only when the sequence has scans (docs/camera_scale.md):

* the stereo pair's **disparity offset** (px, ``StereoCamera.disparity_offset``): real KITTI
  colour pairs measure disparities ~0.6 px shorter than the LiDAR geometry at every range,
  which made the stereo trajectory 2-4 % too long. ``"auto"`` estimates it from the first
  frame's stereo keypoints against the scan (:func:`twistslam.camera_lidar.estimate_offset`);
  a number fixes it; without scans ``"auto"`` is 0 (the calibration is trusted).
* **keypoint depth** from the scan (``depth``): keypoints near LiDAR returns take the depth of
  a local plane through them; the thresholds are the C++ ``LidarDepthOptions`` (cpp/lidar).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ._settings import param

#: fields read in Python, not passed to the C++ core
PYTHON_ONLY = ("disparity_offset", "offset_min_samples", "offset_min_significance",
               "offset_min_abs_px")


def _auto_or_float(value: str, key: str, bound: float) -> float | None:
    """``None`` for "auto", else the finite float within +-bound; ValueError naming key."""
    text = str(value).strip().lower()
    if text == "auto":
        return None
    try:
        number = float(text)
    except ValueError:
        raise ValueError(f"{key}: expected 'auto' or a number, got {value!r}") from None
    if not math.isfinite(number) or abs(number) > bound:
        raise ValueError(f"{key}: {number} is out of range [-{bound}, {bound}]")
    return number


@dataclass
class LidarConfig:
    """LiDAR for the camera: the stereo disparity offset and keypoint depth."""

    use_depth: bool = param(
        True, "keypoints near LiDAR returns take the scan's depth (static classes only); "
        "on real KITTI 0001 ATE 0.041 -> 0.037 m, RPE_t 0.052 -> 0.051 m/frame (the offset applied "
        "in both)")
    disparity_offset: str = param(
        "auto", "px added to measured stereo disparities: 'auto' = estimated from the first "
        "frame with a scan (0.6-0.7 px on real KITTI 0001), else 0; or a number", "px")
    offset_min_samples: int = param(
        100, "keypoints with both a stereo and a LiDAR depth needed to estimate the offset; "
        "a real KITTI frame gives ~500, the MAD of ~0.3 px makes 100 a 0.04 px median error",
        "keypoints", lo=3, hi=1000000)
    offset_min_significance: float = param(
        3.0, "an estimated offset is applied only when it is this many standard errors from 0 "
        "(SE of a median = 1.2533 x 1.4826 MAD / sqrt(n)): on real KITTI 0001 0.76 px is 40 SE "
        "from 0; on the exact simulator 0.03 px is 0.7 SE and is noise that moved ATE",
        "standard errors", lo=0.0, hi=100.0)
    offset_min_abs_px: float = param(
        0.2, "an estimated offset nearer 0 than this is not applied either: the estimator has "
        "a bias of its own that no sample count removes (keypoints at depth edges, where the "
        "local plane of returns is not the surface the stereo window matched). The "
        "simulator's exact pairs (true offset 0) gave first-frame estimates of -0.11 to "
        "+0.10 px on 17 sequences, two of them 3.5 standard errors from 0: applied, urban "
        "seed 11's -0.109 px lengthened its 330 m path by 0.38 % (camera ATE 0.081 -> 0.401 m, "
        "cars' canonical ATE 0.41 -> 1.01 m). Real KITTI 0001's is +0.76 px (per frame "
        "0.47-0.93). A true offset below 0.2 px is left in: at most 0.8 % of depth at 15 m",
        "px", lo=0.0, hi=8.0)
    cell_size_px: float = param(8.0, "side of the scan's pixel buckets (>= search radius: "
                                "a query visits at most 3 x 3 buckets)", "px", lo=1.0, hi=1024.0)
    search_radius_px: float = param(6.0, "returns this close to a keypoint form its "
                                    "neighbourhood: KITTI's scan lines are 4-7 px apart, 6 px "
                                    "brackets a keypoint by two lines", "px", lo=0.5, hi=64.0)
    min_depth_m: float = param(1.0, "returns nearer than this are dropped (nothing the "
                               "camera matches is closer)", "m", lo=0.01, hi=1000.0)
    max_depth_m: float = param(120.0, "returns farther than this are dropped (the HDL-64's "
                               "rated range)", "m", lo=0.1, hi=10000.0)
    min_returns: int = param(4, "returns needed for a local plane: 3 parameters + 1 to "
                             "measure the residual", "returns", lo=3, hi=10000)
    max_fit_residual: float = param(0.02, "RMS relative depth residual above which the "
                                    "neighbourhood is not one plane (~10x the HDL-64's noise "
                                    "at 10 m)", "ratio", lo=1e-6, hi=10.0)
    layer_gap: float = param(0.1, "relative gap between sorted depths that splits a near "
                             "layer from a far one at a depth edge", "ratio", lo=1e-6, hi=100.0)

    def fixed_disparity_offset(self) -> float | None:
        """The configured offset in px, or ``None`` for "auto"."""
        return _auto_or_float(self.disparity_offset, "lidar.disparity_offset", 8.0)

    def validate(self) -> None:
        self.fixed_disparity_offset()
        if self.min_depth_m >= self.max_depth_m:
            raise ValueError(f"lidar.min_depth_m ({self.min_depth_m}) must be below "
                             f"lidar.max_depth_m ({self.max_depth_m})")
