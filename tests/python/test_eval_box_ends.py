"""Box-end offsets (twistslam.eval.box_ends): hand-built boxes with known near / far ends,
the view angle, one-to-one matching, and the ``eval-detections --box-ends`` command on real
KITTI detections."""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest

from twistslam.datasets import ObjectTable
from twistslam.eval.box_ends import COLUMNS, box_end_offsets, evaluate_box_ends
from twistslam.eval_detections_cli import add_eval_detections

COL = {name: i for i, name in enumerate(COLUMNS)}


def _table(boxes, frame: int = 0, cls: str = "Car") -> ObjectTable:
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 7)
    n = len(boxes)
    return ObjectTable(frame=np.full(n, frame), track_id=np.full(n, -1), cls=[cls] * n,
                       truncation=np.zeros(n), occlusion=np.zeros(n), alpha=np.zeros(n),
                       box_2d=np.tile([0.0, 0.0, 50.0, 50.0], (n, 1)), box_3d=boxes,
                       score=np.ones(n))


# a 4.5 m car 20 m straight ahead, its length along the line of sight (ry = -pi/2: +z)
AHEAD = [0.0, 1.0, 20.0, 4.5, 1.8, 1.5, -math.pi / 2]


def test_a_box_short_at_its_far_end_reports_it_there():
    # the detection keeps the near end (z = 17.75) and stops 0.3 m short of the far one
    short = [0.0, 1.0, 19.85, 4.2, 1.8, 1.5, -math.pi / 2]
    offsets, n_det = box_end_offsets(_table([AHEAD]), _table([short]))
    assert n_det == 1 and offsets.shape == (1, len(COLUMNS))
    row = offsets[0]
    assert row[COL["range_m"]] == pytest.approx(20.0)
    assert row[COL["view_deg"]] == pytest.approx(0.0, abs=1e-6)
    assert row[COL["near_m"]] == pytest.approx(0.0, abs=1e-9)
    assert row[COL["far_m"]] == pytest.approx(-0.3)
    assert row[COL["dl_m"]] == pytest.approx(-0.3)
    assert row[COL["centre_m"]] == pytest.approx(-0.15)  # towards the sensor


def test_ends_do_not_depend_on_the_heading_sign_nor_on_which_way_the_car_faces():
    short = [0.0, 1.0, 19.85, 4.2, 1.8, 1.5, -math.pi / 2]
    flipped = list(short[:6]) + [math.pi / 2]  # the same box, heading reversed
    facing = list(AHEAD[:6]) + [math.pi / 2]  # the label facing the camera instead
    for gt, det in ((AHEAD, flipped), (facing, short), (facing, flipped)):
        row = box_end_offsets(_table([gt]), _table([det]))[0][0]
        assert row[COL["near_m"]] == pytest.approx(0.0, abs=1e-9)
        assert row[COL["far_m"]] == pytest.approx(-0.3)


def test_view_angle_of_a_broadside_car_and_a_long_box_beyond_its_near_end():
    # broadside at 15 m: the ends are left and right, the nearer one is the one towards x = 0
    side = [3.0, 1.0, 15.0, 4.0, 1.8, 1.5, 0.0]  # length along camera x
    longer = [3.0 - 0.1, 1.0, 15.0, 4.4, 1.8, 1.5, 0.0]  # 0.3 m beyond the near end, 0.1 far
    row = box_end_offsets(_table([side]), _table([longer]))[0][0]
    assert row[COL["view_deg"]] == pytest.approx(math.degrees(math.atan2(15.0, 3.0)))
    assert row[COL["near_m"]] == pytest.approx(0.3)
    assert row[COL["far_m"]] == pytest.approx(0.1)
    # a box turned a quarter (length along z) is measured by its width along the label's axis
    quarter = [3.0, 1.0, 15.0, 1.8, 4.0, 1.5, math.pi / 2]
    row = box_end_offsets(_table([side]), _table([quarter]))[0][0]
    assert row[COL["near_m"]] == pytest.approx(0.0, abs=1e-9)
    assert row[COL["far_m"]] == pytest.approx(0.0, abs=1e-9)


def test_matching_is_one_to_one_closest_first_and_bounded():
    gt = _table([AHEAD, [1.4, 1.0, 20.0, 4.5, 1.8, 1.5, -math.pi / 2]])  # and one beside it
    dets = _table([[0.2, 1.0, 20.0, 4.5, 1.8, 1.5, -math.pi / 2],   # 0.2 m from the left car, 1.2 from the right
                   [0.1, 1.0, 20.3, 4.5, 1.8, 1.5, -math.pi / 2],   # 0.32 / 1.33 m: no car left for it
                   [9.0, 1.0, 20.0, 4.5, 1.8, 1.5, -math.pi / 2],   # 7.6 m from every car
                   [0.0, 1.0, 20.0, 4.5, 1.8, 1.5, -math.pi / 2]])  # exact, matched first
    gt_ped = _table([AHEAD], cls="Pedestrian")
    offsets, n_det = box_end_offsets(gt, dets)
    assert n_det == 4 and len(offsets) == 2  # left: the exact box; right: the 1.2 m one
    assert sorted(np.round(offsets[:, COL["near_m"]], 6)) == [0.0, 0.0]
    assert len(box_end_offsets(gt_ped, dets)[0]) == 0  # other classes play no part


