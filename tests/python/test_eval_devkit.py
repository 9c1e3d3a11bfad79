"""The ``kitti`` protocol: the KITTI tracking devkit as AB3DMOT's evaluate.py runs it.

Checked three ways: the figures AB3DMOT's own evaluator printed on its output files
(``ab3dmot/README.md``), an independent implementation of that evaluator (the PyPI package
``eval-ab-3d-mot``, a refactoring of AB3DMOT's ``scripts/KITTI/evaluate.py``) on synthetic
sequences that exercise every rule, and hand-worked track histories.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from twistslam import cli
from twistslam.datasets import ObjectTable, read_labels, write_labels, write_tracking_results
from twistslam.eval import evaluate_mot
from twistslam.eval.devkit import count_devkit_switches, devkit_mot
from twistslam.eval.difficulty import DIFFICULTIES
from twistslam.eval.matching import iou_function, sequence_overlaps

SEQS = ["0001", "0006", "0008", "0010", "0012"]

#: ab3dmot/README.md: AB3DMOT's evaluator, 3D IoU 0.25, car:
#: kind -> seq -> (MOTA, MOTP, IDSW, FRAG, FP, FN)
README = {
    "raw": {
        "0001": (71.17, 79.39, 0, 6, 499, 156), "0006": (90.80, 80.45, 0, 3, 30, 16),
        "0008": (67.76, 72.05, 0, 6, 173, 152), "0010": (65.17, 83.46, 0, 0, 119, 83),
        "0012": (83.92, 79.83, 0, 1, 10, 13),
    },
    "thresholded": {
        "0001": (81.34, 79.58, 0, 4, 244, 180), "0006": (93.80, 82.00, 0, 2, 8, 23),
        "0008": (77.98, 73.42, 0, 1, 24, 198), "0010": (83.10, 83.50, 0, 0, 15, 83),
        "0012": (90.91, 79.83, 0, 1, 0, 13),
    },
}
AB3DMOT_THRESHOLD = 3.240738  # the mean track score behind thresholded/ (README)


# ------------------------------------------------------------------ AB3DMOT's figures
@pytest.fixture(scope="module")
def ab3dmot_kitti(kitti_tracking, ab3dmot_outputs):
    """Our kitti-protocol evaluation of AB3DMOT's raw and thresholded files."""
    return {kind: evaluate_mot(kitti_tracking, ab3dmot_outputs / kind, SEQS, protocol="kitti")
            for kind in README}


@pytest.mark.parametrize("kind", list(README))
@pytest.mark.parametrize("seq", SEQS)
def test_kitti_protocol_equals_ab3dmot_evaluator(ab3dmot_kitti, kind, seq):
    m = ab3dmot_kitti[kind].sequences[seq]
    ours = (round(m.mota, 2), round(m.motp, 2), m.idsw, m.frag, m.fp, m.fn)
    assert ours == README[kind][seq]
    assert m.protocol == "kitti" and ab3dmot_kitti[kind].difficulty == "hard"


def test_overall_is_the_sum_of_the_sequences(ab3dmot_kitti):
    r = ab3dmot_kitti["raw"]
    for key in ("idsw", "frag", "fp", "fn", "n_gt"):
        assert getattr(r.overall, key) == sum(getattr(m, key) for m in r.sequences.values())
    n_gt, errors = r.overall.n_gt, r.overall.fn + r.overall.fp + r.overall.idsw
    assert r.overall.mota == pytest.approx(100.0 * (1 - errors / n_gt))


def test_min_score_reproduces_the_thresholded_files(kitti_tracking, ab3dmot_outputs,
                                                    ab3dmot_kitti):
    # thresholded/ is raw/ keeping tracks whose mean score >= the threshold
    ours = evaluate_mot(kitti_tracking, ab3dmot_outputs / "raw", SEQS, protocol="kitti",
                        min_score=AB3DMOT_THRESHOLD)
    for seq in SEQS:
        a, b = ours.sequences[seq], ab3dmot_kitti["thresholded"].sequences[seq]
        assert (a.mota, a.motp, a.idsw, a.frag, a.fp, a.fn) == (
            b.mota, b.motp, b.idsw, b.frag, b.fp, b.fn)
    # sAMOTA sweeps its own thresholds over every track, whatever min_score
    assert ours.overall.samota == ab3dmot_kitti["raw"].overall.samota


