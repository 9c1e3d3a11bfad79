"""KittiTracking on a small sequence built here, and on the real KITTI tracking files."""

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy.spatial.transform import Rotation

from twistslam.datasets import (
    DATASETS,
    Calibration,
    Frame,
    KittiTracking,
    MissingDataWarning,
    ObjectTable,
    Sequence,
    open_sequence,
    read_calibration,
    write_calibration,
    write_labels,
    write_oxts,
    write_poses,
    write_velodyne,
)

N_FRAMES, SEQ, H, W = 5, "0003", 6, 8


def make_calib():
    """A calibration with non-trivial R_rect and extrinsics (written in the devkit spelling)."""
    P2 = np.array([[700.0, 0, 4, 45.0], [0, 700, 3, 0.2], [0, 0, 1, 0.003]])
    P3 = P2.copy()
    P3[0, 3] = 45.0 - 0.54 * 700
    R_cam_velo = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    Tr_velo_cam = np.hstack([Rotation.from_rotvec([0.01, -0.02, 0.005]).as_matrix() @ R_cam_velo,
                             [[-0.004], [-0.076], [-0.27]]])
    return Calibration(P0=P2, P1=P2, P2=P2, P3=P3,
                       R_rect=Rotation.from_rotvec([0.004, -0.007, 0.01]).as_matrix(),
                       Tr_velo_cam=Tr_velo_cam,
                       Tr_imu_velo=np.hstack([np.eye(3), [[-0.8], [0.3], [-0.8]]]))


def make_poses():
    T = np.tile(np.eye(4), (N_FRAMES, 1, 1))
    for i in range(N_FRAMES):
        T[i, :3, :3] = Rotation.from_rotvec([0.0, -0.05 * i, 0.0]).as_matrix()
        T[i, :3, 3] = [-0.1 * i**2, 0.0, 1.2 * i]
    return T


def make_labels():
    rows = [(f, t) for f in range(N_FRAMES) for t in (0, 4) if not (f == 1 and t == 4)]
    n = len(rows)
    return ObjectTable(
        frame=[r[0] for r in rows], track_id=[r[1] for r in rows],
        cls=["Car" if r[1] == 0 else "Pedestrian" for r in rows], truncation=np.zeros(n),
        occlusion=np.zeros(n), alpha=np.full(n, 0.3), box_2d=np.tile([1.0, 1.0, 5.0, 4.0], (n, 1)),
        box_3d=[[r[0] * 0.5, 0.8, 10.0 + r[1], 4.0, 1.6, 1.5, 0.1] for r in rows], score=np.ones(n),
    )


@pytest.fixture
def kitti_root(tmp_path):
    """A complete 5-frame sequence 0003 with every modality."""
    base = tmp_path / "training"
    write_calibration(base / "calib" / f"{SEQ}.txt", make_calib())
    rng = np.random.default_rng(0)
    for i in range(N_FRAMES):
        for cam in ("image_02", "image_03"):
            (base / cam / SEQ).mkdir(parents=True, exist_ok=True)
            pixels = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
            Image.fromarray(pixels).save(base / cam / SEQ / f"{i:06d}.png")
        points = rng.normal(0, 10, (50 + i, 4)).astype(np.float32)
        write_velodyne(base / "velodyne" / SEQ / f"{i:06d}.bin", points)
    write_labels(base / "label_02" / f"{SEQ}.txt", make_labels())
    write_oxts(base / "oxts" / f"{SEQ}.txt", make_poses(), make_calib())
    return tmp_path


def record_warnings(fn):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = fn()
    return result, [w for w in caught if issubclass(w.category, MissingDataWarning)]


def test_length_indexing_and_iteration(kitti_root):
    seq, caught = record_warnings(lambda: KittiTracking(kitti_root, 3))
    assert caught == []
    assert isinstance(seq, Sequence)
    assert len(seq) == N_FRAMES
    assert seq[-1].index == N_FRAMES - 1 and seq[-N_FRAMES].index == 0
    for bad in (N_FRAMES, -N_FRAMES - 1):
        with pytest.raises(IndexError):
            seq[bad]
    with pytest.raises(TypeError):
        seq["1"]
    frames = list(seq)
    assert [f.index for f in frames] == list(range(N_FRAMES))
    f = frames[2]
    assert isinstance(f, Frame)
    assert f.image_left.shape == (H, W, 3) and f.image_left.dtype == np.uint8
    assert f.image_right.shape == (H, W, 3)
    assert not np.array_equal(f.image_left, f.image_right)
    assert f.points_velo.shape == (52, 4) and f.points_velo.dtype == np.float32
    np.testing.assert_allclose(seq.timestamps, 0.1 * np.arange(N_FRAMES))
    assert f.timestamp == pytest.approx(0.2)
    assert f.calib == make_calib()


