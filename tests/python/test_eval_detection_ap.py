"""KITTI object detection AP: hand-worked cases, the devkit's rules, real labels and
real PointRCNN detections, and ``twistslam eval-detections``.

Hand-built scenes use boxes far apart (one every 10 m along z) with tall image boxes, so that
every overlap but the intended ones is zero and every AP follows from the definition
``AP_R40 = mean over r = 1/40 .. 1 of max {precision at recall >= r}``.
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest

from twistslam.datasets import (
    KittiObject, ObjectTable, read_detections, read_labels, write_tracking_results,
)
from twistslam.datasets.labels import format_label_lines
from twistslam.eval.detection_ap import evaluate_detections
from twistslam.eval.detection_matching import score_thresholds
from twistslam.eval_detections_cli import add_eval_detections

CAR_SIZE = (4.0, 1.6, 1.5)  # l, w, h (m): a typical KITTI car
SPACING_M = 10.0  # distance between hand-built objects along z: no two of them overlap
TALL_BOX_PX = 60.0  # image box height inside every difficulty level (>= 40 px)


def _boxes(specs: list[dict], frame: int = 0) -> ObjectTable:
    """Table from ``{cls, slot, dx, score, occ, trunc, height_px, box_2d}`` rows; ``slot``
    places the box at z = 10 (slot + 1) m, ``dx`` shifts it along its length (camera x)."""
    n = len(specs)
    box_3d, box_2d = np.zeros((n, 7)), np.zeros((n, 4))
    for i, s in enumerate(specs):
        z = SPACING_M * (s.get("slot", i) + 1)
        box_3d[i] = [s.get("dx", 0.0), 1.0, z, *CAR_SIZE, 0.0]
        x1 = 100.0 * s.get("slot", i)  # image boxes of different slots do not overlap
        box_2d[i] = s.get("box_2d", [x1, 150.0, x1 + 50.0, 150.0 + s.get("height_px", TALL_BOX_PX)])
    return ObjectTable(
        frame=np.full(n, frame), track_id=np.full(n, -1), cls=[s.get("cls", "Car") for s in specs],
        truncation=[s.get("trunc", 0.0) for s in specs], occlusion=[s.get("occ", 0) for s in specs],
        alpha=np.zeros(n), box_2d=box_2d, box_3d=box_3d, score=[s.get("score", 1.0) for s in specs],
    )


def _car_ap(gt, dets, metric="3d", iou=0.7, difficulty="moderate", sampling="exact") -> float:
    r = evaluate_detections(gt, dets, classes=("Car",), metrics=(metric,), iou=iou,
                            difficulties=(difficulty,), sampling=sampling)
    return r.ap("Car", difficulty, metric, iou)


# ------------------------------------------------------------------ hand-worked AP values
def test_two_of_four_cars_found_first():
    """4 cars; the two highest scores find two of them, two lower-scored boxes hit nothing.
    Thresholds sit at the true-positive scores 0.9 and 0.8: precision 1 at recall 1/4 and
    2/4; the false positives (0.7, 0.6) are never kept. p(r) = 1 for r <= 1/2 (20 of the 40
    points), 0 above: AP_R40 = 20/40 = 50 %. AP_R11: r = 0, 0.1, .., 0.5 -> 6/11."""
    gt = _boxes([{"slot": k} for k in range(4)])
    dets = _boxes([{"slot": 0, "score": 0.9}, {"slot": 1, "score": 0.8},
                   {"slot": 5, "score": 0.7}, {"slot": 6, "score": 0.6}])
    r = evaluate_detections(gt, dets, classes=("Car",), metrics=("3d",), iou=0.7)
    curve = r.curve("Car", "moderate", "3d", 0.7)
    assert curve.ap_r40 == pytest.approx(20 / 40 * 100)
    assert curve.ap_r11 == pytest.approx(6 / 11 * 100)
    assert curve.n_gt == 4


def test_false_positive_between_true_positives():
    """Scores: TP 0.9, FP 0.85, TP 0.8 over 4 cars. At 0.9: P = 1, R = 1/4; at 0.8: P = 2/3,
    R = 2/4. p(r) = 1 for the 10 points r <= 1/4, 2/3 for the 10 points up to 1/2:
    AP_R40 = (10 + 10 * 2/3) / 40."""
    gt = _boxes([{"slot": k} for k in range(4)])
    dets = _boxes([{"slot": 0, "score": 0.9}, {"slot": 7, "score": 0.85},
                   {"slot": 1, "score": 0.8}])
    assert _car_ap(gt, dets) == pytest.approx((10 + 10 * 2 / 3) / 40 * 100)


def test_devkit_sampling_reproduces_its_few_box_shortcut():
    """The devkit takes its k-th threshold as recall k/40: with 2 TPs (2 thresholds) it
    credits only point 1 -> 1/40; with 9 perfect boxes, points 1..8 -> 8/40."""
    gt = _boxes([{"slot": k} for k in range(4)])
    dets = _boxes([{"slot": 0, "score": 0.9}, {"slot": 1, "score": 0.8}])
    assert _car_ap(gt, dets, sampling="devkit") == pytest.approx(1 / 40 * 100)
    nine = _boxes([{"slot": k, "score": 1.0 - 0.01 * k} for k in range(9)])
    assert _car_ap(nine, nine, sampling="devkit") == pytest.approx(8 / 40 * 100)
    assert _car_ap(nine, nine, sampling="exact") == pytest.approx(100.0)


def test_score_thresholds_follow_recall_on_many_boxes():
    """With 1000 true positives of 1000 boxes, the k-th threshold reaches recall k/40 (the
    first one, for recall 0, the smallest recall there is: 1/1000)."""
    n = 1000
    scores = np.linspace(1.0, 0.001, n)
    t = score_thresholds(scores, n)
    assert len(t) == 41
    recall_of = {s: (i + 1) / n for i, s in enumerate(scores)}
    reached = np.array([recall_of[s] for s in t])
    expected = np.maximum(np.arange(41) / 40, 1 / n)
    np.testing.assert_allclose(reached, expected, atol=1 / n)


def test_shifted_box_fails_iou_07_but_passes_05():
    """Same-size boxes shifted by 1 m along their 4 m length: IoU = (4 - 1) / (4 + 1) = 0.6
    in bird view and in 3D (same height)."""
    gt = _boxes([{"slot": 0}])
    dets = _boxes([{"slot": 0, "dx": 1.0, "score": 0.9}])
    from twistslam.geometry import box_iou_3d, box_iou_bev

    expected_iou = (4.0 - 1.0) / (4.0 + 1.0)
    assert box_iou_bev(dets.box_3d, gt.box_3d)[0, 0] == pytest.approx(expected_iou)
    assert box_iou_3d(dets.box_3d, gt.box_3d)[0, 0] == pytest.approx(expected_iou)
    for metric in ("bev", "3d"):
        assert _car_ap(gt, dets, metric, iou=0.7) == 0.0
        assert _car_ap(gt, dets, metric, iou=0.5) == pytest.approx(100.0)


# ------------------------------------------------------------------ the devkit's rules
def test_thresholds_come_from_the_highest_scored_candidate():
    """One car found twice (A listed first, score 0.5; B 0.9) and a false positive at 0.7.
    The threshold pass credits B, so the only threshold is 0.9: precision 1, recall 1 ->
    100. Crediting A would put the threshold at 0.5, keeping both duplicates and the false
    positive: precision 1/3."""
    gt = _boxes([{"slot": 0}])
    dets = _boxes([{"slot": 0, "dx": 0.1, "score": 0.5}, {"slot": 0, "score": 0.9},
                   {"slot": 4, "score": 0.7}])
    assert _car_ap(gt, dets) == pytest.approx(100.0)


def test_counting_takes_the_candidate_of_largest_iou():
    """Two cars 2 m apart along x; X (listed first, score 0.8) sits between them (IoU 0.6
    with both), Y (score 0.9) on the first (IoU 3.8/4.2 = 0.90; 1.8/6.2 = 0.29 with the
    second). At threshold 0.8 the first car takes Y, its largest IoU, and the second X:
    precision 1 at recall 1 -> 100. Taking the first candidate (X) would leave the second
    car missed and Y false: 50."""
    gt = _boxes([{"slot": 0}, {"slot": 0, "dx": 2.0}])
    dets = _boxes([{"slot": 0, "dx": 1.0, "score": 0.8}, {"slot": 0, "dx": -0.2, "score": 0.9}])
    assert _car_ap(gt, dets, "bev", iou=0.5) == pytest.approx(100.0)


def test_van_and_dont_care_are_ignored_not_false_positives():
    """A car found at score 0.9; higher-scored Car detections on a Van (0.95) and inside a
    DontCare region (0.93) would halve the precision if they counted. The Van match is
    ignored in every metric; the DontCare region (an image box only) excuses its detection
    in the image metric, and -- as in the devkit, whose region boxes have no 3D extent -- not
    in bird view or 3D: precision 1/2 there."""
    dont_care_px = [600.0, 150.0, 700.0, 250.0]
    gt = _boxes([{"slot": 0}, {"slot": 1, "cls": "Van"},
                 {"slot": 2, "cls": "DontCare", "box_2d": dont_care_px}])
    dets = _boxes([{"slot": 0, "score": 0.9}, {"slot": 1, "score": 0.95},
                   {"slot": 3, "score": 0.93, "box_2d": [620.0, 160.0, 680.0, 240.0]}])
    assert _car_ap(gt, dets, "2d") == pytest.approx(100.0)
    for metric in ("bev", "3d"):
        assert _car_ap(gt, dets, metric) == pytest.approx(50.0)
    # without the Van label its detection is a plain false positive (precision 1/2)
    no_van = gt.select(gt.cls != "Van")
    assert _car_ap(no_van, dets.select(dets.score != 0.93), "2d") == pytest.approx(50.0)


def test_difficulty_levels():
    """A: visible, 60 px; B: occlusion 2 (hard only); C: 30 px (not easy); D: truncated 0.4
    (hard only). Only A is detected: easy 1 box -> 100; moderate A, C -> recall 1/2 -> 20/40;
    hard all four -> recall 1/4 -> 10/40. A 20 px detection (below every minimum height) of
    high score far from all boxes is ignored, not a false positive."""
    gt = _boxes([{"slot": 0}, {"slot": 1, "occ": 2}, {"slot": 2, "height_px": 30.0},
                 {"slot": 3, "trunc": 0.4}])
    dets = _boxes([{"slot": 0, "score": 0.9}, {"slot": 8, "score": 0.99, "height_px": 20.0}])
    expected = {"easy": 100.0, "moderate": 20 / 40 * 100, "hard": 10 / 40 * 100}
    for level, ap in expected.items():
        assert _car_ap(gt, dets, difficulty=level) == pytest.approx(ap), level
    r = evaluate_detections(gt, dets, classes=("Car",), metrics=("3d",))
    assert [r.curve("Car", d, "3d", 0.7).n_gt for d in ("easy", "moderate", "hard")] == [1, 2, 4]


def test_detection_matched_to_an_ignored_box_is_no_false_positive():
    """C (30 px) is outside easy: a detection on it with the top score costs nothing there,
    and in moderate it is a true positive (both cars found)."""
    gt = _boxes([{"slot": 0}, {"slot": 2, "height_px": 30.0}])
    dets = _boxes([{"slot": 0, "score": 0.9}, {"slot": 2, "score": 0.95, "height_px": 30.0}])
    assert _car_ap(gt, dets, difficulty="easy") == pytest.approx(100.0)
    assert _car_ap(gt, dets, difficulty="moderate") == pytest.approx(100.0)


def test_no_ground_truth_gives_nan_and_frames_as_dicts():
    gt = {0: _boxes([{"slot": 0}]), 1: ObjectTable.empty()}
    dets = {0: _boxes([{"slot": 0, "score": 0.5}]), 1: _boxes([{"slot": 1, "score": 0.9}], 1)}
    r = evaluate_detections(gt, dets, classes=("Car", "Cyclist"), metrics=("bev",))
    assert r.n_frames == 2
    assert math.isnan(r.ap("Cyclist", "easy", "bev", 0.5))
    # frame 1's detection (score 0.9) is a false positive above the only true positive
    assert r.ap("Car", "easy", "bev", 0.7) == pytest.approx(50.0)
    assert r.to_dict()["curves"][-1]["ap_r40"] is None
    assert "Cyclist" in r.table() and " -" in r.table()


def test_bad_arguments():
    gt = _boxes([{"slot": 0}])
    with pytest.raises(ValueError, match="unknown metric"):
        evaluate_detections(gt, gt, metrics=("iou",))
    with pytest.raises(ValueError, match="van"):
        evaluate_detections(gt, gt, classes=("Van",))
    assert evaluate_detections(gt, gt, classes=("Van",), iou=0.7).curves  # named threshold
    with pytest.raises(TypeError, match="ObjectTable"):
        evaluate_detections({0: "boxes"}, gt)
    with pytest.raises(ValueError, match="sampling"):
        evaluate_detections(gt, gt, sampling="coco")
    one = evaluate_detections(gt, gt, classes="Car", metrics="bev", difficulties="easy")
    assert [(c.cls, c.metric, c.difficulty) for c in one.curves] == [("Car", "bev", "easy")] * 2


# ------------------------------------------------------------------ real KITTI
def test_real_object_labels_against_themselves(kitti_object):
    ds = KittiObject(kitti_object)
    labels = {i: ds.labels(i) for i in ds.ids}
    r = evaluate_detections(labels, labels)
    evaluated = [c for c in r.curves if c.n_gt > 0]
    assert {c.cls for c in evaluated} >= {"Car", "Pedestrian"}
    assert all(c.ap_r40 == pytest.approx(100.0) for c in evaluated)
    assert all(math.isnan(c.ap_r40) for c in r.curves if c.n_gt == 0)


def test_real_tracking_labels_against_themselves(kitti_tracking_lidar):
    labels = read_labels(kitti_tracking_lidar / "training" / "label_02" / "0001.txt")
    r = evaluate_detections(labels, labels, classes=("Car",))
    assert r.curve("Car", "moderate", "3d", 0.7).n_gt > 100  # 113 cars over 27 frames
    assert all(c.ap_r40 == pytest.approx(100.0) for c in r.curves)


def test_orientation_similarity_counts_a_turned_box_as_zero():
    """AOS weights each true positive by (1 + cos(d alpha)) / 2: every box facing its label
    gives AOS = AP; every box turned around (alpha + pi, an IoU unchanged) AOS 0; a quarter
    turn 0.5 of the AP; an unknown angle (-10) no AOS."""
    gt = _boxes([{"slot": k} for k in range(4)])
    same = _boxes([{"slot": k, "score": 0.9 - 0.1 * k} for k in range(3)])

    def aos_and_ap(dets):
        r = evaluate_detections(gt, dets, classes=("Car",), metrics=("2d",), iou=0.7,
                                difficulties=("moderate",))
        return r.aos("Car", "moderate", 0.7), r.ap("Car", "moderate", "2d", 0.7)

    aos, ap = aos_and_ap(same)
    assert ap == pytest.approx(75.0) and aos == pytest.approx(ap)  # 3 of 4 found
    turned = _boxes([{"slot": k, "score": 0.9 - 0.1 * k} for k in range(3)])
    turned.alpha[:] = np.pi
    aos, ap = aos_and_ap(turned)
    assert ap == pytest.approx(75.0) and aos == pytest.approx(0.0, abs=1e-9)
    quarter = _boxes([{"slot": k, "score": 0.9 - 0.1 * k} for k in range(3)])
    quarter.alpha[:] = np.pi / 2
    assert aos_and_ap(quarter)[0] == pytest.approx(37.5)
    unknown = _boxes([{"slot": k, "score": 0.9 - 0.1 * k} for k in range(3)])
    unknown.alpha[1] = -10.0
    assert math.isnan(aos_and_ap(unknown)[0])


def test_real_labels_give_aos_equal_to_ap(kitti_tracking_lidar):
    labels = read_labels(kitti_tracking_lidar / "training" / "label_02" / "0001.txt")
    r = evaluate_detections(labels, labels, classes=("Car",), metrics=("2d",))
    assert r.aos("Car", "moderate", 0.7) == pytest.approx(100.0)


def test_real_pointrcnn_detections_of_0001(kitti_tracking_lidar):
    """PointRCNN (Shi et al., CVPR 2019) reports about 78.6 % 3D AP (R11) for moderate cars
    at IoU 0.7 on KITTI val, where BEV AP is higher and IoU 0.5 leaves only the misses;
    sequence 0001 is a city street with parked cars, neither much easier nor harder. A
    range, not a number: wrong box conventions (bottom vs centre y, yaw sign) would drop
    3D@0.7 towards 0, a broken matcher would give 100 or 0."""
    labels = read_labels(kitti_tracking_lidar / "training" / "label_02" / "0001.txt")
    dets = read_detections(kitti_tracking_lidar / "detections" / "pointrcnn_car_val" / "0001.txt")
    r = evaluate_detections(labels, dets, classes=("Car",))
    ap = {(m, iou): r.ap("Car", "moderate", m, iou) for m in ("2d", "bev", "3d")
          for iou in (0.7, 0.5)}
    assert 60.0 < ap["3d", 0.7] < 95.0
    assert 75.0 < ap["bev", 0.7] < 99.0
    assert ap["bev", 0.5] > 90.0 and ap["3d", 0.5] > 90.0
    # 3D IoU never exceeds bird-view IoU for boxes of this height; a looser IoU finds more
    assert ap["3d", 0.7] <= ap["bev", 0.7] <= ap["bev", 0.5]
    # PointRCNN knows front from back: its orientation score stays near its 2D AP
    assert ap["2d", 0.7] - 5.0 < r.aos("Car", "moderate", 0.7) <= ap["2d", 0.7] + 1e-9


# ------------------------------------------------------------------ command line
def _run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="twistslam")
    add_eval_detections(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["eval-detections", *argv])
    return args.handler(args)


def _write_object_results(folder, tables: dict[int, ObjectTable]) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for frame, table in tables.items():
        # the tracking format without its first two columns (frame, track id) is the object one
        lines = [line.split(" ", 2)[2] for line in format_label_lines(table)]
        (folder / f"{frame:06d}.txt").write_text("".join(f"{s}\n" for s in lines))


def test_cli_object_root_and_result_folder(kitti_object, tmp_path, capsys):
    ds = KittiObject(kitti_object)
    _write_object_results(tmp_path / "dets", {i: ds.labels(i) for i in ds.ids[:4]})
    out = tmp_path / "out" / "ap.json"
    assert _run([str(kitti_object), str(tmp_path / "dets"), "--metrics", "bev", "3d",
                 "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "over 4 frames" in text and "BEV@0.7" in text and "100.00" in text
    data = json.loads(out.read_text())
    assert data["n_frames"] == 4 and data["sampling"] == "exact"
    assert {c["metric"] for c in data["curves"]} == {"bev", "3d"}


def test_cli_tracking_root_with_pointrcnn_and_result_files(kitti_tracking_lidar, tmp_path,
                                                            capsys):
    dets = kitti_tracking_lidar / "detections" / "pointrcnn_car_val"
    assert _run([str(kitti_tracking_lidar), str(dets), "--seq", "0001", "--classes", "Car"]) == 0
    comma = capsys.readouterr().out
    assert "over 27 frames" in comma
    # the same detections as a tracking result file give the same table
    write_tracking_results(tmp_path / "0001.txt", read_detections(dets / "0001.txt"))
    assert _run([str(kitti_tracking_lidar), str(tmp_path / "0001.txt"), "--seq", "0001",
                 "--classes", "Car"]) == 0
    assert capsys.readouterr().out == comma


def test_cli_errors(kitti_object, kitti_tracking_lidar, tmp_path):
    with pytest.raises(ValueError, match="--seq"):
        _run([str(kitti_tracking_lidar), str(tmp_path)])
    with pytest.raises(FileNotFoundError, match="sequence 0007"):
        _run([str(kitti_tracking_lidar), str(tmp_path), "--seq", "0007"])
    with pytest.raises(ValueError, match="no detection files"):
        _run([str(kitti_object), str(tmp_path)])
    _write_object_results(tmp_path / "far", {123: _boxes([{"slot": 0}])})
    with pytest.raises(ValueError, match="no label file for detected frame 000123"):
        _run([str(kitti_object), str(tmp_path / "far")])
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "000001.txt").write_text("Car 0 0 0 1 2 3\n")
    with pytest.raises(ValueError, match=r"000001.txt:1: expected 15 or 16 columns"):
        _run([str(kitti_object), str(bad)])
