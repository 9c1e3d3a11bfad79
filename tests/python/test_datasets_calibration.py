"""Calibration reader/writer against the real KITTI tracking calibration files."""

import numpy as np
import pytest

from twistslam import geometry
from twistslam.datasets import Calibration, read_calibration, write_calibration

#: the 21 sequences of the KITTI tracking training split
TRAINING_SEQS = [f"{i:04d}" for i in range(21)]
MATRICES = ("P0", "P1", "P2", "P3", "R_rect", "Tr_velo_cam", "Tr_imu_velo")


@pytest.mark.parametrize("seq", TRAINING_SEQS)
def test_every_real_calibration_reads(kitti_tracking, seq):
    calib = read_calibration(kitti_tracking / "training" / "calib" / f"{seq}.txt")
    assert 0.50 < calib.baseline < 0.56
    # R_rect is a rotation, the extrinsics have rotation blocks
    np.testing.assert_allclose(calib.R_rect @ calib.R_rect.T, np.eye(3), atol=1e-5)
    np.testing.assert_allclose(np.linalg.det(calib.T_c_velo[:3, :3]), 1.0, atol=1e-5)
    np.testing.assert_allclose(calib.K, calib.P2[:, :3])
    assert calib.K[0, 0] > 600 and calib.K[2, 2] == 1.0


def test_composed_transforms_follow_design(kitti_tracking):
    calib = read_calibration(kitti_tracking / "training" / "calib" / "0001.txt")
    X_velo = np.array([10.0, 2.0, -1.0, 1.0])
    # by hand: rectify (3x3) after the 3x4 velodyne -> camera extrinsics
    X_expected = calib.R_rect @ (calib.Tr_velo_cam @ X_velo)
    np.testing.assert_allclose((calib.T_c_velo @ X_velo)[:3], X_expected, atol=1e-12)
    X_imu = np.array([1.0, -3.0, 0.5, 1.0])
    X_velo = np.append(calib.Tr_imu_velo @ X_imu, 1.0)
    np.testing.assert_allclose(
        (calib.T_c_imu @ X_imu)[:3], calib.R_rect @ (calib.Tr_velo_cam @ X_velo), atol=1e-12
    )
    # a LiDAR point straight ahead (velo x forward) is in front of the camera (z forward)
    assert (calib.T_c_velo @ np.array([20.0, 0.0, 0.0, 1.0]))[2] > 19


def test_both_spellings_give_identical_matrices(tmp_path, kitti_tracking):
    original = kitti_tracking / "training" / "calib" / "0005.txt"
    text = original.read_text()
    assert "R0_rect:" in text or "R_rect " in text  # KITTI ships both spellings
    calib = read_calibration(original)
    write_calibration(tmp_path / "devkit.txt", calib)
    text = (tmp_path / "devkit.txt").read_text()
    assert "R_rect " in text and "Tr_velo_cam " in text and "Tr_imu_velo " in text
    assert ":" not in text
    again = read_calibration(tmp_path / "devkit.txt")
    for name in MATRICES:
        np.testing.assert_array_equal(getattr(again, name), getattr(calib, name), err_msg=name)
    assert again == calib


def _write_lines(path, lines):
    path.write_text("\n".join(lines) + "\n")
    return path


def _devkit_lines():
    eye34 = " ".join(["1", "0", "0", "0", "0", "1", "0", "0", "0", "0", "1", "0"])
    p3 = eye34.replace("1 0 0 0", "1 0 0 -0.5", 1)
    return [f"P0: {eye34}", f"P1: {eye34}", f"P2: {eye34}", f"P3 {p3}",
            "R_rect 1 0 0 0 1 0 0 0 1", f"Tr_velo_cam {eye34}", f"Tr_imu_velo {eye34}"]


def test_mixed_spellings_and_baseline(tmp_path):
    calib = read_calibration(_write_lines(tmp_path / "c.txt", _devkit_lines()))
    assert calib.baseline == pytest.approx(0.5)
    np.testing.assert_array_equal(calib.T_c_imu, np.eye(4))


def test_malformed_value_names_file_line_and_key(tmp_path):
    lines = _devkit_lines()
    lines[4] = "R_rect 1 0 0 0 1 0 0 0"  # 8 of 9 values, on line 5
    path = _write_lines(tmp_path / "bad.txt", lines)
    with pytest.raises(ValueError, match=r"bad\.txt:5: R_rect: expected 9 values, got 8"):
        read_calibration(path)
    lines = _devkit_lines()
    lines[1] = lines[1].replace("0 1 0 0", "0 x 0 0")
    with pytest.raises(ValueError, match=r"bad\.txt:2: P1.*'x'"):
        read_calibration(_write_lines(tmp_path / "bad.txt", lines))


def test_missing_key_names_file_and_key(tmp_path):
    path = _write_lines(tmp_path / "short.txt", _devkit_lines()[:-1])
    with pytest.raises(ValueError, match=r"short\.txt: missing key Tr_imu_velo"):
        read_calibration(path)


def test_stereo_camera_from_geometry_module():
    P2 = np.array([[700.0, 0, 600, 45.0], [0, 700, 170, 0.2], [0, 0, 1, 0.003]])
    P3 = P2.copy()
    P3[0, 3] = 45.0 - 0.54 * 700
    eye34 = np.eye(3, 4)
    calib = Calibration(P0=P2, P1=P2, P2=P2, P3=P3, R_rect=np.eye(3),
                        Tr_velo_cam=eye34, Tr_imu_velo=eye34)
    cam = calib.stereo_camera(1242, 375)
    assert isinstance(cam, geometry.StereoCamera)
    assert cam.baseline == pytest.approx(0.54)
    assert (cam.width, cam.height) == (1242, 375)
    X = np.array([[1.0, -0.5, 12.0]])
    uv = (P2 @ np.append(X[0], 1.0))
    np.testing.assert_allclose(cam.project(X)[0], uv[:2] / uv[2], atol=1e-6)


def test_simulator_default_is_kitti_sequence_0000(kitti_tracking):
    """The simulator's built-in calibration holds every digit of calib/0000.txt."""
    from twistslam.sim.world import load_calibration

    built_in = load_calibration(None, 1242, 375)
    assert built_in == read_calibration(kitti_tracking / "training" / "calib" / "0000.txt")
