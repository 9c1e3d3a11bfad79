"""CLEAR MOT: parity with motmetrics on 2D-IoU matching problems, and the devkit's ignore rules."""

from __future__ import annotations

import motmetrics as mm
import numpy as np
import pytest

from twistslam.datasets.objects import ObjectTable
from twistslam.eval.clear_mot import clear_mot, count_switches
from twistslam.eval.difficulty import DIFFICULTIES, Difficulty
from twistslam.eval.matching import assign, iou_function, match_sequence

#: no difficulty filtering, so that the devkit's ignore rules and motmetrics coincide
EVERYTHING = Difficulty("everything", min_height=0.0, max_occlusion=3, max_truncation=1.0)


def table(rows) -> ObjectTable:
    """rows: ``(frame, track_id, cls, x1, y1, x2, y2[, occlusion, truncation])``; boxes are 2D
    only (the 3D columns are zeros: these tests match in the image)."""
    if not rows:
        return ObjectTable.empty()
    rows = [tuple(r) if len(r) == 9 else (*r, 0, 0.0) for r in rows]
    n = len(rows)
    return ObjectTable(
        frame=[r[0] for r in rows], track_id=[r[1] for r in rows], cls=[r[2] for r in rows],
        truncation=[r[8] for r in rows], occlusion=[r[7] for r in rows], alpha=np.zeros(n),
        box_2d=[r[3:7] for r in rows], box_3d=np.zeros((n, 7)), score=np.ones(n),
    )


