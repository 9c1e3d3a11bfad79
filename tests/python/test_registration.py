"""GICP of object scans (twistslam.registration): real KITTI car scans of sequence 0001 moved by
a known motion, consecutive real frames of the same car, and the checks at the binding."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from twistslam import geometry
from twistslam import registration as reg
from twistslam.datasets import KittiTracking

#: Known-motion recovery on real scans (exact ground truth, 1 cm noise): the car centre within
#: 1 cm (the issue's target) and the rotation within 0.25 deg (the bench measures a median of
#: 0.14 deg on 0001's cars: the ring pattern leaves the yaw of a partial view weakly held).
CENTRE_TOLERANCE_M = 0.01
ROTATION_TOLERANCE_DEG = 0.25


def known_motion(centre: np.ndarray, dist_m: float, angle_deg: float, axis) -> np.ndarray:
    R = Rotation.from_rotvec(np.radians(angle_deg) * np.asarray(axis) / np.linalg.norm(axis))
    T = np.eye(4)
    T[:3, :3] = R.as_matrix()
    T[:3, 3] = centre - T[:3, :3] @ centre + [dist_m * 0.8, 0.0, dist_m * 0.6]
    return T


@pytest.fixture(scope="module")
def sequence(kitti_tracking_lidar):
    return KittiTracking(kitti_tracking_lidar, 1)


def car_box(seq: KittiTracking, frame: int, track_id: int) -> np.ndarray:
    table = seq.gt_objects.in_frame(frame)
    return table.box_3d[np.flatnonzero(table.track_id == track_id)[0]]


@pytest.mark.parametrize("frame,track_id", [(0, 0), (5, 1), (10, 2)])
def test_known_motion_of_a_real_car_scan_is_recovered(sequence, frame, track_id):
    box = car_box(sequence, frame, track_id)
    target = reg.object_scan(sequence.frame(frame).points_c, box)
    assert len(target) > 500  # a near car: hundreds of returns
    T_true = known_motion(box[:3], 0.5, 5.0, [0.1, 1.0, 0.05])  # mostly yaw, as cars turn
    rng = np.random.default_rng(frame)
    T_inv = np.linalg.inv(T_true)
    source = target @ T_inv[:3, :3].T + T_inv[:3, 3] + rng.normal(0.0, 0.01, target.shape)
    result = reg.gicp(source, target)  # from identity: 0.5 m and 5 deg away
    assert result.converged, result.status
    dt, dr = reg.motion_error(T_true, result.T_target_source, box[:3])
    assert dt < CENTRE_TOLERANCE_M and dr < ROTATION_TOLERANCE_DEG, (dt, dr)
    assert result.num_inliers > 0.95 * len(source)
    assert result.information.shape == (6, 6)
    assert np.all(np.linalg.eigvalsh(result.information) > 0)


def test_consecutive_real_frames_of_a_car_agree_with_the_labels(sequence):
    """Parked car 1 in frames i -> i + 1 from a prediction 0.3 m off the labels' motion.

    The labels' box difference is itself good to ~5-10 cm (it differs from the oxts ego-motion,
    the exact motion of a parked car, by 4-11 cm). GICP on real consecutive scans is not as
    good as on a moved copy: the two partial views differ, and every GICP in
    benchmarks/bench_gicp.py (ours, small_gicp, Open3D, PCL alike) ends ~2 deg off the labels
    (median; 90th percentile 6 deg) although labels and oxts agree to 0.1 deg. So the test asks
    for the centre within 0.15 m and at least twice closer to the labels than the prediction,
    and the rotation within 5 deg only: real consecutive scans do not give the issue's 0.1 deg.
    Frames 0-5 (car 6-13 m ahead, 500-1200 returns) are asserted; at frames 7-10 the car is
    2-5 m away and partly outside the scan, and GICP ends up to 9.6 deg / 0.18 m off
    (docs/registration.md)."""
    rng = np.random.default_rng(0)
    for frame in (0, 3, 5):
        box_a, box_b = car_box(sequence, frame, 1), car_box(sequence, frame + 1, 1)
        source = reg.object_scan(sequence.frame(frame).points_c, box_a)
        target = reg.object_scan(sequence.frame(frame + 1).points_c, box_b)
        T_labels = reg.box_motion(box_a, box_b)
        offset = rng.normal(size=3)
        T_init = T_labels.copy()
        T_init[:3, 3] += 0.3 * offset / np.linalg.norm(offset)
        result = reg.gicp(reg.make_scan(source), reg.make_scan(target), T_init=T_init)
        assert result.converged, (frame, result.status)
        init_error, _ = reg.motion_error(T_labels, T_init, box_b[:3])
        dt, dr = reg.motion_error(T_labels, result.T_target_source, box_b[:3])
        assert dt < 0.15 and dt < 0.5 * init_error and dr < 5.0, (frame, dt, dr)


def test_a_scan_built_once_gives_the_same_result_as_arrays(sequence):
    box = car_box(sequence, 4, 1)
    target = reg.object_scan(sequence.frame(4).points_c, box)
    T = known_motion(box[:3], 0.3, 3.0, [0, 1, 0])
    source = target @ np.linalg.inv(T)[:3, :3].T + np.linalg.inv(T)[:3, 3]
    scan_s, scan_t = reg.make_scan(source), reg.make_scan(target)
    assert scan_t.num_points == len(target) and scan_t.usable
    a = reg.gicp(scan_s, scan_t)
    b = reg.gicp(source, target)
    np.testing.assert_allclose(a.T_target_source, b.T_target_source, atol=1e-12)


def test_planar_link_keeps_the_motion_in_the_road_plane():
    rng = np.random.default_rng(1)
    # A box-shaped "car" 12 m ahead: three faces with 1 cm noise.
    faces = [np.c_[rng.uniform(-2, 2, 600), rng.uniform(-0.7, 0.7, 600), np.full(600, -0.85)],
             np.c_[np.full(400, -2.0), rng.uniform(-0.7, 0.7, 400), rng.uniform(-0.85, 0.85, 400)],
             np.c_[rng.uniform(-2, 2, 600), np.full(600, -0.7), rng.uniform(-0.85, 0.85, 600)]]
    target = np.vstack(faces) + [3.0, 1.0, 12.0] + rng.normal(0, 0.01, (1600, 3))
    T_true = known_motion(np.array([3.0, 1.0, 12.0]), 0.4, 4.0, [0.2, 1.0, 0.0])  # rolls too
    T_inv = np.linalg.inv(T_true)
    source = target @ T_inv[:3, :3].T + T_inv[:3, 3]
    Pi = np.asarray(geometry.projector_planar(np.array([0.0, 1.0, 0.0])))
    result = reg.gicp(source, target, projector=Pi)
    assert result.converged
    xi = np.asarray(geometry.se3_log(result.T_target_source))
    np.testing.assert_allclose(xi[[1, 3, 5]], 0.0, atol=1e-12)  # no lift, no roll, no pitch
    assert abs(xi[4]) > np.radians(2.0)  # but it did turn about the normal


def test_bad_input_is_a_status_or_a_clear_error():
    rng = np.random.default_rng(2)
    points = rng.uniform(-1, 1, (200, 3))
    empty = reg.gicp(np.zeros((0, 3)), points)
    assert not empty.converged and empty.status == "too_few_points"
    np.testing.assert_array_equal(empty.T_target_source, np.eye(4))
    with_nan = points.copy()
    with_nan[[3, 7]] = np.nan
    scan = reg.make_scan(with_nan)
    assert scan.num_dropped_non_finite == 2 and scan.num_points == 198
    assert np.isfinite(scan.points).all()
    assert reg.make_scan(points.astype(np.float32)).num_points == 200  # float32 accepted
    far = np.eye(4)
    far[0, 3] = 100.0
    assert reg.gicp(points, points, T_init=far).status == "too_few_correspondences"
    with pytest.raises(ValueError, match="points"):
        reg.make_scan(points[:, :2])
    with pytest.raises(ValueError, match="source"):
        reg.gicp(points[:, :2], points)
    with pytest.raises(ValueError, match="T_init"):
        reg.gicp(points, points, T_init=2.0 * np.eye(4))
    with pytest.raises(ValueError, match="projector"):
        reg.gicp(points, points, projector=np.eye(5))
    with pytest.raises(ValueError, match="max_iteration"):
        reg.gicp(points, points, max_iteration=3)  # typo: unknown option
    with pytest.raises(ValueError, match="kernel"):
        reg.gicp(points, points, kernel="cauchy")
    with pytest.raises(ValueError, match="max_correspondence_distance_m"):
        reg.gicp(points, points, max_correspondence_distance_m=0.0)
    with pytest.raises(ValueError, match="max_step_halvings"):
        reg.gicp(points, points, max_step_halvings=-1)
    assert set(reg.default_options()) >= {"max_correspondence_distance_m", "num_neighbors",
                                          "max_iterations", "kernel", "max_step_halvings"}


def test_limiting_step_halvings_keeps_the_accuracy_on_real_scans(sequence):
    """Consecutive real scans of car 1 (frames 0-5): the default (one halving of a rejected step)
    ends where unlimited halving does, within 1 cm and 0.2 deg (a tenth of the ~2 deg median
    error of real consecutive pairs against the labels; measured: up to 0.1 deg), in no more
    iterations (measured: 5-8 instead of 8-16)."""
    for frame in range(5):
        box_a, box_b = car_box(sequence, frame, 1), car_box(sequence, frame + 1, 1)
        source = reg.make_scan(reg.object_scan(sequence.frame(frame).points_c, box_a))
        target = reg.make_scan(reg.object_scan(sequence.frame(frame + 1).points_c, box_b))
        T_init = reg.box_motion(box_a, box_b)
        T_init[:3, 3] += [0.2, 0.0, -0.1]
        limited = reg.gicp(source, target, T_init=T_init)
        unlimited = reg.gicp(source, target, T_init=T_init, max_step_halvings=1000)
        assert limited.converged and unlimited.converged
        assert limited.iterations <= unlimited.iterations
        dt, dr = reg.motion_error(unlimited.T_target_source, limited.T_target_source, box_b[:3])
        assert dt < 0.01 and dr < 0.2, (frame, dt, dr)
