"""Detection sources behind one protocol: precomputed files (the real PointRCNN file of KITTI
0001, KITTI tracking and object result formats), the factory, and ``twistslam detect``."""

from __future__ import annotations

import argparse

import numpy as np
import pytest

from twistslam.datasets import (
    KittiObject, ObjectTable, read_detections, read_labels, write_tracking_results,
)
from twistslam.detect_cli import add_detect
from twistslam.perception import (
    ClassicalDetector, DetectionStage, Detections3D, FileDetections, detection_source,
)


class _Frame:  # what a file source needs of a frame: its number
    def __init__(self, index: int) -> None:
        self.index = index


def _pointrcnn(root):
    return root / "detections" / "pointrcnn_car_val" / "0001.txt"


def _run_detect(argv: list[str]) -> int:
    parser = argparse.ArgumentParser()
    add_detect(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["detect", *argv])
    return args.handler(args)


def test_real_pointrcnn_file(kitti_tracking_lidar):
    path = _pointrcnn(kitti_tracking_lidar)
    source = detection_source("auto", path=path)
    assert isinstance(source, FileDetections) and isinstance(source, DetectionStage)
    table = read_detections(path)
    first = source(_Frame(0))
    rows = table.in_frame(0)
    assert len(first) == len(rows) == 6
    assert np.array_equal(first.boxes, rows.box_3d)  # geometric centre, as read_detections
    assert np.array_equal(first.scores, rows.score) and set(first.classes) == {"Car"}
    # y of the file is the bottom centre: the box centre sits h / 2 above it
    assert np.isclose(first.boxes[0, 1], 1.6089 - 1.5206 / 2)
    total = sum(len(source(_Frame(i))) for i in range(27))
    assert total == len(table)
    assert len(source(_Frame(500))) == 0  # a frame absent from a one-file source: nothing found


def test_kitti_tracking_result_file_round_trip(kitti_tracking_lidar, tmp_path):
    table = read_detections(_pointrcnn(kitti_tracking_lidar))
    path = tmp_path / "0001.txt"
    write_tracking_results(path, table)
    source = FileDetections(path)
    again = read_labels(path)
    for frame in (0, 5, 26):
        dets = source(_Frame(frame))
        expected = again.in_frame(frame)
        assert len(dets) == len(expected) > 0
        assert np.allclose(dets.boxes, expected.box_3d) and np.allclose(dets.scores, expected.score)
        # the same boxes as the comma file, to the result format's 6 decimals
        original = table.in_frame(frame)
        order = np.lexsort(original.box_3d.T[::-1])
        assert np.allclose(np.sort(dets.boxes, axis=0), np.sort(original.box_3d[order], axis=0), atol=1e-5)


def test_dontcare_rows_are_not_detections(tmp_path):
    path = tmp_path / "r.txt"
    path.write_text("0 -1 DontCare -1 -1 -10 1 2 3 4 -1000 -1000 -1000 -10 -1 -1 -10 0.5\n"
                    "0 -1 Car 0 0 0.1 1 2 3 4 1.5 1.6 4.0 1.0 1.7 10.0 0.2 3.5\n")
    dets = FileDetections(path)(_Frame(0))
    assert list(dets.classes) == ["Car"]
    assert np.allclose(dets.boxes[0], [1.0, 1.7 - 0.75, 10.0, 4.0, 1.6, 1.5, 0.2])


def test_detect_cli_writes_object_results_read_back_as_files(kitti_object, tmp_path):
    out = tmp_path / "results"
    assert _run_detect([str(kitti_object), "--out", str(out)]) == 0
    ds = KittiObject(kitti_object)
    assert sorted(p.name for p in out.iterdir()) == [f"{i:06d}.txt" for i in ds.ids]
    source = detection_source("files", path=out)
    detect = ClassicalDetector()
    for index in (0, 8):
        frame = ds.frame(index)
        direct, read = detect(frame), source(frame)
        assert len(direct) == len(read) > 0
        assert np.allclose(read.boxes, direct.boxes, atol=2e-6)  # 6 decimals in the file
        assert np.allclose(read.scores, direct.scores, atol=1e-6)
        assert list(read.classes) == list(direct.classes)
        # 16 columns: the object label format plus the score; image boxes from P2
        fields = (out / f"{index:06d}.txt").read_text().splitlines()[0].split()
        assert len(fields) == 16 and fields[0] in ("Car", "Pedestrian", "Cyclist")
        x1, y1, x2, y2 = map(float, fields[4:8])
        assert 0 <= x1 < x2 <= frame.image_left.shape[1] and 0 <= y1 < y2 <= frame.image_left.shape[0]


