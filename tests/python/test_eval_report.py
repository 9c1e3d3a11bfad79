"""Report tables: layout, Markdown, and the paper's rows from tables.json beside ours."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from twistslam.datasets import read_labels, write_tracking_results
from twistslam.eval.camera import CameraMetrics
from twistslam.eval.metrics import EvalSettings, SequenceMetrics
from twistslam.eval.report import load_paper_tables, render_markdown, render_text
from twistslam.eval.sequence import evaluate_sequence

from conftest import paper_tables


def camera_only(seq: str) -> SequenceMetrics:
    cam = CameraMetrics(0.0412, 0.0321, 0.05, 0.04, 0.9, 1.5, 100, 100, 0, 99)
    return SequenceMetrics(seq=seq, settings=EvalSettings(), camera=cam)


def test_camera_table_with_and_without_paper():
    text = render_text(camera_only("0004"))
    lines = text.splitlines()
    assert lines[0] == "Camera"
    row = next(line for line in lines if line.startswith("04 "))
    assert row.split()[1:] == ["ours", "0.041", "0.032", "0.050", "0.040", "0.900"]
    assert "ORB-SLAM2" not in text  # the paper is only read when asked for

    paper = load_paper_tables(paper_tables())
    text = render_text(camera_only("0004"), paper)
    rows = {" ".join(line.split()[:-5]): line.split()[-5:] for line in text.splitlines()[4:-1]}
    for system, seqs in paper["camera"].items():
        # the paper gives mean RPE only: its rmse and ATE cells are empty
        expected = [f"{seqs['04']['rpe_t']:.2f}", f"{seqs['04']['rpe_r']:.2f}", "-", "-", "-"]
        assert rows[system] == expected
    # a sequence the paper does not list gets no paper rows
    assert "ORB-SLAM2" not in render_text(camera_only("0001"), paper)


def test_object_tables_print_the_paper_rows_of_the_same_object(tmp_path, kitti_tracking):
    ROOT = kitti_tracking
    gt = read_labels(ROOT / "training" / "label_02" / "0003.txt")
    write_tracking_results(tmp_path / "tracking" / "0003.txt", gt)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = evaluate_sequence(ROOT, tmp_path, "0003")
    paper = load_paper_tables(paper_tables())
    text = render_text(m, paper)
    lines = text.splitlines()
    i = lines.index(next(line for line in lines if line.startswith("03 / 1 / car")))
    ours = lines[i].split()
    # ATE, RPE_t, RPE_R and the yaw error of the labels themselves: zero
    assert ours[5] == "ours" and ours[6:10] == ["0.000", "0.000", "0.000", "0.000"]
    # the lines after ours: one per system of the paper, with its numbers from tables.json
    # (the paper gives no yaw error: "-")
    for k, (system, rows) in enumerate(paper["objects"].items()):
        row = next(r for r in rows if r["seq"] == "03" and r["track_id"] == 1)
        cells = lines[i + 1 + k].split()
        assert " ".join(cells[:-4]) == system
        assert cells[-4:] == [f"{row[key]:.2f}" for key in ("ate", "rpe_t", "rpe_r")] + ["-"]
    # objects without a paper row have none
    j = lines.index(next(line for line in lines if line.startswith("03 / 0 / car")))
    assert lines[j + 1].startswith("03 / ")

    md = render_markdown(m, paper)
    assert "| 03 / 1 / car | ours | 0.000 | 0.000 | 0.000 |" in md
    assert "### CLEAR MOT" in md
    assert md.count("| --- | --- |") == 3  # pose, boxes, CLEAR MOT


def test_nan_prints_as_dash_and_json_as_null():
    cam = CameraMetrics(*([float("nan")] * 6), 1, 0, 1, 0)
    m = SequenceMetrics(seq="0002", settings=EvalSettings(), camera=cam)
    row = next(line for line in render_text(m).splitlines() if line.startswith("02 "))
    assert row.split() == ["02", "ours", "-", "-", "-", "-", "-"]
    assert json.loads(json.dumps(m.to_dict()))["camera"]["ate_rmse"] is None
    assert np.isnan(m.objects_mean["ate"])


def test_yaw_error_counts_a_box_facing_backwards_as_180_degrees(tmp_path, kitti_tracking):
    # the labels as results, one track's boxes turned by pi (and one by 10 deg): the box
    # covers the same space (its IoU, ATE and MOTP unchanged) but its heading is wrong
    gt = read_labels(kitti_tracking / "training" / "label_02" / "0003.txt")
    cars = np.unique(gt.track_id[np.char.lower(gt.cls.astype(str)) == "car"])
    flipped, turned = int(cars[0]), int(cars[1])
    box = gt.box_3d.copy()
    box[gt.track_id == flipped, 6] += np.pi
    box[gt.track_id == turned, 6] += np.radians(10.0)
    est = type(gt)(**{**vars(gt), "box_3d": box})
    write_tracking_results(tmp_path / "tracking" / "0003.txt", est)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = evaluate_sequence(kitti_tracking, tmp_path, "0003")
    yaw = {o.track_id: o.yaw for o in m.objects}
    assert yaw[flipped] == pytest.approx(180.0, abs=1e-3)
    assert yaw[turned] == pytest.approx(10.0, abs=1e-3)
    assert all(v == pytest.approx(0.0, abs=1e-3) for t, v in yaw.items() if t not in (flipped, turned))
    ate = {o.track_id: o.ate for o in m.objects}
    assert ate[flipped] == pytest.approx(0.0, abs=1e-6)
