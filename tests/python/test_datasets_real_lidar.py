"""The readers on real KITTI scans: labelled car boxes hold the LiDAR points of their car.

Two collections of the data folder (``$TWISTSLAM_DATA``, see docs/design.md "Real data"):

- ``kitti_tracking_lidar``: tracking sequence 0001, frames 0-26, with stereo images, Velodyne
  scans, oxts, labels and PointRCNN detections, read by :class:`KittiTracking`;
- ``kitti_object``: KITTI object frames 000000-000010 (scan, left image, labels, calibration in
  the object spelling), read by :class:`KittiObject`.

Only those frames are used, so a folder pointing into a full KITTI download passes too.

A car's points are found in its box frame (``inv(T_c_o) X_c`` with ``T_c_o`` of
:func:`box_poses`), so these tests check the LiDAR -> camera chain of the calibration, the
box convention (geometric centre, ``l`` along object x, ``h`` along y, ``w`` along z) and the
readers together: any error in one of them empties the boxes.
"""

import warnings

import numpy as np
import pytest

from twistslam.datasets import (
    DONT_CARE,
    KittiObject,
    KittiTracking,
    box_poses,
    read_calibration,
    read_detections,
    read_labels,
)

N_FRAMES = 27  # frames 000000-000026 of sequence 0001
N_OBJECT_FRAMES = 11  # KITTI object frames 000000-000010
NEAR = 30.0  # m; an unoccluded, untruncated car closer than this is hit by many beams
MIN_POINTS = 50  # the fewest seen in such a box over the 27 frames is 69


