"""sAMOTA, AMOTA, AMOTP (AB3DMOT's definitions): hand-worked cases, the independent
implementation of AB3DMOT's evaluator (PyPI ``eval-ab-3d-mot``) on synthetic sequences, and
AB3DMOT's own output files."""

from __future__ import annotations

import contextlib
import importlib
import io

import numpy as np
import pytest
from test_eval_devkit import SEQS, our_overlaps, reference_evaluation, write_synthetic

from twistslam.datasets import ObjectTable
from twistslam.eval import evaluate_mot
from twistslam.eval.amota import recall_thresholds, score_sweep
from twistslam.eval.difficulty import Difficulty
from twistslam.eval.matching import iou_function, sequence_overlaps

#: nothing ignored for difficulty: the hand-worked counts are plain CLEAR MOT
EVERYTHING = Difficulty("everything", min_height=0.0, max_occlusion=3, max_truncation=1.0)


def test_recall_thresholds_hand_worked():
    scores = np.array([0.6, 0.95, 0.9, 0.85, 0.8, 0.75, 0.7, 0.65])  # any order
    # 8 ground-truth boxes, 4 recall points (targets 0, .25, .5, .75, 1). Sorted, score k
    # reaches recall (k+1)/8. Target 0: score 0 (.125; the next, .25, is not nearer).
    # Target .25: score 1 reaches .25 exactly. Target .5: score 2 (.375) is skipped, the
    # next (.5) is nearer; score 3. Likewise .75 -> score 5, and 1.0 -> score 7 (the last
    # score always closes the walk). The target-0 point is dropped.
    thresholds, recalls = recall_thresholds(scores, n_gt=8, n_points=4)
    assert thresholds.tolist() == [0.9, 0.8, 0.7, 0.6]
    assert recalls.tolist() == [0.25, 0.5, 0.75, 1.0]
    # a tracker that never gets past recall 4/8: the curve stops at its last score
    thresholds, recalls = recall_thresholds(scores[1:5], n_gt=8, n_points=4)
    assert thresholds.tolist() == [0.9, 0.8] and recalls.tolist() == [0.25, 0.5]
    assert len(recall_thresholds(np.zeros(0), 8)[0]) == 0


CAR = (100.0, 100.0, 200.0, 180.0)


def _rows_2d(rows: list[tuple]) -> ObjectTable:
    """rows: ``(frame, track_id, x1, y1, x2, y2, score)``, class Car, image boxes only."""
    n = len(rows)
    return ObjectTable(
        frame=[r[0] for r in rows], track_id=[r[1] for r in rows], cls=["Car"] * n,
        truncation=np.zeros(n), occlusion=np.zeros(n), alpha=np.zeros(n),
        box_2d=[r[2:6] for r in rows], box_3d=np.zeros((n, 7)), score=[r[6] for r in rows],
    )


def hand_case(false_positives: list[tuple[int, float, range]]):
    """One ground-truth car over frames 0-39. Track 10 (score 0.9) covers it in frames
    0-19, track 20 (score 0.4) in frames 20-39 (exact boxes); each ``(id, score, frames)``
    adds a false-positive track far away."""
    gt = _rows_2d([(f, 1, *CAR, 1.0) for f in range(40)])
    est = [(f, 10 if f < 20 else 20, *CAR, 0.9 if f < 20 else 0.4) for f in range(40)]
    for tid, score, frames in false_positives:
        est += [(f, tid, 600.0 + 10 * tid, 100.0, 700.0 + 10 * tid, 180.0, score)
                for f in frames]
    return sequence_overlaps(gt, _rows_2d(est), iou_function("2d"), cls="car",
                             difficulty=EVERYTHING, threshold=0.5, mode="2d",
                             gt_min_height=False)


@pytest.mark.parametrize("protocol", ["kitti", "clear"])
def test_score_sweep_hand_worked(protocol):
    # All tracks: 40 matches (20 of score 0.9, 20 of 0.4), no miss: n = 40, one match per
    # recall point, so all 40 scores are picked with targets 0, 1/40, ... and the first is
    # dropped: 19 thresholds 0.9 (recall k/40, k = 1..19), 20 thresholds 0.4 (k = 20..39).
    # Few false positives: track 30 (score 0.8), 5 boxes.
    #   t = 0.9: track 10 only: FN 20, FP 0, IDSW 0; MOTA = 1 - 20/40 = 0.5;
    #            sMOTA = 1 - (20 - (1 - r) 40) / (40 r) = 20 / (40 r) >= 1 for r <= 0.5: 1.
    #   t = 0.4: all three: FN 0, FP 5, IDSW 1 (10 -> 20 on consecutive frames 19, 20);
    #            MOTA = 1 - 6/40 = 0.85; sMOTA = 34 / (40 r) = 34 / k: 1 up to k = 34,
    #            then 34/35 .. 34/39.
    #   MOTP = 1 at every point (exact boxes).
    s = score_sweep(hand_case([(30, 0.8, range(5))]), protocol)
    assert len(s.thresholds) == 39 and s.recalls[-1] == pytest.approx(39 / 40)
    assert s.samota == pytest.approx(100 * (19 + 15 + sum(34 / k for k in range(35, 40))) / 40)
    assert s.amota == pytest.approx(100 * (19 * 0.5 + 20 * 0.85) / 40)
    assert s.amotp == pytest.approx(100 * 39 / 40)
    assert s.protocol == protocol

    # Many false positives that no threshold removes (score 0.95 > every threshold, and
    # unmatched, so they add no threshold): tracks 30 (40 boxes) and 31 (10 boxes).
    #   t = 0.9: errors 20 + 50 = 70 > n_gt: sMOTA = 1 - (30 + 40 r) / (40 r) < 0 -> 0;
    #            MOTA = 1 - 70/40 = -0.75 (MOTA is not clipped).
    #   t = 0.4: errors 50 + 1 = 51: sMOTA -> 0; MOTA = 1 - 51/40 = -0.275.
    s = score_sweep(hand_case([(30, 0.95, range(40)), (31, 0.95, range(10))]), protocol)
    assert s.samota == 0.0
    assert s.amota == pytest.approx(100 * (19 * -0.75 + 20 * -0.275) / 40)


