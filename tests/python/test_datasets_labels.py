"""Labels, tracking results and detections against the real KITTI tracking files."""

import numpy as np
import pytest

from twistslam import geometry
from twistslam.datasets import (
    DONT_CARE,
    ObjectTable,
    read_calibration,
    read_detections,
    read_image,
    read_labels,
    read_tracking_results,
    write_tracking_results,
)

COLUMNS = ("frame", "track_id", "cls", "truncation", "occlusion", "alpha", "box_2d", "box_3d",
           "score")


@pytest.fixture
def labels_file(kitti_tracking):
    """Real ground truth of sequence 0001 (447 frames)."""
    return kitti_tracking / "training" / "label_02" / "0001.txt"


@pytest.fixture
def detections_file(kitti_tracking):
    """Real PointRCNN car detections of sequence 0001."""
    return kitti_tracking / "detections" / "pointrcnn_car_val" / "0001.txt"


def box_corners(boxes: np.ndarray) -> np.ndarray:
    """(N, 7) [cx cy cz l w h ry] -> (N, 8, 3) corners; object x (length) along camera x at ry=0."""
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) / 2
    local = signs[None] * boxes[:, None, [3, 5, 4]]  # x: l, y: h, z: w
    c, s = np.cos(boxes[:, 6]), np.sin(boxes[:, 6])
    zeros, ones = np.zeros_like(c), np.ones_like(c)
    R_y = np.stack([np.stack([c, zeros, s], -1), np.stack([zeros, ones, zeros], -1),
                    np.stack([-s, zeros, c], -1)], axis=1)
    return local @ R_y.transpose(0, 2, 1) + boxes[:, None, :3]


def assert_tables_equal(a: ObjectTable, b: ObjectTable) -> None:
    assert len(a) == len(b)
    for name in COLUMNS:
        x, y = getattr(a, name), getattr(b, name)
        if x.dtype.kind in "iU":
            np.testing.assert_array_equal(x, y, err_msg=name)
        else:
            np.testing.assert_allclose(x, y, rtol=1e-6, atol=1e-9, err_msg=name)


def test_real_labels_read_with_geometric_centre(labels_file):
    table = read_labels(labels_file)
    assert len(table) == sum(1 for line in labels_file.read_text().splitlines() if line.strip())
    first_car = labels_file.read_text().splitlines()
    first_car = next(line.split() for line in first_car if line.split()[2] == "Car")
    h, y = float(first_car[10]), float(first_car[14])
    row = np.flatnonzero(table.cls == "Car")[0]
    assert table.box_3d[row, 1] == pytest.approx(y - h / 2)  # geometric, not bottom, centre
    length, width = float(first_car[12]), float(first_car[11])
    np.testing.assert_allclose(table.box_3d[row, 3:6], [length, width, h])
    assert np.all(table.score == 1.0)
    assert {"Car", "Pedestrian", DONT_CARE} <= set(table.cls)
    dont_care = table.cls == DONT_CARE
    assert np.all(table.track_id[dont_care] == -1)
    np.testing.assert_array_equal(table.box_3d[dont_care][:, 3:6], -1000.0)  # placeholders kept


@pytest.mark.parametrize("frame", [10, 15, 20])
def test_projected_3d_boxes_match_2d_labels(frame, labels_file, kitti_tracking):
    calib = read_calibration(kitti_tracking / "training" / "calib" / "0001.txt")
    image = read_image(kitti_tracking / "training" / "image_02" / "0001" / f"{frame:06d}.png")
    assert image.shape == (375, 1242, 3) and image.dtype == np.uint8
    table = read_labels(labels_file).in_frame(frame)
    table = table.select((table.cls != DONT_CARE) & (table.truncation < 0.1))
    assert len(table) >= 3
    corners = box_corners(table.box_3d)
    uvw = np.concatenate([corners, np.ones((*corners.shape[:2], 1))], -1) @ calib.P2.T
    uv = uvw[..., :2] / uvw[..., 2:]
    projected = np.concatenate([uv.min(1), uv.max(1)], axis=1)
    # label boxes are clipped to the image; so must the projections be
    projected = np.clip(projected, 0, [image.shape[1] - 1, image.shape[0] - 1] * 2)
    error = np.abs(projected - table.box_2d).max(axis=1)
    # KITTI tracking 2D boxes are the projected 3D boxes: sub-pixel for most objects; a wrong
    # centre convention (bottom vs geometric) would be off by ~h/2 * f / z, 10+ px here
    assert np.median(error) < 3.0, error
    assert np.all(error < 8.0), error


def test_labels_write_read_round_trip(tmp_path, labels_file):
    table = read_labels(labels_file)
    write_tracking_results(tmp_path / "0001.txt", table)
    lines = (tmp_path / "0001.txt").read_text().splitlines()
    assert all(len(line.split()) == 18 for line in lines)
    # DontCare placeholders and bottom-centre y come back exactly as KITTI wrote them
    original = labels_file.read_text().splitlines()
    assert lines[0].split()[:17] == original[0].split()
    again = read_tracking_results(tmp_path / "0001.txt")
    assert_tables_equal(table, again)


