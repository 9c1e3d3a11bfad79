"""LiDAR road points in the road plane fit (issue 11, paper sec. "Injecting LiDAR scans"):
returns of the frame's scan on road pixels join the stereo road keypoints of each keyframe.
On a short simulated sequence the plane fitted with them matches the simulator's true road,
the smooth height field its streets are laid on, against the first camera."""

from __future__ import annotations

import numpy as np
import pytest

import twistslam
from twistslam.datasets import KittiTracking
from twistslam.perception.panoptic_files import read_sim_panoptic
from twistslam.sim import generate
from twistslam.sim.scenario import scenario_config
from twistslam.sim.world import World

FRAMES = 12
SEED = 0


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    root = tmp_path_factory.mktemp("road_lidar")
    generate(root, "urban", frames=FRAMES, seed=SEED, progress=False, overwrite=True)
    return root


def track(sim, road_lidar_points: bool) -> twistslam.Slam:
    """Every frame through the SLAM with the simulator's class image and scan."""
    config = twistslam.Config()
    config.visual_objects.road_lidar_points = road_lidar_points
    sequence = KittiTracking(sim, "0000")
    slam = twistslam.Slam(config, sequence.calib)
    for i in range(FRAMES):
        frame = sequence[i]
        assert frame.points_c is not None and len(frame.points_c) > 10000
        labels = read_sim_panoptic(sim / "training" / "panoptic" / "0000" / f"{i:06d}.png")
        slam.track(frame, labels.class_id)
    return slam


def true_road_plane(keyframes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, d) of the least-squares plane through the simulator's road surface 5-25 m ahead of
    every keyframe (+-4 m across), in the world frame (the first camera); and those samples."""
    cfg = scenario_config("urban")
    cfg.frames, cfg.seed = FRAMES, SEED
    world = World(cfg)
    T_c0_m = np.linalg.inv(world.T_m_c[0])
    samples = []
    for n in keyframes:
        T_m_c = world.T_m_c[int(n)]
        ahead = T_m_c[:2, 2] / np.linalg.norm(T_m_c[:2, 2])  # optical axis, horizontal
        across = np.array([-ahead[1], ahead[0]])
        a, b = np.meshgrid(np.arange(5.0, 25.5, 1.0), np.arange(-4.0, 4.5, 1.0))
        xy = T_m_c[:2, 3] + a.reshape(-1, 1) * ahead + b.reshape(-1, 1) * across
        X_m = world.terrain.lift(xy)
        samples.append(X_m @ T_c0_m[:3, :3].T + T_c0_m[:3, 3])
    X = np.concatenate(samples)
    centre = X.mean(0)
    normal = np.linalg.svd(X - centre, full_matrices=False)[2][2]
    normal = -normal if normal[1] > 0 else normal  # up is -y in a camera frame
    return np.r_[normal, -normal @ centre], X


def test_lidar_road_points_join_the_fit_and_give_the_true_plane(sim):
    with_lidar, stereo_only = track(sim, True), track(sim, False)
    road, alone = with_lidar.road_plane(), stereo_only.road_plane()
    assert road["valid"] and alone["valid"]
    # the scan's road returns joined the reservoir: up to road_lidar_max_points per keyframe
    keyframes = with_lidar.keyframes()["frame_index"]
    assert len(keyframes) >= 3
    cap = twistslam.Config().visual_objects.road_lidar_max_points
    assert alone["num_points"] + 100 * len(keyframes) < road["num_points"]
    assert road["num_points"] <= alone["num_points"] + cap * len(keyframes)
    truth, samples = true_road_plane(keyframes)
    n, d = road["plane"][:3], road["plane"][3]
    # measured on this sequence: 0.023 deg, 0.04 cm and a mean height difference of 0.14 cm
    # over the road samples (stereo keypoints alone: 0.093 deg, 0.005 cm, 0.42 cm); the
    # height field's samples lie 0.09 cm RMS from their plane over 12 frames
    assert np.degrees(np.arccos(np.clip(n @ truth[:3], -1.0, 1.0))) < 0.06
    assert abs(d - truth[3]) < 0.01
    assert np.abs(samples @ n + d).mean() < 0.005

