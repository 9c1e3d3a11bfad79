"""Issue 11's yaw error and 3D TP / MOTP of object tracks on synthetic ground truth."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from twistslam.datasets import ObjectTable, write_labels, write_poses
from twistslam.eval.object_tracks import (
    GtTrack, SequenceGroundTruth, detection_rates, evaluate_object_tracks,
)
from twistslam.eval.object_yaw import heading, heading_error_deg, mean_yaw_error_deg
from twistslam.objects.result import TrackedObject

FRAMES = 30
SIZE = np.array([4.0, 1.8, 1.5])  # l, w, h (m)


def pose(yaw_deg=0.0, t=(0.0, 0.0, 0.0)):
    """A KITTI box pose: rotation R_y(yaw) about the camera's y (down), then ``t``."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.0, np.deg2rad(yaw_deg), 0.0]).as_matrix()
    T[:3, 3] = t
    return T


def test_heading_is_kitti_ry_and_errors_wrap_modulo_2pi():
    ry = np.deg2rad([-170.0, -30.0, 0.0, 45.0, 179.0])
    np.testing.assert_allclose(heading(np.stack([pose(np.rad2deg(a)) for a in ry])), ry, atol=1e-12)
    # 350 deg apart is 10 deg; opposite directions are 180, not 0 (mod pi would say 0)
    np.testing.assert_allclose(heading_error_deg(np.deg2rad([175.0, 90.0, 10.0]),
                                                 np.deg2rad([-175.0, -90.0, 10.0])),
                               [10.0, 180.0, 0.0], atol=1e-9)


def test_mean_yaw_error_of_offset_and_flipped_tracks():
    gt = np.stack([pose(yaw, (1.0, 1.5, 10.0 + k)) for k, yaw in enumerate(np.linspace(-60, 80, 10))])
    offset = gt @ pose(3.0)  # 3 deg heading offset in every frame
    flipped = gt @ pose(180.0)  # same box, driving the wrong way
    assert mean_yaw_error_deg(gt, offset) == pytest.approx(3.0, abs=1e-9)
    assert mean_yaw_error_deg(gt, flipped) == pytest.approx(180.0, abs=1e-9)
    half = np.concatenate([offset[:5], flipped[5:]])
    assert mean_yaw_error_deg(gt, half) == pytest.approx((5 * 3.0 + 5 * 180.0) / 10, abs=1e-9)
    assert np.isnan(mean_yaw_error_deg(gt[:0], gt[:0]))
    with pytest.raises(ValueError, match="ground-truth poses"):
        mean_yaw_error_deg(gt, gt[:3])


def synthetic_world():
    """A camera driving forward and one moving car ahead; the SLAM world is a rigid
    transform ``A`` of the ground-truth world (camera and object alike)."""
    T_w_c = np.stack([pose(0.5 * f, (0.0, 0.0, 1.0 * f)) for f in range(FRAMES)])
    T_w_o = np.stack([pose(-90.0 + 1.0 * f, (2.0, 0.8, 12.0 + 1.2 * f)) for f in range(FRAMES)])
    car = GtTrack(7, "Car", True, np.arange(FRAMES), T_w_o, SIZE, np.ones(FRAMES, bool),
                  np.full(FRAMES, 80.0))
    A = pose(20.0, (3.0, -1.0, 4.0))
    return SequenceGroundTruth(T_w_c=T_w_c, tracks={7: car}), A


def estimate(track_id, T_w_o):
    n = len(T_w_o)
    return TrackedObject(track_id=track_id, cls="Car", state="confirmed", link="planar",
                         frames=np.arange(n), T_w_o=T_w_o, size=SIZE, velocity_kmh=np.zeros(n),
                         detected=np.ones(n, bool), reported=np.ones(n, bool), score=np.ones(n),
                         mean_score=1.0)


@pytest.mark.parametrize("yaw_offset_deg, expected_deg", [(0.0, 0.0), (4.0, 4.0), (180.0, 180.0)])
def test_yaw_error_of_a_track_in_a_drifted_slam_world(yaw_offset_deg, expected_deg):
    gt, A = synthetic_world()
    est = estimate(70, A @ gt.tracks[7].T_w_o @ pose(yaw_offset_deg))
    ev = evaluate_object_tracks([est], A @ gt.T_w_c, gt, canonical_ids={70})
    assert ev.cars[0].est_ids == [70]
    assert ev.cars[0].yaw_deg == pytest.approx(expected_deg, abs=1e-6)
    assert ev.summary()["yaw_deg"] == pytest.approx(expected_deg, abs=1e-6)