def in_box_frame(points_c: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Points of the camera frame near ``box``, in the frame of the box (centre at the
    origin); points farther than the box's half diagonal + 1 m are left out (speed)."""
    xyz = points_c[:, :3].astype(np.float64)
    reach = np.linalg.norm(box[3:6]) / 2 + 1.0
    xyz = xyz[np.all(np.abs(xyz - box[:3]) < reach, axis=1)]
    T_o_c = np.linalg.inv(box_poses(box)[0])
    return xyz @ T_o_c[:3, :3].T + T_o_c[:3, 3]


def inside(points_o: np.ndarray, box: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """Mask of box-frame points inside the box grown by ``margin`` on every side."""
    half = np.array([box[3], box[5], box[4]]) / 2 + margin  # x: l, y: h, z: w
    return np.all(np.abs(points_o) <= half, axis=1)


def fit_ratio(points_c: np.ndarray, box: np.ndarray) -> tuple[int, int]:
    """Points within 5 cm of the box against points within 30 cm, the road (the lowest 20 cm
    of the box and below) left out: near 1 for a box that fits its car, low for a moved box."""
    p = in_box_frame(points_c, box)
    above_road = p[:, 1] < box[5] / 2 - 0.2  # camera y points down
    return int((inside(p, box, 0.05) & above_road).sum()), int((inside(p, box, 0.3) & above_road).sum())


def near_clear_cars(objects):
    cars = objects.of_class("Car")
    distance = np.linalg.norm(cars.box_3d[:, [0, 2]], axis=1)
    return cars.select((cars.occlusion == 0) & (cars.truncation == 0) & (distance < NEAR))


def assert_boxes_fit(ratios_fit, ratios_moved):
    fit, moved = np.asarray(ratios_fit), np.asarray(ratios_moved)
    assert len(fit) >= 10
    assert np.median(fit) > 0.95 and np.percentile(fit, 10) > 0.85
    # the same boxes moved 1 m sideways no longer fit: the test can fail
    assert np.median(moved) < 0.85


# -------------------------------------------------------------- tracking sequence 0001 + LiDAR
@pytest.fixture(scope="module")
def seq(kitti_tracking_lidar):
    return KittiTracking(kitti_tracking_lidar, "0001")


@pytest.fixture(scope="module")
def frames(seq):
    return [seq[i] for i in range(N_FRAMES)]


def test_every_modality_of_every_frame(seq, frames):
    assert len(seq) >= N_FRAMES
    for f in frames:
        assert f.image_left.shape == f.image_right.shape == (375, 1242, 3)
        assert f.image_left.dtype == np.uint8
        assert 100_000 < len(f.points_velo) == len(f.points_c) < 130_000
        np.testing.assert_array_equal(f.points_c[:, 3], f.points_velo[:, 3])  # intensity kept
        assert f.T_w_c_gt is not None and f.objects_gt is not None
    # the devkit spelling of this calibration: a 0.53 m stereo baseline
    assert 0.52 < seq.calib.baseline < 0.55
    assert "R_rect " in (seq.base / "calib" / "0001.txt").read_text()


def test_lidar_points_fill_the_labelled_car_boxes(frames):
    counts = []
    for f in frames:
        for box in near_clear_cars(f.objects_gt).box_3d:
            p = in_box_frame(f.points_c, box)
            n = int(inside(p, box).sum())
            counts.append(n)
            assert n >= MIN_POINTS, f"frame {f.index}: car at {box[:3].round(1)} holds {n} points"
            # the same points are inside by the independent corner test of the box frame
            held = p[inside(p, box)]
            assert np.all(np.abs(held) <= np.array([box[3], box[5], box[4]]) / 2 + 1e-9)
    assert len(counts) >= 20  # 24 such boxes over the 27 frames
    # the raw scan (LiDAR frame: x forward, z up) is not the camera frame: its boxes are empty
    f = frames[0]
    assert sum(int(inside(in_box_frame(f.points_velo, b), b).sum())
               for b in near_clear_cars(f.objects_gt).box_3d) < 10


def test_car_boxes_fit_their_points(frames):
    fit, moved = [], []
    for f in frames:
        for box in f.objects_gt.of_class("Car").box_3d:
            n5, n30 = fit_ratio(f.points_c, box)
            if n30 >= 30:
                fit.append(n5 / n30)
            n5, n30 = fit_ratio(f.points_c, box + [1.0, 0, 0, 0, 0, 0, 0])  # 1 m along camera x
            if n30 >= 30:
                moved.append(n5 / n30)
    assert_boxes_fit(fit, moved)


def test_oxts_poses_are_rigid_and_drive_forward(seq):
    T = seq.gt_poses[:N_FRAMES]
    assert T.shape == (N_FRAMES, 4, 4)
    np.testing.assert_allclose(T[0], np.eye(4), atol=1e-9)  # world = camera of frame 0
    R = T[:, :3, :3]
    # rotations to the precision of the 7-digit calibration the IMU poses are moved through
    np.testing.assert_allclose(R @ R.transpose(0, 2, 1), np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-6)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-6)
    np.testing.assert_array_equal(T[:, 3], np.broadcast_to([0.0, 0.0, 0.0, 1.0], (N_FRAMES, 4)))
    # ego car at about 10.5 m/s (oxts speed 10.7 -> 10.2 m/s): ~1.05 m per 0.1 s frame, give
    # or take the jitter of the frame times, forward along the camera z axis
    steps = np.linalg.inv(T[:-1]) @ T[1:]
    speed = np.linalg.norm(steps[:, :3, 3], axis=1) / 0.1
    assert 10.0 < speed.mean() < 11.0 and np.all((9.0 < speed) & (speed < 12.5))
    assert np.all(steps[:, 2, 3] > 0.95 * np.linalg.norm(steps[:, :3, 3], axis=1))


def test_parked_cars_stay_put_in_the_world(seq):
    """Labels and oxts together: a car whose world position is steady over the 27 frames
    (parked) moves less than the label noise, although the ego car drove ~28 m."""
    tracks = [t for t in seq.gt_tracks.values() if t.cls == "Car"]
    spread = [np.ptp(t.T_w_o[t.frames < N_FRAMES, :3, 3], axis=0).max() for t in tracks
              if np.sum(t.frames < N_FRAMES) >= 10]
    assert np.linalg.norm(seq.gt_poses[N_FRAMES - 1, :3, 3]) > 25.0
    assert sum(s < 0.5 for s in spread) >= 3


def test_pointrcnn_detections_sit_on_the_labelled_cars(kitti_tracking_lidar, frames):
    det = read_detections(kitti_tracking_lidar / "detections" / "pointrcnn_car_val" / "0001.txt")
    assert set(det.frame) >= set(range(N_FRAMES)) and set(det.cls) == {"Car"}
    found = []
    for f in frames:
        gt = near_clear_cars(f.objects_gt)
        d = det.in_frame(f.index).box_3d
        dist = np.linalg.norm(gt.box_3d[:, None, :3] - d[None, :, :3], axis=-1)
        found.extend(dist.min(axis=1) < 1.0)
    assert np.mean(found) > 0.9


def test_same_files_as_the_kitti_tracking_folder(kitti_tracking_lidar, kitti_tracking):
    """The 27-frame copy agrees with the full-length ground truth of sequence 0001, and its
    devkit-spelled calibration with the object-spelled one."""
    a = read_calibration(kitti_tracking_lidar / "training" / "calib" / "0001.txt")
    b = read_calibration(kitti_tracking / "training" / "calib" / "0001.txt")
    for name in ("P2", "P3", "R_rect", "Tr_velo_cam", "Tr_imu_velo"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-9, err_msg=name)
    short = read_labels(kitti_tracking_lidar / "training" / "label_02" / "0001.txt")
    full = read_labels(kitti_tracking / "training" / "label_02" / "0001.txt")
    assert short.select(short.frame < N_FRAMES).equals(full.select(full.frame < N_FRAMES))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the kitti_tracking folder has few images, no LiDAR
        full_poses = KittiTracking(kitti_tracking, "0001").gt_poses
    np.testing.assert_allclose(KittiTracking(kitti_tracking_lidar, "0001").gt_poses[:N_FRAMES],
                               full_poses[:N_FRAMES], atol=1e-6)


# ------------------------------------------------------------------- KITTI object frames
@pytest.fixture(scope="module")
def objects(kitti_object):
    return KittiObject(kitti_object)


def test_object_frames_read(objects):
    assert objects.ids[:N_OBJECT_FRAMES] == list(range(N_OBJECT_FRAMES))
    f = objects[1]
    assert f.index == 1 and f.image_right is None and f.T_w_c_gt is None
    assert sorted(f.objects_gt.cls) == ["Car", "Cyclist", *[DONT_CARE] * 4, "Truck"]
    assert np.all(f.objects_gt.track_id == -1) and np.all(f.objects_gt.frame == 1)
    # object spelling (R0_rect:, Tr_velo_to_cam:) read into the same fields
    rows = dict(line.split(":", 1) for line in objects.path("calib", 1).read_text().splitlines()
                if ":" in line)
    R0 = np.eye(4)
    R0[:3, :3] = np.array(rows["R0_rect"].split(), float).reshape(3, 3)
    Tr = np.eye(4)
    Tr[:3] = np.array(rows["Tr_velo_to_cam"].split(), float).reshape(3, 4)
    np.testing.assert_allclose(f.calib.T_c_velo, R0 @ Tr, atol=1e-12)
    X = f.points_velo[:5, :3].astype(np.float64)
    np.testing.assert_allclose(f.points_c[:5, :3], X @ (R0 @ Tr)[:3, :3].T + (R0 @ Tr)[:3, 3],
                               atol=1e-4)
    for frame in map(objects.frame, range(N_OBJECT_FRAMES)):
        h, w, _ = frame.image_left.shape
        assert 360 <= h <= 376 and 1220 <= w <= 1245  # object images vary by a few pixels
        real = frame.objects_gt.select(frame.objects_gt.cls != DONT_CARE)
        if len(real):  # label image boxes lie in their image
            assert np.all(real.box_2d[:, 2] <= w) and np.all(real.box_2d[:, 3] <= h)
        assert len(frame.points_c) == len(frame.points_velo) > 100_000


def test_object_car_boxes_hold_their_lidar_points(objects):
    cars_seen = 0
    fit, moved = [], []
    for f in map(objects.frame, range(N_OBJECT_FRAMES)):
        for box in near_clear_cars(f.objects_gt).box_3d:
            n = int(inside(in_box_frame(f.points_c, box), box).sum())
            assert n >= MIN_POINTS, f"frame {f.index:06d}: car at {box[:3].round(1)} holds {n}"
            cars_seen += 1
        for box in f.objects_gt.of_class("Car").box_3d:
            n5, n30 = fit_ratio(f.points_c, box)
            if n30 >= 30:
                fit.append(n5 / n30)
            n5, n30 = fit_ratio(f.points_c, box + [1.0, 0, 0, 0, 0, 0, 0])
            if n30 >= 30:
                moved.append(n5 / n30)
    assert cars_seen >= 8
    assert_boxes_fit(fit, moved)