def test_bins_take_medians_and_leave_empty_bins_out():
    gt, dets = {}, {}
    for f, (z, short_m) in enumerate([(12.0, 0.1), (12.5, 0.3), (13.0, 0.2), (40.0, 0.6)]):
        g = [0.0, 1.0, z, 4.5, 1.8, 1.5, -math.pi / 2]
        d = [0.0, 1.0, z - short_m / 2, 4.5 - short_m, 1.8, 1.5, -math.pi / 2]
        gt[f], dets[f] = _table([g], frame=f), _table([d], frame=f)
    result = evaluate_box_ends(gt, dets)
    assert result.n_matched == 4 and result.n_detections == 4
    assert [(r.view_deg, r.range_m, r.n) for r in result.rows] == [
        ((0.0, 10.0), (0.0, 15.0), 3), ((0.0, 10.0), (30.0, 80.0), 1)]
    assert result.rows[0].far_m == pytest.approx(-0.2)
    assert result.rows[1].far_m == pytest.approx(-0.6)
    assert "3 of" not in result.table() and "4 of 4" in result.table()
    assert json.loads(json.dumps(result.to_dict()))["bins"][0]["n"] == 3


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="view_bins_deg"):
        evaluate_box_ends(_table([AHEAD]), _table([AHEAD]), view_bins_deg=(10.0, 0.0))
    with pytest.raises(ValueError, match="max_centre_distance_m"):
        box_end_offsets(_table([AHEAD]), _table([AHEAD]), max_centre_distance_m=0.0)
    with pytest.raises(ValueError, match="non-finite"):
        box_end_offsets(_table([AHEAD]), _table([[0.0, 1.0, 20.0, np.nan, 1.8, 1.5, 0.0]]))
    with pytest.raises(TypeError, match="ObjectTable"):
        box_end_offsets({0: "not a table"}, _table([AHEAD]))


def test_cli_box_ends_on_real_pointrcnn_detections(kitti_tracking_lidar, tmp_path, capsys):
    parser = argparse.ArgumentParser(prog="twistslam")
    add_eval_detections(parser.add_subparsers(dest="command", required=True))
    dets = kitti_tracking_lidar / "detections" / "pointrcnn_car_val"
    out = tmp_path / "ap.json"
    args = parser.parse_args(["eval-detections", str(kitti_tracking_lidar), str(dets), "--seq",
                              "0001", "--classes", "Car", "--box-ends", "--json", str(out)])
    assert args.handler(args) == 0
    assert "Car box ends along the label's axis" in capsys.readouterr().out
    ends = json.loads(out.read_text())["box_ends"][0]
    assert ends["class"] == "Car" and ends["n_matched"] > 50
    # within 30 m a learned detector's boxes end where the labels do, within a few decimetres
    # per bin (a wrong axis or end convention puts whole car lengths there)
    near_bins = [b for b in ends["bins"] if b["n"] >= 10 and b["range_m"][1] <= 30]
    assert len(near_bins) >= 2
    for b in near_bins:
            assert abs(b["near_m"]) < 0.3 and abs(b["far_m"]) < 0.4, b


def test_an_oblique_car_is_measured_along_its_own_axis():
    # ry = -pi/4: the length runs along (x, z) = (1, 1) / sqrt 2, the car points away
    gt = [5.0, 1.0, 20.0, 4.5, 1.8, 1.5, -math.pi / 4]
    axis = np.array([1.0, 1.0]) / math.sqrt(2.0)
    centre = np.array([5.0, 20.0]) - 0.2 * axis  # 0.4 m shorter, the near end kept
    det = [centre[0], 1.0, centre[1], 4.1, 1.8, 1.5, -math.pi / 4]
    row = box_end_offsets(_table([gt]), _table([det]))[0][0]
    view = math.degrees(math.acos(np.array([5.0, 20.0]) @ axis / math.hypot(5.0, 20.0)))
    assert row[COL["view_deg"]] == pytest.approx(view)
    assert row[COL["near_m"]] == pytest.approx(0.0, abs=1e-9)
    assert row[COL["far_m"]] == pytest.approx(-0.4)
