"""LiDAR for the camera (issue 9, section 2): a scan's metric depth fixes a wrong stereo scale,
a frame without a scan falls back to stereo, and the disparity offset config is validated."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import twistslam
from twistslam import Config
from twistslam.datasets import KittiTracking
from twistslam.datasets.calibration import read_calibration, write_calibration
from twistslam.sim.generate import generate
from twistslam.slam import Slam

#: how much longer than the true one the corrupted calibration's baseline is
BASELINE_ERROR = 0.05


def path_length(poses: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1).sum())


@pytest.fixture(scope="module")
def wrong_baseline_sequence(tmp_path_factory) -> KittiTracking:
    """A simulated static drive whose calibration states a 5 % longer baseline than the one
    the images were rendered with: stereo depth (fx b / d) comes out 5 % too long."""
    root = generate(tmp_path_factory.mktemp("sim") / "static", "static", frames=12,
                    progress=False)
    calib_path = root / "training" / "calib" / "0000.txt"
    calib = read_calibration(calib_path)
    P3 = calib.P3.copy()
    fx = calib.P2[0, 0]
    baseline = calib.baseline
    P3[0, 3] = calib.P2[0, 3] - fx * baseline * (1 + BASELINE_ERROR)  # right camera moved out
    write_calibration(calib_path, dataclasses.replace(calib, P3=P3))
    sequence = KittiTracking(root, "0000")
    assert sequence.calib.baseline == pytest.approx(baseline * (1 + BASELINE_ERROR), rel=1e-4)
    assert sequence.lidar_vertical_offset_deg == 0.0  # simulated scans are exact
    return sequence


def run_ratio(sequence: KittiTracking, *overrides: str) -> float:
    config = Config().override(list(overrides))
    result = twistslam.run(sequence, config, progress=False)
    assert (result.status != "lost").all()
    gt = sequence.gt_poses[result.frames]
    assert path_length(gt) > 5.0
    return path_length(result.camera_poses) / path_length(gt)


def test_lidar_depth_recovers_the_true_scale(wrong_baseline_sequence):
    stereo = run_ratio(wrong_baseline_sequence, "lidar.use_depth=false",
                       "lidar.disparity_offset=0")
    with_lidar = run_ratio(wrong_baseline_sequence)  # LiDAR depth + the offset estimate
    assert stereo > 1 + 0.6 * BASELINE_ERROR, f"stereo alone should inherit the error: {stereo}"
    assert abs(with_lidar - 1.0) < 0.015, f"with LiDAR depth: {with_lidar}"


def test_frames_without_a_scan_fall_back_to_stereo(kitti_tracking_lidar):
    sequence = KittiTracking(kitti_tracking_lidar, "0001")
    slam = Slam(Config(), sequence.calib)
    counts = []
    for i in range(6):
        frame = sequence[i]
        if i % 2:
            frame.points_c = None  # this frame has no scan
        out = slam.track(frame)
        assert out.status in ("initialized", "ok"), (i, out.status)
        counts.append(out.num_lidar_depth)
        assert ("lidar_depth" in out.timings_ms) == (i % 2 == 0)
    assert all(c > 200 for c in counts[::2]), counts  # ~600 keypoints get a LiDAR depth
    assert counts[1::2] == [0, 0, 0]
    assert slam.disparity_offset is not None and 0.3 < slam.disparity_offset < 1.2


def test_disparity_offset_config_is_checked():
    assert Config().override("lidar.disparity_offset=0.7").lidar.fixed_disparity_offset() == 0.7
    assert Config().lidar.fixed_disparity_offset() is None  # "auto"
    for bad in ("nan", "inf", "12", "fast"):
        with pytest.raises(ValueError, match="lidar.disparity_offset"):
            Config().override(f"lidar.disparity_offset={bad}")
    with pytest.raises(ValueError, match="lidar.search_radius_px"):
        Config().override("lidar.search_radius_px=1e30")