def test_yaw_error_only_for_canonical_tracks():
    gt, A = synthetic_world()
    est = estimate(70, A @ gt.tracks[7].T_w_o @ pose(30.0))
    assert np.isnan(evaluate_object_tracks([est], A @ gt.T_w_c, gt, canonical_ids=[]).cars[0].yaw_deg)
    assert evaluate_object_tracks([est], A @ gt.T_w_c, gt).cars[0].yaw_deg == pytest.approx(30.0)


def test_yaw_error_of_a_camera_only_track_from_its_box_frame():
    gt, A = synthetic_world()
    # a cluster's object frame keeps the world axes at birth; its box frame carries the
    # heading the output gave it (objects/camera_boxes.py), 5 deg off here
    T_o_box = pose(-90.0 + 5.0)
    T_w_o = A @ gt.tracks[7].T_w_o @ np.linalg.inv(T_o_box) @ pose(5.0)
    est = estimate(70, T_w_o)
    plain = evaluate_object_tracks([est], A @ gt.T_w_c, gt, canonical_ids=[])
    assert np.isnan(plain.cars[0].yaw_deg)  # no box frame: not evaluated
    ev = evaluate_object_tracks([est], A @ gt.T_w_c, gt, canonical_ids=[],
                                box_frames={70: T_o_box})
    assert ev.cars[0].yaw_deg == pytest.approx(5.0, abs=1e-6)
    turned = evaluate_object_tracks([est], A @ gt.T_w_c, gt, canonical_ids=[],
                                    box_frames={70: T_o_box @ pose(180.0)})
    assert turned.cars[0].yaw_deg == pytest.approx(175.0, abs=1e-6)
    # a canonical track's own frame is its box: box_frames does not apply to it
    canon = evaluate_object_tracks([est], A @ gt.T_w_c, gt, canonical_ids=[70],
                                   box_frames={70: T_o_box})
    assert canon.cars[0].yaw_deg == pytest.approx(
        evaluate_object_tracks([est], A @ gt.T_w_c, gt).cars[0].yaw_deg)


def boxes(frames, track_ids, x, z, ry, score=None):
    """An ObjectTable of cars: geometric centre (x, 1.0, z) in the camera frame, size SIZE."""
    n = len(frames)
    box_3d = np.column_stack([x, np.full(n, 1.0), z, np.tile(SIZE, (n, 1)), ry])
    return ObjectTable(frame=np.asarray(frames), track_id=np.asarray(track_ids),
                       cls=np.full(n, "Car"), truncation=np.zeros(n), occlusion=np.zeros(n, int),
                       alpha=np.zeros(n), box_2d=np.tile([500.0, 150.0, 700.0, 250.0], (n, 1)),
                       box_3d=box_3d, score=np.ones(n) if score is None else score)


def kitti_root(tmp_path, labels):
    """A KITTI tracking layout holding only what the evaluator reads: labels and calibration."""
    base = tmp_path / "training"
    write_labels(base / "label_02" / "0000.txt", labels)
    (base / "calib").mkdir(parents=True)
    P = "700 0 600 0 0 700 180 0 0 0 1 0"
    eye34 = "1 0 0 0 0 1 0 0 0 0 1 0"
    (base / "calib" / "0000.txt").write_text(
        f"P0 {P}\nP1 {P}\nP2 {P}\nP3 {P}\nR_rect 1 0 0 0 1 0 0 0 1\n"
        f"Tr_velo_cam {eye34}\nTr_imu_velo {eye34}\n")
    write_poses(base / "poses" / "0000.txt", np.tile(np.eye(4), (FRAMES, 1, 1)))
    return tmp_path


def test_detection_rates_3d_of_a_known_shift(tmp_path):
    frames = np.arange(10)
    z = 15.0 + frames
    labels = boxes(frames, np.full(10, 3), np.zeros(10), z, np.zeros(10))
    root = kitti_root(tmp_path, labels)
    # ry = 0: the box length lies along the camera x axis; a 1 m shift along it leaves an
    # overlap of (l - 1) / (l + 1) of the union. Frames 8-9 are shifted 3.5 m: IoU
    # 0.5 / 7.5 < 0.25, so they are misses and leave the MOTP out
    shift = np.where(frames < 8, 1.0, 3.5)
    est = boxes(frames, np.full(10, 11), shift, z, np.zeros(10))
    rates = detection_rates(root, "0000", est)
    tp, motp = rates[3]
    assert tp == pytest.approx(80.0)
    assert motp == pytest.approx(100.0 * (SIZE[0] - 1.0) / (SIZE[0] + 1.0), abs=0.05)
    assert detection_rates(root, "0000", est, gt_ids=[4]) == {}
    tp_none, motp_none = detection_rates(root, "0000", est.select(est.frame < 0))[3]
    assert tp_none == 0.0 and np.isnan(motp_none)
