"""Geometry of the C++ core: SE(3)/SO(3), mechanical links, stereo camera, planes, boxes.

Typed facade of ``twistslam._core.geometry``; every function checks array shapes and values
and raises ``ValueError`` (wrong shape, NaN / Inf, a matrix that is not a rotation or rigid
transform) or ``TypeError`` (non-numeric input), naming the argument. See
``docs/geometry_api.md`` for conventions (twists ``[v; w]``, boxes ``[cx, cy, cz, l, w, h, ry]``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from twistslam._core import geometry as _g

from ._facade import doc_from

Array = NDArray[np.float64]

#: Rectified pinhole stereo pair (``StereoCamera.from_kitti(P2, P3, width, height)``).
StereoCamera = _g.StereoCamera
#: Result of :func:`fit_plane_ransac`: ``plane``, ``inliers``, ``num_inliers``, ``rms``.
PlaneFit = _g.PlaneFit


# ----------------------------------------------------------------------------- SO(3)
@doc_from(_g.so3_exp)
def so3_exp(w: ArrayLike) -> Array:
    return _g.so3_exp(w)


@doc_from(_g.so3_log)
def so3_log(R: ArrayLike) -> Array:
    return _g.so3_log(R)


@doc_from(_g.so3_left_jacobian)
def so3_left_jacobian(w: ArrayLike) -> Array:
    return _g.so3_left_jacobian(w)


@doc_from(_g.so3_right_jacobian)
def so3_right_jacobian(w: ArrayLike) -> Array:
    return _g.so3_right_jacobian(w)


@doc_from(_g.so3_left_jacobian_inverse)
def so3_left_jacobian_inverse(w: ArrayLike) -> Array:
    return _g.so3_left_jacobian_inverse(w)


@doc_from(_g.so3_right_jacobian_inverse)
def so3_right_jacobian_inverse(w: ArrayLike) -> Array:
    return _g.so3_right_jacobian_inverse(w)


# ----------------------------------------------------------------------------- SE(3)
@doc_from(_g.se3_exp)
def se3_exp(xi: ArrayLike) -> Array:
    return _g.se3_exp(xi)


@doc_from(_g.se3_log)
def se3_log(T: ArrayLike) -> Array:
    return _g.se3_log(T)


@doc_from(_g.se3_inverse)
def se3_inverse(T: ArrayLike) -> Array:
    return _g.se3_inverse(T)


@doc_from(_g.se3_compose)
def se3_compose(A: ArrayLike, B: ArrayLike) -> Array:
    return _g.se3_compose(A, B)


@doc_from(_g.se3_adjoint)
def se3_adjoint(T: ArrayLike) -> Array:
    return _g.se3_adjoint(T)


@doc_from(_g.se3_left_jacobian)
def se3_left_jacobian(xi: ArrayLike) -> Array:
    return _g.se3_left_jacobian(xi)


@doc_from(_g.se3_right_jacobian)
def se3_right_jacobian(xi: ArrayLike) -> Array:
    return _g.se3_right_jacobian(xi)


@doc_from(_g.se3_left_jacobian_inverse)
def se3_left_jacobian_inverse(xi: ArrayLike) -> Array:
    return _g.se3_left_jacobian_inverse(xi)


@doc_from(_g.se3_right_jacobian_inverse)
def se3_right_jacobian_inverse(xi: ArrayLike) -> Array:
    return _g.se3_right_jacobian_inverse(xi)


@doc_from(_g.twist_between)
def twist_between(T_a: ArrayLike, T_b: ArrayLike) -> Array:
    return _g.twist_between(T_a, T_b)


@doc_from(_g.predict_constant_velocity)
def predict_constant_velocity(T_previous: ArrayLike, T_last: ArrayLike) -> Array:
    return _g.predict_constant_velocity(T_previous, T_last)


@doc_from(_g.transform_points)
def transform_points(T: ArrayLike, points: ArrayLike) -> Array:
    return _g.transform_points(T, points)


# ----------------------------------------------------------------------------- links, planes
@doc_from(_g.projector_free)
def projector_free() -> Array:
    return _g.projector_free()


@doc_from(_g.projector_planar)
def projector_planar(normal: ArrayLike) -> Array:
    return _g.projector_planar(normal)


@doc_from(_g.fit_plane_ransac)
def fit_plane_ransac(points: ArrayLike, inlier_threshold: float = 0.05, iterations: int = 200,
                     seed: int = 0) -> PlaneFit:
    return _g.fit_plane_ransac(points, inlier_threshold, iterations, seed)


# ----------------------------------------------------------------------------- boxes
@doc_from(_g.box_corners)
def box_corners(boxes: ArrayLike) -> Array:
    return _g.box_corners(boxes)


@doc_from(_g.project_boxes)
def project_boxes(boxes: ArrayLike, P: ArrayLike, width: int = 0, height: int = 0) -> Array:
    return _g.project_boxes(boxes, P, width, height)


@doc_from(_g.box_iou_2d)
def box_iou_2d(boxes_a: ArrayLike, boxes_b: ArrayLike) -> Array:
    return _g.box_iou_2d(boxes_a, boxes_b)


@doc_from(_g.box_iou_bev)
def box_iou_bev(boxes_a: ArrayLike, boxes_b: ArrayLike) -> Array:
    return _g.box_iou_bev(boxes_a, boxes_b)


@doc_from(_g.box_iou_3d)
def box_iou_3d(boxes_a: ArrayLike, boxes_b: ArrayLike) -> Array:
    return _g.box_iou_3d(boxes_a, boxes_b)


@doc_from(_g.box_giou_bev)
def box_giou_bev(boxes_a: ArrayLike, boxes_b: ArrayLike) -> Array:
    return _g.box_giou_bev(boxes_a, boxes_b)


@doc_from(_g.box_giou_3d)
def box_giou_3d(boxes_a: ArrayLike, boxes_b: ArrayLike) -> Array:
    return _g.box_giou_3d(boxes_a, boxes_b)


__all__ = [
    "PlaneFit", "StereoCamera", "box_corners", "box_giou_3d", "box_giou_bev", "box_iou_2d",
    "box_iou_3d", "box_iou_bev", "fit_plane_ransac", "predict_constant_velocity", "project_boxes",
    "projector_free", "projector_planar", "se3_adjoint", "se3_compose", "se3_exp", "se3_inverse",
    "se3_left_jacobian", "se3_left_jacobian_inverse", "se3_log", "se3_right_jacobian",
    "se3_right_jacobian_inverse", "so3_exp", "so3_left_jacobian", "so3_left_jacobian_inverse",
    "so3_log", "so3_right_jacobian", "so3_right_jacobian_inverse", "transform_points",
    "twist_between",
]
