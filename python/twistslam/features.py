"""Features of the C++ core: bucketed ORB and stereo matching along rectified rows.

Typed facade of ``twistslam._core.features`` (each function's docstring lists its options
and returns); the SLAM system calls the same code per frame. See ``docs/features.md``.

>>> from twistslam import features                                         # doctest: +SKIP
>>> out = features.match_stereo(left, right, seq.calib.stereo_camera(W, H))  # doctest: +SKIP
>>> out["points_c"][out["matched"]]                                         # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twistslam._core import features as _f

from ._facade import doc_from
from .geometry import StereoCamera


@doc_from(_f.extract_orb)
def extract_orb(image: ArrayLike, options: Mapping[str, Any] | None = None,
                mask: ArrayLike | None = None, **kwargs: Any) -> dict[str, Any]:
    return _f.extract_orb(image, _as_dict(options), mask, **kwargs)


@doc_from(_f.match_stereo)
def match_stereo(image_left: ArrayLike, image_right: ArrayLike, camera: StereoCamera,
                 options: Mapping[str, Any] | None = None, mask: ArrayLike | None = None,
                 **kwargs: Any) -> dict[str, Any]:
    return _f.match_stereo(image_left, image_right, camera, _as_dict(options), mask, **kwargs)


@doc_from(_f.default_options)
def default_options() -> dict[str, int | float]:
    return _f.default_options()


@doc_from(_f.option_ranges)
def option_ranges() -> dict[str, tuple[float, float]]:
    return _f.option_ranges()


@doc_from(_f.hamming_distance)
def hamming_distance(a: ArrayLike, b: ArrayLike) -> NDArray[np.int32]:
    return _f.hamming_distance(a, b)


def _as_dict(options: Mapping[str, Any] | None) -> dict[str, Any] | None:
    # the core reads a dict; any mapping (a Config section's dict, a MappingProxy) will do
    return options if options is None or isinstance(options, dict) else dict(options)


__all__ = ["default_options", "extract_orb", "hamming_distance", "match_stereo", "option_ranges"]