def test_missing_frame_in_a_result_folder(tmp_path):
    (tmp_path / "000000.txt").write_text("Car 0 0 0.1 1 2 3 4 1.5 1.6 4.0 1.0 1.7 10.0 0.2 3.5\n")
    strict = FileDetections(tmp_path)
    assert len(strict(_Frame(0))) == 1
    with pytest.raises(FileNotFoundError, match="000003.txt|frame 000003"):
        strict(_Frame(3))
    lenient = detection_source("files", path=tmp_path, missing_frames="empty")
    assert len(lenient(_Frame(3))) == 0


def test_bad_files_and_sources(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        FileDetections(tmp_path / "nothing.txt")
    bad = tmp_path / "bad.txt"
    bad.write_text("0,2,1,2,3,4,0.9,1.5,1.6,4.0,1.0,1.7\n")
    with pytest.raises(ValueError, match=r"bad.txt:1: expected 15 columns"):
        FileDetections(bad)
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    assert len(FileDetections(empty)(_Frame(0))) == 0
    with pytest.raises(ValueError, match="expected one of"):
        detection_source("yolo")
    with pytest.raises(ValueError, match="needs path"):
        detection_source("files")
    with pytest.raises(ValueError, match="needs weights"):
        detection_source("3dssd")
    with pytest.raises(ValueError, match="missing_frames"):
        FileDetections(empty, missing_frames="skip")
    assert isinstance(detection_source(), ClassicalDetector)  # the default without weights


def test_detect_cli_tracking_sequence_and_errors(kitti_tracking_lidar, tmp_path):
    out = tmp_path / "track"
    assert _run_detect([str(kitti_tracking_lidar), "--seq", "0001", "--out", str(out),
                        "--set", "max_range_m=40"]) == 0
    table = read_labels(out / "0001.txt")
    assert set(table.frames) <= set(range(27)) and len(table.frames) >= 20
    assert np.all(np.hypot(table.box_3d[:, 0], table.box_3d[:, 2]) <= 40.0 + 3.0)
    with pytest.raises(ValueError, match="needs path"):
        _run_detect([str(kitti_tracking_lidar), "--seq", "0001", "--out", str(out),
                     "--detector", "files"])
    with pytest.raises(ValueError, match="max_rnage_m"):
        _run_detect([str(kitti_tracking_lidar), "--seq", "0001", "--out", str(out),
                     "--set", "max_rnage_m=40"])


def test_detections3d_table_round_trip():
    dets = Detections3D([[1.0, 0.9, 10.0, 4.0, 1.6, 1.5, 0.3]], [0.7], ["Car"])
    table = dets.to_table(frame=4)
    assert isinstance(table, ObjectTable) and table.frame[0] == 4 and table.track_id[0] == -1
    assert np.isclose(table.alpha[0], 0.3 - np.arctan2(1.0, 10.0))
    back = Detections3D.from_table(table)
    assert np.array_equal(back.boxes, dets.boxes) and list(back.classes) == ["Car"]
    with pytest.raises(ValueError, match="finite"):
        Detections3D([[np.nan] * 7], [1.0], ["Car"])


def test_a_run_leaves_out_pointrcnn_boxes_below_its_floor_only(kitti_tracking_lidar, tmp_path):
    from twistslam.datasets import KittiTracking
    from twistslam.perception.run_stages import POINTRCNN_MIN_SCORE, _file_detections

    seq = KittiTracking(kitti_tracking_lidar, "0001")
    path = _pointrcnn(kitti_tracking_lidar)
    every = read_detections(path)
    low = every.score < POINTRCNN_MIN_SCORE
    assert low.sum() > 20 and (~low).sum() > 100  # the real file has both
    used = _file_detections(path, seq)
    assert len(used) == int((~low).sum()) and (used.score >= POINTRCNN_MIN_SCORE).all()
    # a table read from that file is still PointRCNN's scale; the same boxes written as KITTI
    # tracking results (any writer's scale) are all kept
    assert len(_file_detections(every, seq)) == len(used)
    results = tmp_path / "0001.txt"
    write_tracking_results(results, every)
    assert len(_file_detections(results, seq)) == len(every)
