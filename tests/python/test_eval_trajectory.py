"""Camera and object ATE / RPE against evo on the same seeded random trajectories."""

from __future__ import annotations

import copy

import evo.core.metrics as evo_metrics
import numpy as np
import pytest
from evo.core.trajectory import PosePath3D
from scipy.spatial.transform import Rotation

from twistslam import geometry
from twistslam.eval.camera import evaluate_camera
from twistslam.eval.object_poses import MIN_RPE_PATH_M, box_poses, track_pose_errors, world_poses
from twistslam.eval.trajectory import umeyama_alignment


def random_walk(rng: np.random.Generator, n: int, step: float = 1.0, turn: float = 0.05):
    """(n, 4, 4) smooth-ish trajectory: each pose = previous @ small random motion."""
    poses = [np.eye(4)]
    for _ in range(n - 1):
        d = np.eye(4)
        d[:3, :3] = Rotation.from_rotvec(rng.normal(0, turn, 3)).as_matrix()
        d[:3, 3] = rng.normal([0, 0, step], 0.2)
        poses.append(poses[-1] @ d)
    return np.stack(poses)


def perturb(rng: np.random.Generator, poses: np.ndarray, sigma_t: float, sigma_r: float):
    out = poses.copy()
    for T in out:
        T[:3, :3] = Rotation.from_rotvec(rng.normal(0, sigma_r, 3)).as_matrix() @ T[:3, :3]
        T[:3, 3] += rng.normal(0, sigma_t, 3)
    return out


def evo_ape(gt, est, align=False):
    ref, e = PosePath3D(poses_se3=list(gt)), PosePath3D(poses_se3=list(est))
    if align:
        e = copy.deepcopy(e)
        e.align(ref, correct_scale=False)
    m = evo_metrics.APE(evo_metrics.PoseRelation.translation_part)
    m.process_data((ref, e))
    return m


def evo_rpe(gt, est, relation):
    ref, e = PosePath3D(poses_se3=list(gt)), PosePath3D(poses_se3=list(est))
    m = evo_metrics.RPE(relation, delta=1, delta_unit=evo_metrics.Unit.frames, all_pairs=False)
    m.process_data((ref, e))
    return m


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_camera_metrics_equal_evo(seed):
    rng = np.random.default_rng(seed)
    gt = random_walk(rng, 60)
    # a drifting estimate: noise plus a rigid offset, so aligned and unaligned ATE differ
    offset = np.eye(4)
    offset[:3, :3] = Rotation.from_rotvec([0.02, 0.1, -0.03]).as_matrix()
    offset[:3, 3] = [0.5, -0.2, 1.0]
    est = offset @ perturb(rng, gt, 0.05, 0.01)

    ours = evaluate_camera(gt, est)
    rpe_t = evo_rpe(gt, est, evo_metrics.PoseRelation.translation_part)
    rpe_r = evo_rpe(gt, est, evo_metrics.PoseRelation.rotation_angle_deg)
    stat = evo_metrics.StatisticsType
    assert ours.rpe_t_mean == pytest.approx(rpe_t.get_statistic(stat.mean), abs=1e-6)
    assert ours.rpe_t_rmse == pytest.approx(rpe_t.get_statistic(stat.rmse), abs=1e-6)
    assert ours.rpe_r_mean == pytest.approx(rpe_r.get_statistic(stat.mean), abs=1e-6)
    assert ours.rpe_r_rmse == pytest.approx(rpe_r.get_statistic(stat.rmse), abs=1e-6)
    assert ours.ate_rmse_unaligned == pytest.approx(
        evo_ape(gt, est).get_statistic(stat.rmse), abs=1e-6)
    assert ours.ate_rmse == pytest.approx(
        evo_ape(gt, est, align=True).get_statistic(stat.rmse), abs=1e-6)
    # the JSON value is the aligned one, and alignment must matter on this input
    assert ours.to_dict()["ate_rmse"] == ours.ate_rmse
    assert ours.ate_rmse < 0.5 * ours.ate_rmse_unaligned
    assert ours.n_skipped == 0 and ours.n_pairs == 59


