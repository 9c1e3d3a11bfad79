"""Heading (yaw) error of object tracks: issue 11's "yaw error <= 2 deg".

The heading of a box pose in a camera frame is KITTI's ``ry``: the angle of the object's x
axis (its length) about the camera's y axis (down), the ``ry`` of ``R_y(ry)``. The error is
taken modulo 2 pi, not pi: a box whose x axis points backwards (a car estimated driving the
wrong way) is 180 deg off, although its box covers the same space.
"""

from __future__ import annotations

import numpy as np


def heading(T_c_o: np.ndarray) -> np.ndarray:
    """(N,) rad in (-pi, pi]: KITTI ``ry`` of box poses ``T_c_o`` (N, 4, 4) in a camera frame.

    ``atan2(R[0, 2], R[0, 0])``, the heading of the object's x axis projected on the camera's
    x-z plane (what the tracking results write; a roll or pitch of the estimate is ignored).
    """
    R = np.asarray(T_c_o, dtype=np.float64).reshape(-1, 4, 4)[:, :3, :3]
    return np.arctan2(R[:, 0, 2], R[:, 0, 0])


def heading_error_deg(ry_est: np.ndarray, ry_gt: np.ndarray) -> np.ndarray:
    """(N,) deg in [0, 180]: ``|ry_est - ry_gt|`` wrapped modulo 2 pi (a flip is 180 deg)."""
    diff = np.asarray(ry_est, dtype=np.float64) - np.asarray(ry_gt, dtype=np.float64)
    return np.rad2deg(np.abs(np.arctan2(np.sin(diff), np.cos(diff))))


def mean_yaw_error_deg(T_c_o_gt: np.ndarray, T_c_o_est: np.ndarray) -> float:
    """Mean heading error (deg) of an estimated track over its frames.

    Parameters
    ----------
    T_c_o_gt, T_c_o_est : (N, 4, 4) ground-truth and estimated box poses, row ``k`` of both
        in the camera frame of the same frame (each estimate in its own estimated camera:
        the SLAM world's drift does not enter). NaN when N = 0.
    """
    if len(T_c_o_gt) != len(T_c_o_est):
        raise ValueError(f"mean_yaw_error_deg: {len(T_c_o_gt)} ground-truth poses, "
                         f"{len(T_c_o_est)} estimates")
    if not len(T_c_o_gt):
        return float("nan")
    return float(heading_error_deg(heading(T_c_o_est), heading(T_c_o_gt)).mean())