def test_points_are_moved_into_the_rectified_camera_frame(kitti_root):
    seq = KittiTracking(kitti_root, SEQ)
    frame = seq[1]
    calib = make_calib()
    X_velo = frame.points_velo[:, :3].astype(np.float64)
    expected = (calib.R_rect @ (calib.Tr_velo_cam[:, :3] @ X_velo.T + calib.Tr_velo_cam[:, 3:])).T
    assert frame.points_c.dtype == np.float32 and frame.points_c.shape == frame.points_velo.shape
    np.testing.assert_allclose(frame.points_c[:, :3], expected, atol=1e-4)
    np.testing.assert_array_equal(frame.points_c[:, 3], frame.points_velo[:, 3])  # intensity


def test_ground_truth_poses_and_objects(kitti_root):
    seq = KittiTracking(kitti_root, SEQ)
    np.testing.assert_allclose(seq.gt_poses, make_poses(), atol=1e-6)  # from oxts
    np.testing.assert_allclose(seq[3].T_w_c_gt, make_poses()[3], atol=1e-6)
    assert len(seq.gt_objects) == len(make_labels())
    objects = seq[1].objects_gt
    assert list(objects.track_id) == [0]
    np.testing.assert_allclose(objects.box_3d, [[0.5, 0.8, 10.0, 4.0, 1.6, 1.5, 0.1]], atol=1e-6)
    # poses/ wins over oxts/ when both exist
    other = make_poses()
    other[:, 0, 3] += 1.0
    write_poses(kitti_root / "training" / "poses" / f"{SEQ}.txt", other)
    np.testing.assert_array_equal(KittiTracking(kitti_root, SEQ).gt_poses, other)


def test_ground_truth_tracks_are_world_poses(kitti_root):
    seq = KittiTracking(kitti_root, SEQ)
    tracks = seq.gt_tracks
    assert sorted(tracks) == [0, 4]
    car, person = tracks[0], tracks[4]
    assert car.cls == "Car" and person.cls == "Pedestrian"
    np.testing.assert_array_equal(person.frames, [f for f in range(N_FRAMES) if f != 1])
    # T_w_o = T_w_c @ T_c_o: the box centre seen from the camera, moved into the world
    for k, f in enumerate(car.frames):
        centre_c = np.array([f * 0.5, 0.8, 10.0, 1.0])
        np.testing.assert_allclose(car.T_w_o[k] @ [0, 0, 0, 1], make_poses()[f] @ centre_c, atol=1e-6)
        # the object's x axis (its length) is camera x rotated by ry about camera y
        axis_c = np.array([np.cos(0.1), 0.0, -np.sin(0.1)])
        np.testing.assert_allclose(car.T_w_o[k][:3, 0], make_poses()[f][:3, :3] @ axis_c, atol=1e-6)
    np.testing.assert_allclose(car.size, np.tile([4.0, 1.6, 1.5], (N_FRAMES, 1)), atol=1e-6)
    assert car.velocity.shape == (N_FRAMES - 1, 3)


def test_timestamps_file(kitti_root):
    times = 1.5 + 0.1037 * np.arange(N_FRAMES)
    (kitti_root / "training" / "timestamps").mkdir()
    (kitti_root / "training" / "timestamps" / f"{SEQ}.txt").write_text(
        "".join(f"{float(t)!r}\n" for t in times))
    seq = KittiTracking(kitti_root, SEQ)
    np.testing.assert_array_equal(seq.timestamps, times)
    assert seq[4].timestamp == times[4]


def test_frames_load_lazily(kitti_root):
    seq = KittiTracking(kitti_root, SEQ)
    velodyne = kitti_root / "training" / "velodyne" / SEQ
    (velodyne / "000004.bin").write_bytes(b"\0" * 20)  # corrupt after opening: not read yet
    image = kitti_root / "training" / "image_02" / SEQ / "000001.png"
    Image.fromarray(np.full((H, W, 3), 7, np.uint8)).save(image)
    assert np.all(seq[1].image_left == 7)  # read at access time, not at construction
    assert seq[0].points_velo is not None
    with pytest.raises(ValueError, match=r"velodyne/0003/000004\.bin.*multiple of 16"):
        seq[4]


def test_frame_without_lidar_does_not_read_the_scan(kitti_root):
    seq = KittiTracking(kitti_root, SEQ)
    (kitti_root / "training" / "velodyne" / SEQ / "000004.bin").write_bytes(b"\0" * 20)
    frame = seq.frame(4, lidar=False)  # the corrupt scan is never opened
    assert frame.points_c is None and frame.points_velo is None
    assert frame.image_left is not None and frame.T_w_c_gt is not None
    assert seq.frame(2).points_c is not None  # lidar=True (the default) is seq[i]


def test_stereo_loader_skips_the_lidar(kitti_root):
    from twistslam.inputs import load_frame

    (kitti_root / "training" / "velodyne" / SEQ / "000004.bin").write_bytes(b"\0" * 20)
    frame = load_frame(KittiTracking(kitti_root, SEQ), 4)
    assert frame.index == 4 and frame.points_c is None and frame.image_right is not None


