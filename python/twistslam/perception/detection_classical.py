"""The classical LiDAR 3D detector of the C++ core (``twistslam._core.detection``): road
removal, bird's-eye-view clustering, L-shape box fitting with a car-size prior, class from size
and shape. No weights; the default detection source. See ``docs/detection.md``.

>>> detect = ClassicalDetector()                                              # doctest: +SKIP
>>> dets = detect(frame)          # Detections3D, boxes in the rectified camera frame
"""

from __future__ import annotations

from typing import Any

import numpy as np

from twistslam._core import detection as _d

from .detection import Detections3D


def default_options() -> dict[str, Any]:
    """Every option of the classical detector with its default (units in docs/detection.md)."""
    return dict(_d.default_options())


def option_ranges() -> dict[str, tuple[float, float]]:
    """The valid (lo, hi) range of every numeric option, inclusive, in its unit."""
    return dict(_d.option_ranges())


class ClassicalDetector:
    """Callable ``frame -> Detections3D`` running the C++ detector on ``frame.points_c``.

    Parameters
    ----------
    options : dict, optional
        Detector options (see :func:`default_options`); keyword arguments override it.

    Raises
    ------
    ValueError, TypeError
        An unknown option, a value of the wrong type or out of range (checked here, once).

    Attributes
    ----------
    last_stats : dict
        Of the last call: ``num_non_finite``, ``num_selected``, ``num_obstacle``,
        ``num_clusters``, ``num_points`` (per box) and ``timings`` (ms per stage).
    """

    def __init__(self, options: dict[str, Any] | None = None, **kwargs: Any) -> None:
        self.options = {**(options or {}), **kwargs}
        _d.detect(np.zeros((0, 3)), self.options)  # validates the options now, not per frame
        self.last_stats: dict[str, Any] = {}

    def __repr__(self) -> str:
        return f"ClassicalDetector({self.options!r})"

    def detect_points(self, points_c: np.ndarray) -> Detections3D:
        """Detections of a scan: (N, >=3) points in the rectified camera frame (extra columns
        such as intensity are ignored; NaN / Inf rows are skipped)."""
        out = _d.detect(points_c, self.options)
        box_keys = ("boxes", "scores", "classes", "open_end", "heading_known")
        self.last_stats = {k: v for k, v in out.items() if k not in box_keys}
        # every box is the rectangle around its cluster's points: a lower bound of the object
        return Detections3D(out["boxes"], out["scores"], np.asarray(out["classes"], dtype=object),
                            out["open_end"], np.ones(len(out["boxes"]), dtype=bool),
                            out["heading_known"])

    def __call__(self, frame) -> Detections3D:
        if frame.points_c is None:
            raise ValueError(f"classical detection: frame {frame.index} has no LiDAR scan (points_c)")
        return self.detect_points(frame.points_c)
