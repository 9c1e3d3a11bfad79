"""The frame's LiDAR scan as the view shows it: the returns around the car and, in green, the
returns on the road (the paper's figure 1 (d): "LiDAR points (black), road LiDAR points
(green)"). A return is a road return when it projects into the image onto a pixel of the road
class, the rule by which the paper joins LiDAR points to the road cluster (sec. "LiDAR
fusion")."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: returns farther than this from the sensor (horizontal distance, m) are not shown: the map
#: view of figure 1 (d) covers the road around the car, and KITTI's scan reaches ~120 m
LIDAR_VIEW_MAX_RANGE_M = 60.0
#: at most this many returns per frame are shown (every k-th return, evenly over the scan): a
#: KITTI scan holds ~120k; 20k keep the road's rings and every car's outline and make a
#: 100-frame recording ~25 MB instead of ~140 MB
LIDAR_VIEW_MAX_POINTS = 20000


@dataclass
class LidarView:
    """One frame's LiDAR returns in the world frame.

    Attributes
    ----------
    scan_w : (N, 3) float64
        The returns shown (finite, within :data:`LIDAR_VIEW_MAX_RANGE_M`, thinned to
        :data:`LIDAR_VIEW_MAX_POINTS`) that are not road returns.
    road_w : (M, 3) float64
        The returns shown that project onto road pixels (empty without a segmentation).
    """

    scan_w: np.ndarray
    road_w: np.ndarray


def lidar_view(points_c: np.ndarray, T_w_c: np.ndarray, K: np.ndarray,
               class_ids: np.ndarray | None, road_class_id: int, *,
               max_range_m: float = LIDAR_VIEW_MAX_RANGE_M,
               max_points: int = LIDAR_VIEW_MAX_POINTS) -> LidarView:
    """The returns of one scan to show, and which of them lie on the road.

    Parameters
    ----------
    points_c : (N, 3) or (N, 4) array
        The scan in the camera frame ``c`` (x right, y down, z forward; a 4th column, the
        intensity, is ignored). Rows with NaN or inf are left out.
    T_w_c : (4, 4) array
        The camera's pose in the world.
    K : (3, 3) array
        The left camera's intrinsics (the segmentation's pixels).
    class_ids : (H, W) int array or None
        Class id per pixel; None: no road returns.
    road_class_id : int
        The road's class id (Cityscapes 7).
    max_range_m, max_points : float, int
        See :data:`LIDAR_VIEW_MAX_RANGE_M`, :data:`LIDAR_VIEW_MAX_POINTS`.

    Returns
    -------
    LidarView

    Raises
    ------
    ValueError
        ``points_c`` not (N, 3) / (N, 4), ``T_w_c`` not (4, 4), ``K`` not (3, 3) or
        ``class_ids`` not a 2D integer image; the message names the argument.
    """
    points = np.asarray(points_c)
    if points.ndim != 2 or points.shape[1] not in (3, 4):
        raise ValueError(f"lidar_view: points_c must be (N, 3) or (N, 4), got {points.shape}")
    T = np.asarray(T_w_c, dtype=np.float64)
    if T.shape != (4, 4):
        raise ValueError(f"lidar_view: T_w_c must be (4, 4), got {T.shape}")
    K = np.asarray(K, dtype=np.float64)
    if K.shape != (3, 3):
        raise ValueError(f"lidar_view: K must be (3, 3), got {K.shape}")
    if max_points < 1:
        raise ValueError(f"lidar_view: max_points must be >= 1, got {max_points}")
    X = points[:, :3].astype(np.float64)
    keep = np.isfinite(X).all(axis=1)
    keep[keep] = np.hypot(X[keep, 0], X[keep, 2]) <= max_range_m
    X = X[keep]
    if len(X) > max_points:
        X = X[:: -(-len(X) // max_points)]  # every k-th: evenly over the scan's rings
    road = np.zeros(len(X), dtype=bool)
    if class_ids is not None:
        classes = np.asarray(class_ids)
        if classes.ndim != 2 or not np.issubdtype(classes.dtype, np.integer):
            raise ValueError(f"lidar_view: class_ids must be a (H, W) integer image, got "
                             f"{classes.shape} {classes.dtype}")
        front = X[:, 2] > 0.1
        uvw = X[front] @ K.T
        u = np.floor(uvw[:, 0] / uvw[:, 2]).astype(np.int64)
        v = np.floor(uvw[:, 1] / uvw[:, 2]).astype(np.int64)
        height, width = classes.shape
        inside = (u >= 0) & (u < width) & (v >= 0) & (v < height)
        on_road = np.zeros(len(u), dtype=bool)
        on_road[inside] = classes[v[inside], u[inside]] == road_class_id
        road[np.flatnonzero(front)[on_road]] = True
    X_w = X @ T[:3, :3].T + T[:3, 3]
    return LidarView(scan_w=X_w[~road], road_w=X_w[road])