def test_nan_points_are_dropped_with_a_warning(kitti_root):
    path = kitti_root / "training" / "velodyne" / SEQ / "000000.bin"
    points = np.fromfile(path, dtype=np.float32).reshape(-1, 4)
    points[[3, 7], 1] = np.nan
    write_velodyne(path, points)
    frame, caught = record_warnings(lambda: KittiTracking(kitti_root, SEQ)[0])
    assert len(frame.points_velo) == len(points) - 2
    assert np.isfinite(frame.points_c).all()
    assert len(caught) == 1 and "000000.bin" in str(caught[0].message)


def test_missing_modality_warns_once_and_the_rest_loads(kitti_root):
    shutil.rmtree(kitti_root / "training" / "image_03")
    (kitti_root / "training" / "velodyne" / SEQ / "000002.bin").unlink()

    def load_all():
        return list(KittiTracking(kitti_root, SEQ))

    frames, caught = record_warnings(load_all)
    messages = [str(w.message) for w in caught]
    assert len(messages) == 2, messages
    assert sum(str(kitti_root / "training" / "image_03" / SEQ) in m for m in messages) == 1
    assert sum("000002.bin" in m for m in messages) == 1
    assert all(f.image_right is None for f in frames)
    assert all(f.image_left is not None and f.objects_gt is not None for f in frames)
    assert frames[2].points_c is None and frames[3].points_c is not None
    assert len(frames) == N_FRAMES


def test_length_without_images(kitti_root):
    for name in ("image_02", "image_03", "velodyne"):
        shutil.rmtree(kitti_root / "training" / name)
    seq, caught = record_warnings(lambda: KittiTracking(kitti_root, SEQ))
    assert len(caught) == 3
    assert len(seq) == N_FRAMES  # from labels / oxts
    assert seq[4].points_c is None and seq[4].T_w_c_gt is not None


def test_missing_calibration_names_the_file(kitti_root):
    with pytest.raises(FileNotFoundError, match=r"calib/0007\.txt"):
        KittiTracking(kitti_root, 7)


def test_open_sequence(kitti_root):
    assert DATASETS["kitti_tracking"] is KittiTracking
    by_root = open_sequence(kitti_root, 3)
    by_path = open_sequence(kitti_root / "training" / "image_02" / SEQ)
    by_calib = open_sequence(kitti_root / "training" / "calib" / f"{SEQ}.txt")
    for seq in (by_root, by_path, by_calib):
        assert isinstance(seq, KittiTracking) and seq.seq == SEQ and len(seq) == N_FRAMES
    assert open_sequence(by_root) is by_root
    with pytest.raises(ValueError, match="unknown dataset"):
        open_sequence(kitti_root, 3, dataset="nuscenes")
    with pytest.raises(ValueError, match="not a KITTI sequence"):
        open_sequence(kitti_root / "elsewhere" / "0003")


def test_real_sequence_with_partial_modalities(kitti_tracking):
    """The kitti_tracking folder: labels, calibration and oxts of 0001 and a few (or, in a
    full download, all) left images; frames without an image get None and one warning."""
    seq, caught = record_warnings(lambda: KittiTracking(kitti_tracking, 1))
    missing = {m for m in ("image_03", "velodyne")
               if not (kitti_tracking / "training" / m / "0001").is_dir()}
    assert missing <= {m for w in caught for m in missing if m in str(w.message)}
    assert read_calibration(kitti_tracking / "training" / "calib" / "0001.txt") == seq.calib
    assert seq.gt_objects is not None and len(seq.gt_objects) == 4271
    assert len(seq) == int(seq.gt_objects.frame.max()) + 1 == 447
    # oxts/0001.txt: one rigid camera pose per frame, the world is the first camera frame
    assert seq.gt_poses is not None and seq.gt_poses.shape == (447, 4, 4)
    np.testing.assert_allclose(seq.gt_poses[0], np.eye(4), atol=1e-9)
    R = seq.gt_poses[:, :3, :3]
    np.testing.assert_allclose(R @ R.transpose(0, 2, 1), np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-6)

    def load():
        return [seq[i] for i in range(0, 25)]

    frames, caught = record_warnings(load)
    on_disk = sorted(int(p.stem) for p in (kitti_tracking / "training" / "image_02" / "0001")
                     .glob("*.png") if int(p.stem) < 25)
    assert {10, 15, 20} <= set(on_disk)
    image_warnings = [w for w in caught if "image_02" in str(w.message)]
    first_missing = next((i for i in range(25) if i not in on_disk), None)
    if first_missing is None:
        assert not image_warnings
    else:
        assert len(image_warnings) == 1
        assert f"{first_missing:06d}.png" in str(image_warnings[0].message)
    assert [f.index for f in frames if f.image_left is not None] == on_disk
    assert frames[10].image_left.shape == (375, 1242, 3)
    assert all(f.T_w_c_gt is not None for f in frames)
    np.testing.assert_array_equal(frames[10].T_w_c_gt, seq.gt_poses[10])
    if "velodyne" in missing:
        assert all(f.points_c is None for f in frames)
    if "image_03" in missing:
        assert all(f.image_right is None for f in frames)
    assert len(frames[10].objects_gt) == np.sum(seq.gt_objects.frame == 10) > 0
