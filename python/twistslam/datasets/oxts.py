"""KITTI GPS/IMU (oxts) files -> ground-truth camera poses, and the exact inverse.

Each line holds 30 numbers: ``lat lon alt roll pitch yaw vn ve vf vl vu ax ay az af al au
wx wy wz wf wl wu pos_accuracy vel_accuracy navstat numsats posmode velmode orimode``.
The devkit turns the first six into IMU poses ``T_m_imu`` in a local Mercator frame ``m``
(x east, y north, z up, scale fixed by the latitude of the first line). docs/design.md wants
camera poses in the rectified camera frame of frame 0:
``T_w_c(i) = T_c_imu @ inv(T_m_imu(0)) @ T_m_imu(i) @ inv(T_c_imu)``.
"""

from __future__ import annotations

import numpy as np

from ._parsing import PathLike, ensure_parent, format_float, iter_lines, parse_error, to_floats
from .calibration import Calibration

EARTH_RADIUS = 6378137.0  # m, the devkit's (WGS84 equatorial) radius
N_COLUMNS = 30
# fill values written for the columns the poses do not determine (velocities, accelerations,
# rates and accuracies 0; navstat 4, 10 satellites, RTK modes as in typical KITTI drives)
_STATUS = (4, 10, 4, 4, 6)


def read_oxts(path: PathLike) -> np.ndarray:
    """Read an oxts file as an ``(N, 30)`` float64 array (one row per frame)."""
    rows = []
    for line_no, tokens in iter_lines(path):
        if len(tokens) != N_COLUMNS:
            raise parse_error(path, line_no, f"expected {N_COLUMNS} columns, got {len(tokens)}")
        rows.append(to_floats(tokens, path, line_no, "oxts"))
    return np.stack(rows) if rows else np.zeros((0, N_COLUMNS))


