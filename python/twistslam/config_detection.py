"""The ``detection`` section of :class:`twistslam.Config`: the options of the classical LiDAR
detector (``--detector classical``, and ``auto`` when a sequence has scans but no detection
files; C++ ``detection::ClassicalDetectorOptions``, their units and reasons in
docs/detection.md).

The section is built from the core's own option table (defaults and valid ranges), so it has
every option the detector has and nothing else, e.g. ``twistslam run ... --set
detection.max_range_m=40``. Files and 3DSSD boxes do not read it.
"""

from __future__ import annotations

from dataclasses import asdict, make_dataclass

from ._settings import param
from ._core import detection as _detection


def _detection_config() -> type:
    ranges = dict(_detection.option_ranges())
    fields = []
    for name, default in sorted(dict(_detection.default_options()).items()):
        lo, hi = ranges.get(name, (None, None))
        unit = "m" if name.endswith("_m") else "deg" if name.endswith("_deg") else ""
        why = "classical detector option (docs/detection.md; default from the C++ core)"
        fields.append((name, type(default), param(default, why, unit, lo=lo, hi=hi)))
    cls = make_dataclass("DetectionConfig", fields)
    cls.__module__ = __name__
    cls.__doc__ = ("The classical LiDAR detector's options (--detector classical; files and "
                   "3DSSD do not read them).")
    return cls


#: dataclass of the ``detection`` section (one field per classical detector option)
DetectionConfig = _detection_config()


def detector_options(section) -> dict:
    """The section as the options dictionary :class:`~twistslam.perception.ClassicalDetector`
    takes."""
    return asdict(section)