def reference_sweep(label, result, n_frames) -> tuple[float, float, float, list[float]]:
    """sAMOTA, AMOTA, AMOTP (percent) and the thresholds by eval-ab-3d-mot, driven as
    AB3DMOT's evaluate() drives its evaluator, except that the tracker file is reloaded
    before each threshold: AB3DMOT overwrites each box's score with its track's mean and
    then averages those means again, so whether a track whose mean *is* the threshold
    survives depends on round-off (eval-ab-3d-mot instead scales the thresholds by
    1 + 1e-12, which always drops it). Reloaded, a track is kept iff mean >= threshold."""
    get_thresholds = importlib.import_module("eval_ab_3d_mot.thresholds").get_thresholds
    e = reference_evaluation(label, result, n_frames)
    sums = np.zeros(3)
    with contextlib.redirect_stdout(io.StringIO()):
        e.compute_3rd_party_metrics()
        thresholds, recalls = get_thresholds(e.scores, e.num_gt)
        for threshold, recall in zip(thresholds, recalls):
            e.reset()
            e.load_data(is_ground_truth=False)
            e.compute_3rd_party_metrics(threshold, recall)
            sums += [e.sMOTA, e.MOTA, e.MOTP]
    samota, amota, amotp = 100.0 * sums / 40
    return samota, amota, amotp, thresholds


@pytest.mark.parametrize("seed", [0, 3])
def test_score_sweep_equals_reference_implementation(tmp_path, seed):
    label, result, n_frames = write_synthetic(tmp_path, seed)
    samota, amota, amotp, thresholds = reference_sweep(label, result, n_frames)
    ours = score_sweep(our_overlaps(label, result), "kitti")
    assert len(thresholds) > 10  # a real curve, not a degenerate one
    np.testing.assert_allclose(ours.thresholds, thresholds, rtol=0, atol=1e-12)
    assert 0 < ours.samota < 100 and ours.amota < ours.samota
    assert ours.samota == pytest.approx(samota, abs=1e-9)
    assert ours.amota == pytest.approx(amota, abs=1e-9)
    assert ours.amotp == pytest.approx(amotp, abs=1e-6)  # IoU by ConvexHull there


#: eval-ab-3d-mot 2.3.0 on ab3dmot/raw, driven as reference_sweep above (tracker reloaded
#: per threshold), per sequence: sAMOTA, AMOTA, AMOTP in percent (6 decimals). Recomputing
#: them live takes minutes (pure-Python Hungarian and ConvexHull IoUs), hence stored.
REFERENCE_RAW = {
    "0001": (91.474052, 43.861136, 77.527289),
    "0006": (97.257081, 55.300000, 82.611082),
    "0008": (86.128102, 47.098214, 65.873262),
    "0010": (87.218650, 53.116379, 75.873928),
    "0012": (92.457002, 60.594406, 76.513744),
}
REFERENCE_RAW_ALL = (90.938603, 43.290584, 76.243585)  # the five together, pooled


def test_ab3dmot_raw_samota_per_sequence(kitti_tracking, ab3dmot_outputs, capsys):
    r = evaluate_mot(kitti_tracking, ab3dmot_outputs / "raw", SEQS, protocol="kitti")
    with capsys.disabled():
        print("\nAB3DMOT raw, kitti protocol, 3D IoU 0.25, car: sAMOTA AMOTA AMOTP (ours)")
        for seq, m in list(r.sequences.items()) + [("all", r.overall)]:
            print(f"  {seq}: {m.samota:.2f} {m.amota:.2f} {m.amotp:.2f}")
    for seq, expected in REFERENCE_RAW.items():
        m = r.sequences[seq]
        assert (m.samota, m.amota, m.amotp) == pytest.approx(expected, abs=2e-6)
    m = r.overall
    assert (m.samota, m.amota, m.amotp) == pytest.approx(REFERENCE_RAW_ALL, abs=2e-6)
