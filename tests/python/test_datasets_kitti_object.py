"""KittiObject and read_object_labels on small frames built here (real frames: see
test_datasets_real_lidar.py)."""

import shutil
import warnings

import numpy as np
import pytest
from PIL import Image
from scipy.spatial.transform import Rotation

import twistslam.datasets as datasets
from twistslam.datasets import (
    DONT_CARE,
    Calibration,
    Frame,
    KittiObject,
    MissingDataWarning,
    read_object_labels,
    write_calibration,
    write_velodyne,
)

CAR = "Car 0.12 1 -1.57 599.41 156.40 629.75 189.25 1.50 1.60 4.00 1.00 1.65 20.00 0.30"
DONT = "DontCare -1 -1 -10 503.89 169.71 590.61 190.13 -1 -1 -1 -1000 -1000 -1000 -10"
H, W = 6, 8


def make_calib() -> Calibration:
    P2 = np.array([[700.0, 0, 4, 45.0], [0, 700, 3, 0.2], [0, 0, 1, 0.003]])
    R_cam_velo = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    return Calibration(
        P0=P2, P1=P2, P2=P2, P3=P2,
        R_rect=Rotation.from_rotvec([0.004, -0.007, 0.01]).as_matrix(),
        Tr_velo_cam=np.hstack([R_cam_velo, [[-0.004], [-0.076], [-0.27]]]),
        Tr_imu_velo=np.hstack([np.eye(3), [[-0.8], [0.3], [-0.8]]]),
    )


@pytest.fixture
def object_root(tmp_path):
    """Frames 000003 and 000007 of a KITTI object layout (calib, label_2, velodyne, image_2)."""
    base = tmp_path / "training"
    rng = np.random.default_rng(0)
    for i in (3, 7):
        write_calibration(base / "calib" / f"{i:06d}.txt", make_calib())
        (base / "label_2").mkdir(parents=True, exist_ok=True)
        (base / "label_2" / f"{i:06d}.txt").write_text(f"{CAR}\n{DONT}\n")
        points = np.hstack([rng.uniform(-20, 20, (50, 3)), rng.uniform(0, 1, (50, 1))])
        write_velodyne(base / "velodyne" / f"{i:06d}.bin", points)
        (base / "image_2").mkdir(parents=True, exist_ok=True)
        Image.fromarray(np.full((H, W, 3), i, np.uint8)).save(base / "image_2" / f"{i:06d}.png")
    return tmp_path


def test_object_labels_are_the_tracking_columns_without_frame_and_track(tmp_path):
    path = tmp_path / "000005.txt"
    path.write_text(f"{CAR}\n\n{DONT} \n{CAR} 0.75\n")
    table = read_object_labels(path, frame=5)
    assert len(table) == 3 and list(table.cls) == ["Car", DONT_CARE, "Car"]
    assert np.all(table.frame == 5) and np.all(table.track_id == -1)
    assert table.truncation[0] == pytest.approx(0.12) and table.occlusion[0] == 1
    # geometric centre: KITTI's bottom-centre y minus half the height; [l, w, h] order
    np.testing.assert_allclose(table.box_3d[0], [1.0, 1.65 - 0.75, 20.0, 4.0, 1.6, 1.5, 0.3])
    np.testing.assert_allclose(table.box_2d[0], [599.41, 156.40, 629.75, 189.25])
    assert table.alpha[0] == pytest.approx(-1.57)
    np.testing.assert_array_equal(table.box_3d[1], [-1000, -1000, -1000, -1, -1, -1, -10])
    np.testing.assert_allclose(table.score, [1.0, 1.0, 0.75])  # labels score 1, results keep theirs
    (tmp_path / "empty.txt").write_text("")
    assert len(read_object_labels(tmp_path / "empty.txt")) == 0


def test_malformed_object_label_names_file_and_line(tmp_path):
    path = tmp_path / "bad.txt"
    path.write_text(f"{CAR}\n0 1 {CAR}\n")  # a tracking line (17 columns) in an object file
    with pytest.raises(ValueError, match=r"bad\.txt:2: expected 15 or 16 columns, got 17"):
        read_object_labels(path)
    path.write_text(CAR.replace("1.60", "wide") + "\n")
    with pytest.raises(ValueError, match=r"bad\.txt:1: box: cannot parse 'wide'"):
        read_object_labels(path)


def test_frames_by_kitti_number(object_root):
    ds = KittiObject(object_root)
    assert len(ds) == 2 and ds.ids == [3, 7]
    assert "KittiObject" in repr(ds) and datasets.KittiObject is KittiObject
    f = ds[7]
    assert isinstance(f, Frame) and f.index == 7 and np.isnan(f.timestamp)
    assert f.calib == make_calib()
    assert f.image_left.shape == (H, W, 3) and np.all(f.image_left == 7)
    assert f.image_right is None and f.T_w_c_gt is None
    assert list(f.objects_gt.cls) == ["Car", DONT_CARE] and np.all(f.objects_gt.frame == 7)
    # the scan in the rectified camera frame: R_rect Tr_velo_cam X_velo, intensity kept
    T = make_calib().T_c_velo
    xyz = f.points_velo[:, :3].astype(np.float64)
    np.testing.assert_allclose(f.points_c[:, :3], xyz @ T[:3, :3].T + T[:3, 3], atol=1e-4)
    np.testing.assert_array_equal(f.points_c[:, 3], f.points_velo[:, 3])
    assert [g.index for g in ds] == [3, 7]
    light = ds.frame(3, lidar=False, image=False)
    assert light.points_c is None and light.image_left is None and len(light.objects_gt) == 2
    assert ds.labels(3).equals(ds[3].objects_gt)


def test_a_missing_frame_is_an_index_error_naming_the_file(object_root):
    ds = KittiObject(object_root)
    with pytest.raises(IndexError, match=r"frame 000005 not in .*2 frames, 000003\.\.000007.*"
                                         r"calib/000005\.txt not found"):
        ds[5]
    with pytest.raises(TypeError, match="frame number must be an integer"):
        ds["3"]


def test_a_missing_file_is_an_error_naming_it(object_root):
    (object_root / "training" / "velodyne" / "000007.bin").unlink()
    ds = KittiObject(object_root)
    assert ds[3].points_c is not None
    with pytest.raises(FileNotFoundError, match=r"frame 000007 has a calibration but no velodyne file: "
                                                r"'.*velodyne/000007\.bin'"):
        ds[7]
    (object_root / "training" / "label_2" / "000003.txt").unlink()
    with pytest.raises(FileNotFoundError, match=r"label_2/000003\.txt"):
        ds.labels(3)


def test_a_missing_folder_warns_once_and_gives_none(object_root):
    shutil.rmtree(object_root / "training" / "label_2")  # e.g. the testing split
    with pytest.warns(MissingDataWarning, match=r"label_2 not found") as record:
        ds = KittiObject(object_root)
    assert len(record) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # reading frames adds no further warning
        frames = list(ds)
    assert all(f.objects_gt is None and f.points_c is not None for f in frames)


def test_missing_calibration_folder_names_it(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"calibration folder not found: .*testing/calib"):
        KittiObject(tmp_path, split="testing")
