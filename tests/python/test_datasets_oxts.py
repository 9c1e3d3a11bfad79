"""oxts -> camera poses (devkit Mercator conversion), its exact inverse, and pose files."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from twistslam.datasets import (
    Calibration,
    read_oxts,
    read_oxts_poses,
    read_poses,
    write_oxts,
    write_poses,
)

EARTH_RADIUS = 6378137.0
# camera axes (x right, y down, z forward) in IMU axes (x forward, y left, z up)
R_CAM_IMU = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])


def axis_aligned_calib(lever_arm=(0.3, -0.8, 1.1)) -> Calibration:
    """Calibration whose T_c_imu is an exact axis permutation plus a lever arm."""
    P = np.array([[700.0, 0, 600, 0], [0, 700, 180, 0], [0, 0, 1, 0]])
    Tr_velo_cam = np.hstack([R_CAM_IMU, np.zeros((3, 1))])  # velodyne axes = IMU axes
    Tr_imu_velo = np.hstack([np.eye(3), np.reshape(lever_arm, (3, 1))])
    return Calibration(P0=P, P1=P, P2=P, P3=P, R_rect=np.eye(3), Tr_velo_cam=Tr_velo_cam,
                       Tr_imu_velo=Tr_imu_velo)


def real_like_calib() -> Calibration:
    """A calibration with small non-trivial rotations everywhere (as KITTI's)."""
    calib = axis_aligned_calib()
    calib.R_rect = Rotation.from_rotvec([0.004, -0.007, 0.01]).as_matrix()
    R_small = Rotation.from_rotvec([0.01, 0.02, -0.015]).as_matrix()
    calib.Tr_velo_cam[:, :3] = R_small @ R_CAM_IMU
    calib.Tr_velo_cam[:, 3] = [-0.004, -0.076, -0.27]
    calib.Tr_imu_velo[:, :3] = Rotation.from_rotvec([-0.002, 0.015, 0.001]).as_matrix()
    return calib


def oxts_line(lat, lon, alt, roll=0.0, pitch=0.0, yaw=0.0) -> str:
    rest = ["0"] * 19 + ["4", "10", "4", "4", "6"]
    pose = [repr(float(v)) for v in (lat, lon, alt, roll, pitch, yaw)]
    return " ".join(pose + rest)


def mercator_scale(lat0):
    return np.cos(np.radians(lat0))


def test_hand_checked_forward_step(tmp_path):
    # heading east (yaw 0), 10 m forward = 10 m east: longitude grows by 10 m of Mercator x
    lat, lon = 49.0, 8.4
    dlon = 10.0 * 180.0 / (mercator_scale(lat) * np.pi * EARTH_RADIUS)
    path = tmp_path / "oxts.txt"
    path.write_text(oxts_line(lat, lon, 110.0) + "\n" + oxts_line(lat, lon + dlon, 110.0) + "\n")
    assert read_oxts(path).shape == (2, 30)
    T_w_c = read_oxts_poses(path, axis_aligned_calib())
    np.testing.assert_allclose(T_w_c[0], np.eye(4), atol=1e-12)
    np.testing.assert_allclose(T_w_c[1][:3, 3], [0.0, 0.0, 10.0], atol=1e-6)
    np.testing.assert_allclose(T_w_c[1][:3, :3], np.eye(3), atol=1e-12)


def test_hand_checked_north_step_and_left_turn(tmp_path):
    # heading north (yaw +90 deg), 5 m north, then turning left by 0.1 rad on the spot
    lat, lon, yaw = 49.0, 8.4, np.pi / 2
    scale = mercator_scale(lat)
    y0 = scale * EARTH_RADIUS * np.log(np.tan(np.radians(90.0 + lat) / 2))
    lat1 = np.degrees(2 * np.arctan(np.exp((y0 + 5.0) / (scale * EARTH_RADIUS)))) - 90.0
    lines = [oxts_line(lat, lon, 110.0, yaw=yaw), oxts_line(lat1, lon, 110.0, yaw=yaw),
             oxts_line(lat1, lon, 110.0, yaw=yaw + 0.1)]
    (tmp_path / "oxts.txt").write_text("\n".join(lines) + "\n")
    T_w_c = read_oxts_poses(tmp_path / "oxts.txt", axis_aligned_calib(lever_arm=(0, 0, 0)))
    np.testing.assert_allclose(T_w_c[1][:3, 3], [0.0, 0.0, 5.0], atol=1e-6)
    # a left turn swings the camera z axis towards -x: rotation about camera y by -0.1 rad
    R_expected = Rotation.from_rotvec([0.0, -0.1, 0.0]).as_matrix()
    np.testing.assert_allclose(T_w_c[2][:3, :3], R_expected, atol=1e-12)
    np.testing.assert_allclose(T_w_c[2][:3, 3], [0.0, 0.0, 5.0], atol=1e-6)


def curved_trajectory(n=60) -> np.ndarray:
    """Camera poses on a climbing left curve with rolling and pitching (all axes excited)."""
    t = np.arange(n) * 0.1
    T = np.tile(np.eye(4), (n, 1, 1))
    heading = 0.4 * t + 0.05 * t**2  # rotation about camera -y (left turn)
    pitch = 0.05 * np.sin(1.3 * t)
    roll = 0.08 * np.cos(0.9 * t)
    for i in range(n):
        T[i, :3, :3] = Rotation.from_euler("YXZ", [-heading[i], pitch[i], roll[i]]).as_matrix()
    speed = 12.0
    T[:, 0, 3] = -np.cumsum(speed * 0.1 * np.sin(heading))
    T[:, 1, 3] = -0.5 * t**1.5  # climbing (y is down)
    T[:, 2, 3] = np.cumsum(speed * 0.1 * np.cos(heading))
    T[:, :3, 3] -= T[0, :3, 3]
    T[0] = np.eye(4)
    return T


@pytest.mark.parametrize("calib", [axis_aligned_calib(), real_like_calib()], ids=["axis", "real"])
@pytest.mark.parametrize("origin", [(49.0, 8.4, 110.0), (-33.9, 151.2, 5.0)], ids=["ka", "syd"])
def test_write_read_round_trip(tmp_path, calib, origin):
    T_w_c = curved_trajectory()
    assert np.ptp(T_w_c[:, 0, 3]) > 10 and np.ptp(T_w_c[:, 1, 3]) > 0.5  # really curved/3D
    path = tmp_path / "0000.txt"
    write_oxts(path, T_w_c, calib, *origin)
    rows = read_oxts(path)
    assert rows.shape == (len(T_w_c), 30)
    np.testing.assert_allclose(rows[0, :3], origin)
    assert np.abs(rows[:, 3]).max() > 0.01 and np.abs(rows[:, 4]).max() > 0.01  # roll, pitch
    back = read_oxts_poses(path, calib)
    np.testing.assert_allclose(back[:, :3, 3], T_w_c[:, :3, 3], atol=1e-6)
    rot_err = Rotation.from_matrix(back[:, :3, :3].transpose(0, 2, 1) @ T_w_c[:, :3, :3])
    assert rot_err.magnitude().max() < 1e-8


def test_round_trip_rebases_on_first_pose(tmp_path):
    calib = real_like_calib()
    T_w_c = curved_trajectory(10)
    offset = np.eye(4)
    offset[:3, :3] = Rotation.from_rotvec([0.1, 0.5, -0.2]).as_matrix()
    offset[:3, 3] = [3.0, -1.0, 7.0]
    write_oxts(tmp_path / "o.txt", offset @ T_w_c, calib)
    np.testing.assert_allclose(read_oxts_poses(tmp_path / "o.txt", calib), T_w_c, atol=1e-6)


def test_malformed_oxts_line(tmp_path):
    path = tmp_path / "oxts.txt"
    path.write_text(oxts_line(49.0, 8.4, 110.0) + "\n" + "49.0 8.4 110.0 0 0\n")
    with pytest.raises(ValueError, match=r"oxts\.txt:2: expected 30 columns, got 5"):
        read_oxts(path)


def test_poses_round_trip_is_exact(tmp_path):
    T_w_c = curved_trajectory(25)
    write_poses(tmp_path / "poses.txt", T_w_c)
    lines = (tmp_path / "poses.txt").read_text().splitlines()
    assert len(lines) == 25 and all(len(line.split()) == 12 for line in lines)
    np.testing.assert_array_equal(read_poses(tmp_path / "poses.txt"), T_w_c)


def test_poses_reader_layout_and_errors(tmp_path):
    path = tmp_path / "poses.txt"
    path.write_text("1 0 0 4 0 1 0 5 0 0 1 6\n\n1 0 0 0 0 1 0 0 0 0 1\n")
    with pytest.raises(ValueError, match=r"poses\.txt:3: expected 12 values, got 11"):
        read_poses(path)
    path.write_text("1 0 0 4 0 1 0 5 0 0 1 6\n")
    poses = read_poses(path)
    assert poses.shape == (1, 4, 4)
    np.testing.assert_array_equal(poses[0, :3, 3], [4, 5, 6])  # row-major 3x4
    np.testing.assert_array_equal(poses[0, 3], [0, 0, 0, 1])
    with pytest.raises(ValueError, match="shape"):
        write_poses(path, np.eye(4))
