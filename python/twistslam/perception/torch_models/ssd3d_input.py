"""From a frame's LiDAR scan to the network's input: the points the camera sees (KITTI labels
only objects in the left image), inside the detection range, in frame l, resampled to the
network's fixed point count."""

from __future__ import annotations

import numpy as np

from .ssd3d_boxes import camera_to_lidar_points

#: KITTI's left image size (rows, columns) in pixels, used when a frame carries no image
KITTI_IMAGE_SHAPE = (375, 1242)


def in_camera_view(xyz_c: np.ndarray, P2: np.ndarray, image_shape: tuple[int, int]) -> np.ndarray:
    """(N,) bool: in front of the camera and projecting inside the image (``P2`` 3x4)."""
    homogeneous = xyz_c @ P2[:, :3].T + P2[:, 3]
    depth = homogeneous[:, 2]
    ahead = depth > 0.1  # metres: points behind or at the camera do not project
    safe = np.where(ahead, depth, 1.0)
    u, v = homogeneous[:, 0] / safe, homogeneous[:, 1] / safe
    rows, cols = image_shape
    return ahead & (u >= 0) & (u < cols) & (v >= 0) & (v < rows)


def frame_points(points_c: np.ndarray, P2: np.ndarray | None, image_shape: tuple[int, int] | None,
                 point_range) -> np.ndarray:
    """(K, 4) float32 x y z intensity in frame l of the scan ``points_c`` (N, 4, frame c) kept
    by the camera view (skipped without ``P2``) and ``point_range`` (frame l box)."""
    points_c = np.asarray(points_c, dtype=np.float32).reshape(-1, 4)
    keep = np.ones(len(points_c), dtype=bool)
    if P2 is not None:
        keep = in_camera_view(points_c[:, :3].astype(np.float64), np.asarray(P2, np.float64),
                              image_shape or KITTI_IMAGE_SHAPE)
    xyz = camera_to_lidar_points(points_c[keep, :3])
    low, high = np.asarray(point_range[:3]), np.asarray(point_range[3:])
    inside = ((xyz >= low) & (xyz <= high)).all(axis=1)
    return np.hstack([xyz[inside], points_c[keep][inside, 3:4]]).astype(np.float32)


def resample(points: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Exactly ``count`` rows of ``points``: a random subset, or every point plus random
    repeats when there are fewer (3DSSD's input sampling). An empty scan gives zeros."""
    if len(points) == 0:
        return np.zeros((count, points.shape[1] if points.ndim == 2 else 4), np.float32)
    if len(points) >= count:
        return points[rng.choice(len(points), count, replace=False)]
    extra = rng.choice(len(points), count - len(points), replace=True)
    return np.concatenate([points, points[extra]])


def image_shape_of(frame) -> tuple[int, int]:
    """The frame's left image size, else KITTI's."""
    image = getattr(frame, "image_left", None)
    return tuple(image.shape[:2]) if image is not None else KITTI_IMAGE_SHAPE