def random_problem(seed: int, n_frames: int = 80, n_objects: int = 7):
    """Random 2D tracking problem with misses, false positives and id switches.

    Each object lives in its own 400 px cell, so a tracker box can only ever overlap one
    ground-truth box: the optimal assignment is unique and motmetrics' carry-over of last
    frame's matches cannot disagree with the devkit's per-frame Hungarian method.
    """
    rng = np.random.default_rng(seed)
    cells = [(400.0 * (k % 5) + 200, 400.0 * (k // 5) + 200) for k in range(n_objects + 4)]
    size = rng.uniform(40, 90, (n_objects, 2))
    span = np.sort(rng.integers(0, n_frames, (n_objects, 2)), axis=1)
    hyp_id = np.arange(n_objects) + 100
    next_id = 1000
    gt_rows, est_rows = [], []
    for f in range(n_frames):
        if rng.random() < 0.08:  # two trackers swap their objects
            a, b = rng.choice(n_objects, 2, replace=False)
            hyp_id[[a, b]] = hyp_id[[b, a]]
        for k in range(n_objects):
            if not span[k, 0] <= f <= span[k, 1] or rng.random() < 0.05:
                continue  # object not in this frame
            cx, cy = np.array(cells[k]) + rng.normal(0, 5, 2)
            w, h = size[k]
            box = [cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2]
            gt_rows.append((f, k, "Car", *box))
            r = rng.random()
            if r < 0.12:
                continue  # missed
            if rng.random() < 0.04:  # tracker re-initialises with a new id
                hyp_id[k], next_id = next_id, next_id + 1
            shift = rng.normal(0, 4, 2) if r > 0.2 else np.array([1.1 * w, 0.0])  # bad box
            est_rows.append((f, int(hyp_id[k]), "Car", *(np.array(box) + np.tile(shift, 2))))
        for c in cells[n_objects:]:
            if rng.random() < 0.1:  # false positive in an empty cell
                est_rows.append((f, int(next_id), "Car", c[0], c[1], c[0] + 50, c[1] + 60))
                next_id += 1
    return table(gt_rows), table(est_rows)


def motmetrics_summary(gt: ObjectTable, est: ObjectTable, threshold: float) -> dict:
    acc = mm.MOTAccumulator(auto_id=True)
    xywh = lambda b: np.column_stack([b[:, :2], b[:, 2:] - b[:, :2]])  # noqa: E731
    for f in range(int(max(gt.frame.max(), est.frame.max())) + 1):
        g, e = gt.in_frame(f), est.in_frame(f)
        # motmetrics' iou_matrix uses np.asfarray (gone in numpy 2): same formula by hand
        iou = mm.distances.boxiou(xywh(g.box_2d)[:, None], xywh(e.box_2d)[None, :])
        dist = 1.0 - np.asarray(iou, dtype=float).reshape(len(g), len(e))
        dist[dist > 1.0 - threshold] = np.nan
        acc.update(list(g.track_id), list(e.track_id), dist)
    names = ["mota", "motp", "num_switches", "num_false_positives", "num_misses",
             "num_fragmentations", "num_objects", "num_matches"]
    return mm.metrics.create().compute(acc, metrics=names, name="seq").iloc[0].to_dict()


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4])
def test_clear_mot_equals_motmetrics(seed):
    gt, est = random_problem(seed)
    ours = clear_mot(match_sequence(gt, est, iou_function("2d"), cls="car",
                                    difficulty=EVERYTHING, threshold=0.25, mode="2d"))
    ref = motmetrics_summary(gt, est, 0.25)
    # the generated problem must exercise every term
    assert ref["num_switches"] > 0 and ref["num_misses"] > 0 and ref["num_false_positives"] > 0
    # motmetrics files a switching match under SWITCH, not MATCH: both are true positives
    assert ours.n_gt == ref["num_objects"]
    assert ours.tp == ref["num_matches"] + ref["num_switches"]
    assert ours.idsw == ref["num_switches"]
    assert ours.fp == ref["num_false_positives"]
    assert ours.fn == ref["num_misses"]
    assert ours.frag == ref["num_fragmentations"]
    assert ours.mota == pytest.approx(100.0 * ref["mota"], abs=1e-9)
    assert ours.motp == pytest.approx(100.0 * (1.0 - ref["motp"]), abs=1e-9)  # mm: mean 1-IoU


def test_count_switches_and_fragmentations():
    # tracked by 1, lost, tracked by 1, switched to 2, lost twice, tracked by 2
    history = np.array([-1, 1, 1, -1, 1, 2, -1, -1, 2])
    assert count_switches(history) == (1, 2)
    # a switch across a gap is still a switch (last matched id, not last frame's)
    assert count_switches(np.array([5, -1, 6])) == (1, 1)
    assert count_switches(np.array([-1, -1, 3, 3])) == (0, 0)


def test_assign_forbids_pairs_below_threshold_and_maximises_matches():
    iou = np.array([[0.9, 0.3], [0.8, 0.0]])
    # greedy would give row 0 -> col 0 and leave row 1 alone; two matches beat one
    rows, cols = assign(iou, 0.25)
    assert sorted(zip(rows.tolist(), cols.tolist())) == [(0, 1), (1, 0)]
    rows, cols = assign(iou, 0.5)
    assert sorted(zip(rows.tolist(), cols.tolist())) == [(0, 0)]


def run(gt_rows, est_rows, difficulty=DIFFICULTIES["easy"]):
    return clear_mot(match_sequence(table(gt_rows), table(est_rows), iou_function("2d"),
                                    cls="car", difficulty=difficulty, threshold=0.5, mode="2d"))


CAR = (100, 100, 200, 180)  # 80 px high: passes the easy height
FAR = (600, 100, 700, 180)


def test_neighbour_class_is_ignored_both_ways():
    # a Van nobody tracks is not missed; a tracked Van (any class) is no false positive
    m = run([(0, 1, "Car", *CAR), (0, 2, "Van", *FAR)], [(0, 7, "Car", *CAR)])
    assert (m.tp, m.fn, m.fp, m.n_gt) == (1, 0, 0, 1)
    m = run([(0, 1, "Car", *CAR), (0, 2, "Van", *FAR)], [(0, 7, "Car", *CAR), (0, 8, "Car", *FAR)])
    assert (m.tp, m.fn, m.fp) == (1, 0, 0)
    # an unmatched tracker box labelled Van is ignored, one labelled Car is a false positive
    assert run([(0, 1, "Car", *CAR)], [(0, 7, "Car", *CAR), (0, 8, "Van", *FAR)]).fp == 0
    assert run([(0, 1, "Car", *CAR)], [(0, 7, "Car", *CAR), (0, 8, "Car", *FAR)]).fp == 1
    # other classes and untracked rows (track id -1) are not evaluated at all
    assert run([(0, 1, "Car", *CAR)], [(0, 7, "Car", *CAR), (0, 8, "Pedestrian", *FAR),
                                       (0, -1, "Car", *FAR)]).fp == 0


def test_dont_care_and_min_height():
    dc = (580, 90, 720, 200)
    inside, half_out = FAR, (670, 100, 770, 180)  # 100 % and exactly 50 % inside the region
    gt = [(0, 1, "Car", *CAR), (0, -1, "DontCare", *dc)]
    m = run(gt, [(0, 7, "Car", *CAR), (0, 8, "Car", *inside)])
    assert m.fp == 0
    m = run(gt, [(0, 7, "Car", *CAR), (0, 8, "Car", *half_out)])
    assert m.fp == 1  # the devkit needs more than half of the box inside
    small = (600, 100, 700, 130)  # 30 px high, below the easy 40 px
    assert run([(0, 1, "Car", *CAR)], [(0, 7, "Car", *CAR), (0, 8, "Car", *small)]).fp == 0
    assert run([(0, 1, "Car", *CAR)], [(0, 7, "Car", *CAR), (0, 8, "Car", *small)],
               DIFFICULTIES["hard"]).fp == 1  # 30 px passes the hard 25 px


def test_difficulty_ignores_ground_truth():
    occluded = (0, 2, "Car", *FAR, 1, 0.0)  # occlusion level 1
    truncated = (0, 3, "Car", 300, 100, 400, 180, 0, 1.0)  # truncation level 1
    tiny = (0, 4, "Car", 450, 100, 550, 120)  # 20 px high
    hidden = (0, 5, "Car", 800, 100, 900, 180, 2, 0.0)  # occlusion level 2
    gt = [(0, 1, "Car", *CAR), occluded, truncated, tiny, hidden]
    m = run(gt, [(0, 7, "Car", *CAR)])
    assert (m.n_gt, m.tp, m.fn, m.fp) == (1, 1, 0, 0)  # easy: only the first box counts
    # matched to an ignored box: neither a true nor a false positive
    m = run(gt, [(0, 7, "Car", *CAR), (0, 8, "Car", *FAR)])
    assert (m.tp, m.fp) == (1, 0)
    m = run(gt, [(0, 7, "Car", *CAR)], DIFFICULTIES["moderate"])
    assert (m.n_gt, m.fn) == (2, 1)  # moderate admits occlusion 1 (not truncation 1 / 20 px)
    m = run(gt, [(0, 7, "Car", *CAR)], DIFFICULTIES["hard"])
    assert (m.n_gt, m.fn) == (3, 2)  # hard admits occlusion 2 as well


def test_gt_track_is_paired_with_the_tracker_matched_most_often():
    from twistslam.eval.track_metrics import pair_tracks, track_detection

    gt = [(f, 1, "Car", *CAR) for f in range(10)] + [(f, 2, "Car", *FAR) for f in range(4)]
    est = ([(f, 5, "Car", *CAR) for f in range(3)] + [(f, 9, "Car", *CAR) for f in range(3, 10)]
           + [(f, 7 if f < 2 else 8, "Car", *FAR) for f in range(4)])  # a 2 : 2 tie
    m = match_sequence(table(gt), table(est), iou_function("2d"), cls="car",
                       difficulty=DIFFICULTIES["easy"], threshold=0.5, mode="2d")
    assert pair_tracks(m) == {1: 9, 2: 7}  # most frames; a tie goes to the first matched
    det = track_detection(m)
    assert (det[1].n_frames, det[1].n_tp, det[1].tp_rate, det[1].motp) == (10, 10, 100.0, 100.0)
