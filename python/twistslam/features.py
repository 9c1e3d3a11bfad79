"""Features of the C++ core: bucketed ORB and stereo matching along rectified rows.

Thin re-export of ``twistslam._core.features`` (each function's docstring lists its options
and returns); the SLAM system calls the same code per frame. See ``docs/features.md``.

>>> from twistslam import features                                         # doctest: +SKIP
>>> out = features.match_stereo(left, right, seq.calib.stereo_camera(W, H))  # doctest: +SKIP
>>> out["points_c"][out["matched"]]                                         # doctest: +SKIP
"""

from twistslam._core import features as _f

extract_orb = _f.extract_orb
match_stereo = _f.match_stereo
default_options = _f.default_options
hamming_distance = _f.hamming_distance

__all__ = ["extract_orb", "match_stereo", "default_options", "hamming_distance"]