def test_result_scores_and_order(tmp_path):
    table = ObjectTable(
        frame=[3, 1], track_id=[7, 2], cls=["Car", "Cyclist"], truncation=[0, 0.25],
        occlusion=[1, 0], alpha=[0.1, -0.2], box_2d=[[1, 2, 3, 4], [5, 6, 7, 8]],
        box_3d=[[1.0, 0.5, 20.0, 4.0, 1.6, 1.5, 0.3], [-2.0, 0.9, 10.0, 1.8, 0.6, 1.7, -1.0]],
        score=[0.75, 12.5],
    )
    path = tmp_path / "result.txt"
    write_tracking_results(path, table)
    first = path.read_text().splitlines()[0].split()
    assert first[:3] == ["1", "2", "Cyclist"]  # sorted by frame
    assert float(first[14]) == pytest.approx(0.9 + 1.7 / 2)  # bottom centre written back
    assert float(first[17]) == 12.5
    assert_tables_equal(table.sorted(), read_tracking_results(path))


def test_malformed_label_line_names_file_and_line(tmp_path):
    good = "0 1 Car 0 0 -1.5 100 120 200 180 1.5 1.6 4.0 1.0 1.7 20.0 -1.55"
    path = tmp_path / "label.txt"
    path.write_text("\n".join([good, good, "0 2 Car 0 0 1 2 3 4 5 6 7"]) + "\n")
    with pytest.raises(ValueError, match=r"label\.txt:3: expected 17 or 18 columns, got 12"):
        read_labels(path)
    path.write_text(good + "\n" + good.replace("1.6", "wide") + "\n")
    with pytest.raises(ValueError, match=r"label\.txt:2: .*'wide'"):
        read_labels(path)
    path.write_text(good.replace("0 1 Car", "0 1.5 Car") + "\n")
    with pytest.raises(ValueError, match=r"label\.txt:1: track_id"):
        read_labels(path)


def test_empty_label_file(tmp_path):
    (tmp_path / "empty.txt").write_text("")
    assert len(read_labels(tmp_path / "empty.txt")) == 0


def test_pointrcnn_detections(labels_file, detections_file):
    table = read_detections(detections_file)
    assert len(table) == 4418
    assert set(table.cls) == {"Car"}
    assert np.all(table.track_id == -1)
    first = detections_file.read_text().splitlines()[0].split(",")
    h, y = float(first[7]), float(first[11])
    assert table.frame[0] == 0 and table.score[0] == pytest.approx(float(first[6]))
    assert table.box_3d[0, 1] == pytest.approx(y - h / 2)
    np.testing.assert_allclose(table.box_3d[0, 3:6], [float(first[9]), float(first[8]), h])
    assert table.alpha[0] == pytest.approx(float(first[14]))
    # detections sit where the labelled cars are: most labelled cars have a detection < 2 m
    labels = read_labels(labels_file).of_class("Car")
    near = []
    for frame in (10, 15, 20):
        gt, det = labels.in_frame(frame), table.in_frame(frame)
        d = np.linalg.norm(gt.box_3d[:, None, :3] - det.box_3d[None, :, :3], axis=-1)
        near.extend(d.min(axis=1) < 2.0)
    assert np.mean(near) > 0.6


def test_malformed_detection_line(tmp_path):
    good = "0,2,786.7,180.1,1241.0,374.0,12.2,1.52,1.68,4.45,2.93,1.60,6.42,-1.58,-2.01"
    path = tmp_path / "det.txt"
    path.write_text(good + "\n" + good.rsplit(",", 2)[0] + "\n")
    with pytest.raises(ValueError, match=r"det\.txt:2: expected 15 columns, got 13"):
        read_detections(path)
    path.write_text(good + "\n\n" + good.replace("0,2,", "0,9,", 1) + "\n")
    with pytest.raises(ValueError, match=r"det\.txt:3: type: unknown class code 9"):
        read_detections(path)


def test_labels_agree_with_the_geometry_module(labels_file, kitti_tracking):
    """Boxes read here follow the box convention of twistslam.geometry (same 2D projections)."""
    calib = read_calibration(kitti_tracking / "training" / "calib" / "0001.txt")
    table = read_labels(labels_file).in_frame(15)
    table = table.select((table.cls != DONT_CARE) & (table.truncation < 0.1))
    projected = geometry.project_boxes(table.box_3d, calib.P2, 1242, 375)
    assert np.abs(projected - table.box_2d).max() < 8.0
    np.testing.assert_allclose(
        np.sort(geometry.box_corners(table.box_3d), axis=1),
        np.sort(box_corners(table.box_3d), axis=1), atol=1e-9,
    )
