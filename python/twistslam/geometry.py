"""Geometry of the C++ core: SE(3)/SO(3), mechanical links, stereo camera, planes, boxes.

Thin re-export of ``twistslam._core.geometry``; every function checks array shapes and
raises ``ValueError`` (wrong shape) or ``TypeError`` (non-numeric input). See
``docs/geometry_api.md`` for conventions (twists ``[v; w]``, boxes ``[cx, cy, cz, l, w, h, ry]``).
"""

from twistslam._core import geometry as _g

so3_exp = _g.so3_exp
so3_log = _g.so3_log
so3_left_jacobian = _g.so3_left_jacobian
so3_right_jacobian = _g.so3_right_jacobian
so3_left_jacobian_inverse = _g.so3_left_jacobian_inverse
so3_right_jacobian_inverse = _g.so3_right_jacobian_inverse
se3_exp = _g.se3_exp
se3_log = _g.se3_log
se3_inverse = _g.se3_inverse
se3_compose = _g.se3_compose
se3_adjoint = _g.se3_adjoint
se3_left_jacobian = _g.se3_left_jacobian
se3_right_jacobian = _g.se3_right_jacobian
se3_left_jacobian_inverse = _g.se3_left_jacobian_inverse
se3_right_jacobian_inverse = _g.se3_right_jacobian_inverse
twist_between = _g.twist_between
transform_points = _g.transform_points
projector_free = _g.projector_free
projector_planar = _g.projector_planar
StereoCamera = _g.StereoCamera
PlaneFit = _g.PlaneFit
fit_plane_ransac = _g.fit_plane_ransac
box_corners = _g.box_corners
project_boxes = _g.project_boxes
box_iou_2d = _g.box_iou_2d
box_iou_bev = _g.box_iou_bev
box_iou_3d = _g.box_iou_3d
box_giou_bev = _g.box_giou_bev
box_giou_3d = _g.box_giou_3d

__all__ = [name for name in dir() if not name.startswith("_")]