def test_camera_skips_nan_and_missing_frames():
    rng = np.random.default_rng(3)
    gt = random_walk(rng, 30)
    est = perturb(rng, gt, 0.05, 0.01)[:27]  # last 3 frames missing
    est[[5, 6, 12]] = np.nan
    ours = evaluate_camera(gt, est)
    assert ours.n_skipped == 6 and ours.n_evaluated == 24
    # pairs (i, i+1) with both ends present: 26 pairs among frames 0..26 minus 5 broken
    assert ours.n_pairs == 26 - 5
    ok = np.r_[np.arange(5), np.arange(7, 12), np.arange(13, 27)]
    ate = evo_ape(gt[ok], est[ok], align=True).get_statistic(evo_metrics.StatisticsType.rmse)
    assert ours.ate_rmse == pytest.approx(ate, abs=1e-9)
    # RPE only over adjacent frames: equal to evo on each contiguous run, pooled
    runs = [np.arange(0, 5), np.arange(7, 12), np.arange(13, 27)]
    errs = np.concatenate([evo_rpe(gt[r], est[r], evo_metrics.PoseRelation.translation_part).error
                           for r in runs])
    assert ours.rpe_t_mean == pytest.approx(errs.mean(), abs=1e-9)


def test_umeyama_recovers_a_rigid_transform():
    rng = np.random.default_rng(4)
    src = rng.normal(size=(40, 3))
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.3, -1.2, 2.0]).as_matrix()
    T[:3, 3] = [1.0, 2.0, -3.0]
    dst = src @ T[:3, :3].T + T[:3, 3]
    np.testing.assert_allclose(umeyama_alignment(src, dst), T, atol=1e-12)


def test_umeyama_never_returns_a_reflection():
    # a mirrored point set: the unconstrained least-squares "rotation" would be a reflection
    rng = np.random.default_rng(7)
    src = rng.normal(size=(30, 3))
    dst = src * [1.0, 1.0, -1.0] + [0.3, 0.0, 2.0]
    T = umeyama_alignment(src, dst)
    assert np.linalg.det(T[:3, :3]) == pytest.approx(1.0)
    from evo.core.geometry import umeyama_alignment as evo_umeyama

    R, t, _ = evo_umeyama(src.T, dst.T, with_scale=False)
    np.testing.assert_allclose(T[:3, :3], R, atol=1e-9)
    np.testing.assert_allclose(T[:3, 3], t, atol=1e-9)


def boxes_of(poses_w_o, T_w_c):
    """Boxes [cx cy cz l w h ry] of objects at poses T_w_o, seen from cameras T_w_c.

    Objects only rotate about the camera y axis (as KITTI boxes do), so every pose is
    representable by a box."""
    T_c_o = np.linalg.inv(T_w_c) @ poses_w_o
    ry = np.arctan2(T_c_o[:, 0, 2], T_c_o[:, 0, 0])
    size = np.tile([4.2, 1.7, 1.5], (len(ry), 1))  # l w h
    return np.column_stack([T_c_o[:, :3, 3], size, ry])


def planar_walk(rng, n, yaw_sigma=0.05):
    """Poses rotating about y only (cars and a camera on flat ground)."""
    poses, T = [], np.eye(4)
    for _ in range(n):
        d = np.eye(4)
        d[:3, :3] = Rotation.from_rotvec([0, rng.normal(0, yaw_sigma), 0]).as_matrix()
        d[:3, 3] = [rng.normal(0, 0.1), 0.0, rng.normal(1.0, 0.2)]
        T = T @ d
        poses.append(T)
    return np.stack(poses)


