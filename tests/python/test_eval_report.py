"""Report tables: layout, Markdown, and the paper's rows from tables.json beside ours."""

from __future__ import annotations

import json
import warnings

import numpy as np

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
    assert ours[5] == "ours" and ours[6:9] == ["0.000", "0.000", "0.000"]
    # the lines after ours: one per system of the paper, with its numbers from tables.json
    for k, (system, rows) in enumerate(paper["objects"].items()):
        row = next(r for r in rows if r["seq"] == "03" and r["track_id"] == 1)
        cells = lines[i + 1 + k].split()
        assert " ".join(cells[:-3]) == system
        assert cells[-3:] == [f"{row[key]:.2f}" for key in ("ate", "rpe_t", "rpe_r")]
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