def test_clear_protocol_ignores_small_ground_truth(kitti_tracking, ab3dmot_outputs):
    # README: ignoring ground truth under 25 px lowers FN of 0008 from 152 to 9
    clear = evaluate_mot(kitti_tracking, ab3dmot_outputs / "raw", ["0008"], protocol="clear",
                         difficulty="hard")
    assert clear.sequences["0008"].fn == 9 and clear.protocol == "clear"


def test_cli_kitti_protocol(kitti_tracking, ab3dmot_outputs, tmp_path, capsys):
    out = tmp_path / "m.json"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no oxts of some sequences: camera-frame warning
        code = cli.main(["eval", str(kitti_tracking), str(ab3dmot_outputs / "raw"), "--seq",
                         "0001", "--protocol", "kitti", "--json", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert "CLEAR MOT (kitti protocol; car, hard, IoU >= 0.25" in text
    assert "protocol kitti: KITTI tracking devkit" in text
    m = json.loads(out.read_text())
    assert m["settings"]["protocol"] == "kitti" and m["settings"]["difficulty"] == "hard"
    mot = m["mot"]["3d"]
    assert mot["protocol"] == "kitti"
    assert (round(mot["mota"], 2), round(mot["motp"], 2), mot["idsw"], mot["frag"], mot["fp"],
            mot["fn"]) == README["raw"]["0001"]
    assert 0.0 < mot["samota"] <= 100.0 and 0.0 < mot["hota"] <= 100.0


def test_cli_default_protocol_is_clear(kitti_tracking, ab3dmot_outputs, tmp_path):
    out = tmp_path / "m.json"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cli.main(["eval", str(kitti_tracking), str(ab3dmot_outputs / "raw"), "--seq",
                         "0012", "--json", str(out)]) == 0
    m = json.loads(out.read_text())
    assert m["settings"]["protocol"] == "clear" and m["settings"]["difficulty"] == "easy"
    assert {entry["protocol"] for entry in m["mot"].values()} == {"clear"}


def test_cli_missing_label_file_names_the_path(kitti_tracking, ab3dmot_outputs, tmp_path,
                                               capsys):
    root = tmp_path / "kitti"
    (root / "training" / "calib").mkdir(parents=True)
    calib = kitti_tracking / "training" / "calib" / "0001.txt"
    (root / "training" / "calib" / "0001.txt").write_text(calib.read_text())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the copied root has no images, LiDAR or oxts
        code = cli.main(["eval", str(root), str(ab3dmot_outputs / "raw"), "--seq", "0001"])
    assert code == 2
    err = capsys.readouterr().err.strip()
    expected = root / "training" / "label_02" / "0001.txt"
    assert err == ("twistslam eval: error: sequence 0001: ground-truth labels not found: "
                   f"{expected}")


# ------------------------------------------------------------------ hand-worked histories
@pytest.mark.parametrize("history, ignored, expected", [
    # switch between consecutive matched frames: IDSW, and FRAG (the next frame is matched)
    ([1, 1, 2, 2], [0, 0, 0, 0], (1, 1, 4)),
    # a new id after a miss is a fragmentation, not a switch (CLEAR MOT would count both)
    ([1, -1, 2, 2], [0, 0, 0, 0], (0, 1, 3)),
    # re-acquired with the same id after a miss: FRAG
    ([1, -1, 1, 1], [0, 0, 0, 0], (0, 1, 3)),
    # FRAG looks one frame ahead: re-acquired but missed again next frame -> nothing
    ([1, -1, 1, -1, -1], [0, 0, 0, 0, 0], (0, 0, 2)),
    # on the last frame any change to a matched id counts, even the very first match
    ([-1, -1, 3], [0, 0, 0], (0, 1, 1)),
    ([-1, 3], [0, 0], (0, 1, 1)),
    # an ignored frame makes the devkit forget the last id: no switch across it
    ([1, 1, 2, 2], [0, 1, 0, 0], (0, 0, 3)),
    # the first frame counts as tracked even when it is ignored
    ([5, 5, -1], [1, 0, 0], (0, 0, 2)),
    ([7], [0], (0, 0, 1)),
])
def test_devkit_switch_rules(history, ignored, expected):
    assert count_devkit_switches(np.array(history), np.array(ignored, dtype=bool)) == expected


# ------------------------------------------------------------------ synthetic sequences
def _table(rows: list[tuple]) -> ObjectTable:
    """rows: ``(frame, track_id, cls, box_2d(4), box_3d(7), occlusion, truncation, score)``."""
    n = len(rows)
    return ObjectTable(
        frame=[r[0] for r in rows], track_id=[r[1] for r in rows], cls=[r[2] for r in rows],
        truncation=[r[6] for r in rows], occlusion=[r[5] for r in rows], alpha=np.zeros(n),
        box_2d=[r[3] for r in rows], box_3d=[r[4] for r in rows], score=[r[7] for r in rows],
    )


def synthetic_sequence(seed: int, n_frames: int = 40, n_objects: int = 7):
    """A 3D tracking problem that exercises every devkit rule: misses, bad boxes, id swaps
    between consecutive frames, re-initialised ids, Vans on both sides, occluded and
    truncated ground truth, ground truth and false positives under 25 px, false positives
    inside a DontCare region, and track scores spread so that thresholds remove tracks.

    Objects stand 8 m apart side by side and bad boxes are pushed 6 m deeper, so a tracker
    box overlaps at most one ground-truth box: the assignment has no ties."""
    rng = np.random.default_rng(seed)
    ry = rng.uniform(-np.pi, np.pi, n_objects)
    kind = np.where(rng.random(n_objects) < 0.15, "Van", "Car")
    span = np.sort(rng.integers(0, n_frames, (n_objects, 2)), axis=1)
    hyp = list(range(100, 100 + n_objects))
    base: dict[int, float] = {}  # mean score of each tracker id
    next_id, fp_id = 1000, 4999  # re-initialised ids, false-positive ids
    dont_care = [1500.0, 100.0, 1700.0, 220.0]
    placeholder = [-10, -1, -1, -1000, -1000, -1000, -10]  # KITTI's DontCare 3D columns
    gt, est = [], []
    for f in range(n_frames):
        gt.append((f, -1, "DontCare", dont_care, placeholder, -1, -1, 1))
        if rng.random() < 0.08:  # two tracks swap their objects
            a, b = rng.choice(n_objects, 2, replace=False)
            hyp[a], hyp[b] = hyp[b], hyp[a]
        for k in range(n_objects):
            if not span[k, 0] <= f <= span[k, 1] or rng.random() < 0.05:
                continue
            box = np.array([8.0 * k - 24.0, 1.0, 15.0 + 0.3 * f, 4.0, 1.7, 1.5, ry[k]])
            height = rng.uniform(12, 25) if rng.random() < 0.15 else rng.uniform(30, 90)
            box2d = [150.0 * k, 100.0, 150.0 * k + 80.0, 100.0 + height]
            occlusion = int(rng.choice(4, p=[0.75, 0.12, 0.08, 0.05]))
            truncation = int(rng.choice(3, p=[0.85, 0.1, 0.05]))
            gt.append((f, k, kind[k], box2d, box, occlusion, truncation, 1.0))
            r = rng.random()
            if r < 0.12:
                continue  # missed
            if rng.random() < 0.04:  # the tracker re-initialises with a new id
                hyp[k], next_id = next_id, next_id + 1
            tid = hyp[k]
            base.setdefault(tid, rng.uniform(0.0, 1.0))
            noise = (np.r_[rng.normal(0, 0.15, 3), 0, 0, 0, 0] if r > 0.2
                     else [0, 0, 6.0, 0, 0, 0, 0])  # a bad box, 6 m too deep
            cls = "Van" if rng.random() < 0.05 else "Car"
            est.append((f, tid, cls, box2d, box + noise, 0, 0, base[tid] + rng.normal(0, 0.2)))
        if rng.random() < 0.35:  # a false positive, sometimes small or inside the DontCare
            if rng.random() < 0.3:
                fp_id += 1
            base.setdefault(fp_id, rng.uniform(-1.0, 0.5))
            u = rng.random()
            box2d = ([1550.0, 120.0, 1650.0, 200.0] if u < 0.3 else
                     [1200.0, 100.0, 1260.0, 100.0 + (20.0 if u < 0.5 else 60.0)])
            box = [40.0, 1.0, 20.0 + f, 4.0, 1.7, 1.5, 0.0]
            cls = "Van" if rng.random() < 0.2 else "Car"
            est.append((f, fp_id, cls, box2d, box, 0, 0, base[fp_id] + rng.normal(0, 0.2)))
    return _table(gt), _table(est)


def write_synthetic(tmp_path: Path, seed: int) -> tuple[Path, Path, int]:
    """Write a synthetic sequence in the layout eval-ab-3d-mot reads; returns the label
    and result files and the number of frames."""
    gt, est = synthetic_sequence(seed)
    label = tmp_path / "ann" / "label" / "0000.txt"
    result = tmp_path / "res" / "synthetic" / "data_0" / "0000.txt"
    write_labels(label, gt)
    write_tracking_results(result, est)
    return label, result, int(max(gt.frame.max(), est.frame.max())) + 1


def reference_evaluation(label: Path, result: Path, n_frames: int):
    """eval-ab-3d-mot's TrackingEvaluation (AB3DMOT's evaluator), 3D IoU 0.25, car, its
    default (AB3DMOT's) difficulty, loaded with ``label`` and ``result``."""
    module = importlib.import_module("eval_ab_3d_mot.core.tracking_evaluation")
    e = module.TrackingEvaluation(
        "synthetic", {label.stem: n_frames}, ann_root=str(label.parent.parent),
        res_root=str(result.parent.parent.parent), cls="car", eval_3diou=True,
    )
    with contextlib.redirect_stdout(io.StringIO()):
        e.load_data(is_ground_truth=False)
        e.load_data(is_ground_truth=True)
    return e


def our_overlaps(label: Path, result: Path):
    return sequence_overlaps(
        read_labels(label), read_labels(result), iou_function("3d"), cls="car",
        difficulty=DIFFICULTIES["hard"], threshold=0.25, mode="3d", gt_min_height=False,
    )


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_devkit_equals_reference_implementation(tmp_path, seed):
    label, result, n_frames = write_synthetic(tmp_path, seed)
    ref = reference_evaluation(label, result, n_frames)
    with contextlib.redirect_stdout(io.StringIO()):
        ref.compute_3rd_party_metrics()
    ours = devkit_mot(our_overlaps(label, result).match())
    # the problem must exercise the rules where the devkit departs from CLEAR MOT
    assert ref.id_switches > 0 and ref.fragments > ref.id_switches
    assert ref.fp > 0 and ref.fn > 0 and ref.itp > 0 and ref.n_itr > 0
    assert (ours.idsw, ours.frag, ours.fp, ours.fn, ours.n_gt) == (
        ref.id_switches, ref.fragments, ref.fp, ref.fn, ref.n_gt)
    assert ours.n_motp == ref.tp  # the devkit's tp counts matches to ignored ground truth
    assert ours.mota == pytest.approx(100.0 * ref.MOTA, abs=1e-9)
    assert ours.motp == pytest.approx(100.0 * ref.MOTP, abs=1e-6)  # IoU via ConvexHull there
    assert ours.mt == pytest.approx(100.0 * ref.MT, abs=1e-9)
    assert ours.ml == pytest.approx(100.0 * ref.ML, abs=1e-9)


def test_sequence_without_a_labelled_car_is_evaluated(kitti_tracking, tmp_path):
    """0017 has no Car / Van label: its tracks are all false positives, not a crash."""
    labels = read_labels(kitti_tracking / "training" / "label_02" / "0017.txt")
    assert not np.isin(labels.cls, ["Car", "Van"]).any()
    (tmp_path / "tracking").mkdir()
    (tmp_path / "tracking" / "0017.txt").write_text(
        "0 1 Car 0 0 0.0 100 100 200 200 1.5 1.6 4.0 1.0 1.5 20.0 0.0 5.0\n")
    r = evaluate_mot(kitti_tracking, tmp_path, ["0017"], protocol="kitti")
    assert r.overall.n_gt == 0 and r.overall.idsw == 0 and r.overall.fn == 0
    assert np.isnan(r.overall.mota)  # undefined without ground truth, not a crash