def _rotation_zyx(roll: np.ndarray, pitch: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` for arrays of angles -> (N, 3, 3)."""
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    R = np.empty((len(roll), 3, 3))
    R[:, 0] = np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], axis=-1)
    R[:, 1] = np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], axis=-1)
    R[:, 2] = np.stack([-sp, cp * sr, cp * cr], axis=-1)
    return R


def oxts_to_imu_poses(oxts: np.ndarray) -> np.ndarray:
    """Devkit conversion of oxts rows to IMU poses ``T_m_imu`` (N, 4, 4) in Mercator metres.

    Not re-based to the first frame: ``m`` is the Mercator frame itself, so these are the
    ``T_m_imu(i)`` of the module docstring.
    """
    oxts = np.asarray(oxts, dtype=np.float64)
    lat, lon, alt = oxts[:, 0], oxts[:, 1], oxts[:, 2]
    scale = np.cos(lat[0] * np.pi / 180.0)  # Mercator scale from the first line, as the devkit
    T = np.tile(np.eye(4), (len(oxts), 1, 1))
    T[:, 0, 3] = scale * lon * np.pi * EARTH_RADIUS / 180.0
    T[:, 1, 3] = scale * EARTH_RADIUS * np.log(np.tan((90.0 + lat) * np.pi / 360.0))
    T[:, 2, 3] = alt
    T[:, :3, :3] = _rotation_zyx(oxts[:, 3], oxts[:, 4], oxts[:, 5])
    return T


def oxts_to_camera_poses(oxts: np.ndarray, calib: Calibration) -> np.ndarray:
    """Camera poses ``T_w_c`` (N, 4, 4), world = rectified camera frame of frame 0."""
    T_m_imu = oxts_to_imu_poses(oxts)
    if len(T_m_imu) == 0:
        return T_m_imu
    # inv(T_m_imu(0)) @ T_m_imu(i), written out so that the Mercator coordinates (~5e6 m)
    # are subtracted before rotating: inv() @ would lose ~1e-10 m to cancellation
    R0, t0 = T_m_imu[0, :3, :3], T_m_imu[0, :3, 3]
    T_imu0_imu = np.tile(np.eye(4), (len(T_m_imu), 1, 1))
    T_imu0_imu[:, :3, :3] = R0.T @ T_m_imu[:, :3, :3]
    T_imu0_imu[:, :3, 3] = (T_m_imu[:, :3, 3] - t0) @ R0
    T_c_imu = calib.T_c_imu
    return T_c_imu @ T_imu0_imu @ np.linalg.inv(T_c_imu)


def read_oxts_poses(path: PathLike, calib: Calibration) -> np.ndarray:
    """Read an oxts file and return camera poses ``T_w_c`` (N, 4, 4)."""
    return oxts_to_camera_poses(read_oxts(path), calib)


def camera_poses_to_oxts(
    T_w_c: np.ndarray,
    calib: Calibration,
    lat0: float = 49.0,
    lon0: float = 8.4,
    alt0: float = 110.0,
) -> np.ndarray:
    """Exact inverse of :func:`oxts_to_camera_poses`: oxts rows (N, 30) for camera poses.

    The first IMU pose is placed at ``(lat0, lon0, alt0)`` with zero roll, pitch and yaw.
    Poses are taken relative to ``T_w_c[0]`` (the reader always returns identity at frame 0),
    so reading the rows back gives ``inv(T_w_c[0]) @ T_w_c``. Columns other than the pose
    are filled with zeros and plausible status values.
    """
    T_w_c = np.asarray(T_w_c, dtype=np.float64)
    if T_w_c.ndim != 3 or T_w_c.shape[1:] != (4, 4):
        raise ValueError(f"camera_poses_to_oxts: expected (N, 4, 4) poses, got {T_w_c.shape}")
    scale = np.cos(lat0 * np.pi / 180.0)
    T_m_imu0 = np.eye(4)
    T_m_imu0[:3, 3] = [
        scale * lon0 * np.pi * EARTH_RADIUS / 180.0,
        scale * EARTH_RADIUS * np.log(np.tan((90.0 + lat0) * np.pi / 360.0)),
        alt0,
    ]
    T_c_imu = calib.T_c_imu
    T_c0_c = np.linalg.inv(T_w_c[0]) @ T_w_c
    # invert T_w_c(i) = T_c_imu inv(T_m_imu0) T_m_imu(i) inv(T_c_imu) for T_m_imu(i)
    T_m_imu = T_m_imu0 @ np.linalg.inv(T_c_imu) @ T_c0_c @ T_c_imu
    R, t = T_m_imu[:, :3, :3], T_m_imu[:, :3, 3]

    rows = np.zeros((len(T_w_c), N_COLUMNS))
    rows[:, 1] = t[:, 0] * 180.0 / (scale * np.pi * EARTH_RADIUS)
    rows[:, 0] = 360.0 / np.pi * np.arctan(np.exp(t[:, 1] / (scale * EARTH_RADIUS))) - 90.0
    rows[:, 2] = t[:, 2]
    rows[0, :2] = lat0, lon0  # exact first row, so the reader's Mercator scale is exactly ours
    # R = Rz(yaw) Ry(pitch) Rx(roll), pitch in [-pi/2, pi/2]: the standard ZYX decomposition
    rows[:, 3] = np.arctan2(R[:, 2, 1], R[:, 2, 2])
    rows[:, 4] = np.arctan2(-R[:, 2, 0], np.hypot(R[:, 0, 0], R[:, 1, 0]))
    rows[:, 5] = np.arctan2(R[:, 1, 0], R[:, 0, 0])
    rows[:, 25:30] = _STATUS
    return rows


def write_oxts(
    path: PathLike,
    T_w_c: np.ndarray,
    calib: Calibration,
    lat0: float = 49.0,
    lon0: float = 8.4,
    alt0: float = 110.0,
) -> None:
    """Write an oxts file whose devkit conversion gives back ``T_w_c`` (see
    :func:`camera_poses_to_oxts`); numbers are written losslessly."""
    rows = camera_poses_to_oxts(T_w_c, calib, lat0, lon0, alt0)
    path = ensure_parent(path)
    with open(path, "w", encoding="utf-8") as f:
        for row in rows:
            status = " ".join(str(int(v)) for v in row[25:])
            f.write(" ".join(format_float(v) for v in row[:25]) + " " + status + "\n")
