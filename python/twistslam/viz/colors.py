"""Colours of the view: the Cityscapes palette of class ids and a stable colour per track."""

from __future__ import annotations

import colorsys

import numpy as np

#: Cityscapes label id -> RGB, the colours of the Cityscapes label table
CITYSCAPES_COLORS: dict[int, tuple[int, int, int]] = {
    0: (0, 0, 0), 1: (0, 0, 0), 2: (0, 0, 0), 3: (0, 0, 0), 4: (0, 0, 0),
    5: (111, 74, 0), 6: (81, 0, 81), 7: (128, 64, 128), 8: (244, 35, 232),
    9: (250, 170, 160), 10: (230, 150, 140), 11: (70, 70, 70), 12: (102, 102, 156),
    13: (190, 153, 153), 14: (180, 165, 180), 15: (150, 100, 100), 16: (150, 120, 90),
    17: (153, 153, 153), 18: (153, 153, 153), 19: (250, 170, 30), 20: (220, 220, 0),
    21: (107, 142, 35), 22: (152, 251, 152), 23: (70, 130, 180), 24: (220, 20, 60),
    25: (255, 0, 0), 26: (0, 0, 142), 27: (0, 0, 70), 28: (0, 60, 100), 29: (0, 0, 90),
    30: (0, 0, 110), 31: (0, 80, 100), 32: (0, 0, 230), 33: (119, 11, 32),
}

#: colour of the static map points
STATIC_POINT_COLOR = (150, 150, 150)
#: colour of the frame's LiDAR returns (the paper's figure 1 (d) draws them black on white;
#: the viewer's background is dark)
LIDAR_COLOR = (210, 210, 210)
#: colour of the LiDAR returns on the road (green, as in the paper's figure 1 (d))
ROAD_LIDAR_COLOR = (40, 200, 60)
#: colour of the camera trajectory
CAMERA_TRAJECTORY_COLOR = (255, 200, 0)

_GOLDEN_RATIO_CONJUGATE = 0.618033988749895


def track_color(track_id: int) -> tuple[int, int, int]:
    """A saturated colour that depends on the track id only (stable over a run).

    Parameters
    ----------
    track_id : int
        Object track id (instance id for instance masks).

    Returns
    -------
    tuple of int
        RGB in 0..255; consecutive ids get well separated hues.
    """
    hue = (int(track_id) * _GOLDEN_RATIO_CONJUGATE) % 1.0
    value = 0.95 if int(track_id) % 2 == 0 else 0.8
    red, green, blue = colorsys.hsv_to_rgb(hue, 0.85, value)
    return int(round(red * 255)), int(round(green * 255)), int(round(blue * 255))


def rotation_to_quaternion_xyzw(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternion ``(x, y, z, w)`` of a rotation matrix.

    Parameters
    ----------
    rotation : (3, 3) array
        Rotation matrix (orthonormal, det +1).

    Returns
    -------
    (4,) float64 array
        The quaternion with ``w >= 0``.
    """
    r = np.asarray(rotation, dtype=np.float64)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0.0:  # Shepperd's method: divide by the largest of the four candidates
        s = 2.0 * np.sqrt(trace + 1.0)
        q = [(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s]
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s]
    quaternion = np.asarray(q)
    quaternion /= np.linalg.norm(quaternion)
    return -quaternion if quaternion[3] < 0.0 else quaternion
