"""Optimisation of the C++ core: pose-only optimisation and local bundle adjustment.

Typed facade of ``twistslam._core.optim`` (paper eqs. 3 and 9, static term); the SLAM system
runs the same solvers per frame and per keyframe. Inputs are checked at the boundary
(``ValueError`` naming the argument: shapes, index ranges, poses that are not finite rigid
transforms, option values out of range); the solvers run without the GIL.

>>> from twistslam import optim                                              # doctest: +SKIP
>>> r = optim.optimize_pose(T0, X_w, uv, u_right, inv_sigma2, camera, rounds=4)  # doctest: +SKIP
>>> r["T_c_w"], r["inlier"]                                                  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

from numpy.typing import ArrayLike

from twistslam._core import optim as _o

from ._facade import doc_from
from .geometry import StereoCamera


@doc_from(_o.optimize_pose)
def optimize_pose(T_c_w_init: ArrayLike, points_w: ArrayLike, uv: ArrayLike,
                  u_right: ArrayLike | None, inv_sigma2: ArrayLike | None, camera: StereoCamera,
                  **options: Any) -> dict[str, Any]:
    return _o.optimize_pose(T_c_w_init, points_w, uv, u_right, inv_sigma2, camera, **options)


@doc_from(_o.bundle_adjust)
def bundle_adjust(poses_c_w: ArrayLike, fixed_poses: ArrayLike | None, points_w: ArrayLike,
                  fixed_points: ArrayLike | None, obs_keyframe: ArrayLike, obs_point: ArrayLike,
                  uv: ArrayLike, u_right: ArrayLike | None, inv_sigma2: ArrayLike | None,
                  camera: StereoCamera, **options: Any) -> dict[str, Any]:
    return _o.bundle_adjust(poses_c_w, fixed_poses, points_w, fixed_points, obs_keyframe,
                            obs_point, uv, u_right, inv_sigma2, camera, **options)


__all__ = ["bundle_adjust", "optimize_pose"]