@pytest.mark.parametrize("seed", [5, 6])
def test_object_track_errors_equal_evo(seed):
    rng = np.random.default_rng(seed)
    n = 40
    T_w_c = planar_walk(rng, n)
    gt_obj = planar_walk(rng, n)
    gt_obj[:, :3, 3] += [3.0, 1.0, 10.0]
    est_obj = gt_obj.copy()
    # planar noise (yaw and ground-plane translation) keeps the estimate representable by boxes
    for T in est_obj:
        T[:3, :3] = Rotation.from_rotvec([0, rng.normal(0, 0.03), 0]).as_matrix() @ T[:3, :3]
        T[:3, 3] += [rng.normal(0, 0.1), 0, rng.normal(0, 0.1)]
    est_obj[:, :3, 3] += [0.4, 0.0, -0.3]  # a constant bias: canonical and aligned ATE differ

    frames = np.arange(100, 100 + n)
    gt_boxes, est_boxes = boxes_of(gt_obj, T_w_c), boxes_of(est_obj, T_w_c)
    Q, _ = world_poses(frames - 100, gt_boxes, T_w_c)
    P, _ = world_poses(frames - 100, est_boxes, T_w_c)
    np.testing.assert_allclose(Q, gt_obj, atol=1e-9)  # box -> pose round trip

    # the estimate misses 5 frames: both sides are compared on the 35 common ones
    keep = np.ones(n, dtype=bool)
    keep[[3, 4, 17, 30, 39]] = False
    ours = track_pose_errors(frames, Q, frames[keep], P[keep])
    Qc, Pc = Q[keep], P[keep]
    stat = evo_metrics.StatisticsType
    assert ours.n_frames == 35
    assert ours.ate == pytest.approx(evo_ape(Qc, Pc).get_statistic(stat.rmse), abs=1e-6)
    assert ours.ate_aligned == pytest.approx(
        evo_ape(Qc, Pc, align=True).get_statistic(stat.rmse), abs=1e-6)
    assert ours.ate_aligned < ours.ate
    gt_dist = np.linalg.norm(np.diff(Qc[:, :3, 3], axis=0), axis=1).sum()
    rpe_t = evo_rpe(Qc, Pc, evo_metrics.PoseRelation.translation_part).error
    rpe_r = evo_rpe(Qc, Pc, evo_metrics.PoseRelation.rotation_angle_deg).error
    assert ours.length == pytest.approx(gt_dist, abs=1e-9)
    assert ours.rpe_t == pytest.approx(rpe_t.sum() / gt_dist, abs=1e-6)
    assert ours.rpe_r == pytest.approx(rpe_r.sum() / gt_dist, abs=1e-6)


def test_parked_object_has_no_rpe_per_metre():
    boxes = np.tile([1.0, 1.0, 10.0, 4.0, 1.7, 1.5, 0.3], (5, 1))
    P = box_poses(boxes)
    r = track_pose_errors(np.arange(5), P, np.arange(5), P)
    assert r.ate == 0.0 and np.isnan(r.rpe_t) and np.isnan(r.rpe_r)


@pytest.mark.parametrize("step_m, has_rpe", [(0.02, False), (0.2, True)])
def test_crawling_object_below_the_minimum_path_has_no_rpe_per_metre(step_m, has_rpe):
    """A car waiting at a light (2 cm/frame over 30 frames: 0.6 m) with 1 cm label noise
    has no RPE per metre (it would read ~0.9 m/m); the same car at 0.2 m/frame (6 m) has."""
    n = 31
    boxes = np.tile([1.0, 1.0, 10.0, 4.0, 1.7, 1.5, 0.0], (n, 1))
    boxes[:, 2] += step_m * np.arange(n)
    noisy = boxes.copy()
    noisy[:, 0] += np.random.default_rng(3).normal(0.0, 0.01, n)
    r = track_pose_errors(np.arange(n), box_poses(boxes), np.arange(n), box_poses(noisy))
    assert r.length == pytest.approx(step_m * (n - 1))
    assert r.ate > 0.005
    if has_rpe:
        assert r.length >= MIN_RPE_PATH_M and 0.0 < r.rpe_t < 0.1 and np.isfinite(r.rpe_r)
    else:
        assert r.length < MIN_RPE_PATH_M and np.isnan(r.rpe_t) and np.isnan(r.rpe_r)
        assert track_pose_errors(np.arange(n), box_poses(boxes), np.arange(n), box_poses(noisy),
                                 min_path_m=0.0).rpe_t > 0.3  # what the table used to print


def test_box_pose_matches_geometry_corners():
    boxes = np.array([[1.0, 1.5, 12.0, 4.0, 1.6, 1.4, 0.7], [-3.0, 1.0, 20.0, 3.5, 1.8, 1.5, -2.1]])
    T = box_poses(boxes)
    l, w, h = boxes[:, 3:4], boxes[:, 4:5], boxes[:, 5:6]
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) / 2
    for i in range(2):
        # object frame: x along the length, y down (height), z along the width
        local = signs * np.array([l[i, 0], h[i, 0], w[i, 0]])
        ours = local @ T[i, :3, :3].T + T[i, :3, 3]
        theirs = geometry.box_corners(boxes[i : i + 1])[0]
        # same corner set, whatever the order
        d = np.linalg.norm(ours[:, None] - theirs[None], axis=2)
        assert d.min(axis=1).max() < 1e-9
