"""The evaluator on the real KITTI tracking labels: perfect, shifted, dropped and swapped."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from twistslam import geometry
from twistslam.datasets import ObjectTable, read_labels, write_tracking_results
from twistslam.eval.difficulty import DIFFICULTIES
from twistslam.eval.sequence import evaluate_sequence, open_dataset

from conftest import require_real_data

ROOT = require_real_data("kitti_tracking")
LABELS = require_real_data("kitti_tracking", "training", "label_02")
SEQS = ["0001", "0004", "0020"]


@pytest.fixture(scope="module")
def labels_only_root(tmp_path_factory) -> Path:
    """The real calibration and labels without oxts: the evaluator's camera-frame case (the
    hand-computed expectations below shift boxes in each frame's camera frame; 0001 has oxts
    in the data folder, which would move the comparison into the world frame)."""
    import shutil

    root = tmp_path_factory.mktemp("labels_only")
    for folder in ("calib", "label_02"):
        shutil.copytree(ROOT / "training" / folder, root / "training" / folder)
    return root


def evaluate(root: Path, tmp_path: Path, seq: str, results: ObjectTable):
    write_tracking_results(tmp_path / "tracking" / f"{seq}.txt", results)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no oxts: camera-frame warning
        return evaluate_sequence(root, tmp_path, seq)


def easy_cars(gt: ObjectTable) -> np.ndarray:
    """Rows of gt that CLEAR MOT counts for Car / easy."""
    return (gt.cls == "Car") & DIFFICULTIES["easy"].accepts(gt)


@pytest.mark.parametrize("seq", SEQS)
def test_ground_truth_as_result_is_perfect(labels_only_root, tmp_path, seq):
    gt = read_labels(LABELS / f"{seq}.txt")
    m = evaluate(labels_only_root, tmp_path, seq, gt)
    for mode in ("2d", "bv", "3d"):
        mot = m.mot[mode]
        assert mot.mota == pytest.approx(100.0) and mot.motp == pytest.approx(100.0)
        assert mot.tp_rate == pytest.approx(100.0)
        assert (mot.fp, mot.fn, mot.idsw, mot.frag) == (0, 0, 0, 0)
        assert mot.n_gt == easy_cars(gt).sum() > 0
    assert len(m.objects) == len(np.unique(gt.track_id[easy_cars(gt)]))
    for obj in m.objects:
        assert obj.est_track_id == obj.track_id
        for key in ("tp_2d", "motp_2d", "tp_bv", "motp_bv", "tp_3d", "motp_3d"):
            assert getattr(obj, key) == pytest.approx(100.0), key
        assert obj.ate == pytest.approx(0.0, abs=1e-6)


def hand_iou_of_shift(box: np.ndarray, dx: float) -> float:
    """IoU of a box with itself moved by dx along camera x (bird view and 3D alike).

    In the box frame the shift splits into ``dx cos(ry)`` along the length and
    ``dx sin(ry)`` along the width; two equal rectangles offset by (a, b) overlap on
    ``(l - |a|)(w - |b|)``; the height overlap is full, so 3D IoU equals BV IoU.
    """
    length, width, ry = box[3], box[4], box[6]
    a, b = abs(dx * np.cos(ry)), abs(dx * np.sin(ry))
    inter = max(length - a, 0.0) * max(width - b, 0.0)
    return inter / (2 * length * width - inter)


def test_hand_formula_for_an_axis_aligned_box():
    # ry = pi/2: the width lies along camera x, so a sideways move is along the width
    box = np.array([0, 0, 10, 4.0, 1.6, 1.5, np.pi / 2])
    assert hand_iou_of_shift(box, 0.5) == pytest.approx((1.6 - 0.5) / (1.6 + 0.5))
    moved = box + [0.5, 0, 0, 0, 0, 0, 0]
    assert geometry.box_iou_bev(box[None], moved[None])[0, 0] == pytest.approx(1.1 / 2.1)
    assert geometry.box_iou_3d(box[None], moved[None])[0, 0] == pytest.approx(1.1 / 2.1)


@pytest.mark.parametrize("seq", SEQS)
def test_sideways_shift_lowers_bv_and_3d_motp_as_computed_by_hand(labels_only_root, tmp_path, seq):
    gt = read_labels(LABELS / f"{seq}.txt")
    shifted = read_labels(LABELS / f"{seq}.txt")
    real = shifted.box_3d[:, 3] > 0  # DontCare rows carry placeholder sizes
    shifted.box_3d[real, 0] += 0.5
    m = evaluate(labels_only_root, tmp_path, seq, shifted)

    counted = easy_cars(gt)
    expected = 100.0 * np.mean([hand_iou_of_shift(b, 0.5) for b in gt.box_3d[counted]])
    assert expected < 90.0  # the shift must matter
    for mode in ("bv", "3d"):
        mot = m.mot[mode]
        assert mot.tp_rate == pytest.approx(100.0)  # every box still overlaps >= 0.25
        assert mot.motp == pytest.approx(expected, abs=1e-6)
        assert mot.mota == pytest.approx(100.0)
    assert m.mot["2d"].motp == pytest.approx(100.0)  # the image boxes were not touched
    # per track too
    for obj in m.objects:
        rows = counted & (gt.track_id == obj.track_id)
        hand = 100.0 * np.mean([hand_iou_of_shift(b, 0.5) for b in gt.box_3d[rows]])
        assert obj.motp_bv == pytest.approx(hand, abs=1e-6)
        assert obj.motp_3d == pytest.approx(hand, abs=1e-6)
        # the object frame moved by 0.5 m in every frame: canonical ATE is exactly that
        assert obj.ate == pytest.approx(0.5, abs=1e-6)
        assert obj.ate_aligned == pytest.approx(0.0, abs=1e-6)


def longest_easy_car(gt: ObjectTable) -> int:
    ids, counts = np.unique(gt.track_id[easy_cars(gt)], return_counts=True)
    return int(ids[np.argmax(counts)])


@pytest.mark.parametrize("seq", SEQS)
def test_dropping_a_track_counts_its_easy_frames_as_misses(labels_only_root, tmp_path, seq):
    gt = read_labels(LABELS / f"{seq}.txt")
    tid = longest_easy_car(gt)
    n_easy = int((easy_cars(gt) & (gt.track_id == tid)).sum())
    assert 0 < n_easy < (gt.track_id == tid).sum()  # the easy filter matters for this track
    m = evaluate(labels_only_root, tmp_path, seq, gt.select(gt.track_id != tid))
    n_gt = easy_cars(gt).sum()
    for mode in ("2d", "bv", "3d"):
        mot = m.mot[mode]
        assert (mot.fn, mot.fp, mot.idsw) == (n_easy, 0, 0)
        assert mot.mota == pytest.approx(100.0 * (1 - n_easy / n_gt))
    dropped = next(o for o in m.objects if o.track_id == tid)
    assert dropped.tp_3d == 0.0 and np.isnan(dropped.ate) and dropped.est_track_id is None


def two_overlapping_tracks(gt: ObjectTable) -> tuple[int, int, int]:
    """Two easy car tracks with easy frames both before and after a common frame f0."""
    easy = easy_cars(gt)
    ids = np.unique(gt.track_id[easy])
    best = None
    for i, a in enumerate(ids):
        fa = gt.frame[easy & (gt.track_id == a)]
        for b in ids[i + 1:]:
            fb = gt.frame[easy & (gt.track_id == b)]
            common = np.intersect1d(fa, fb)
            if len(common) >= 2:
                f0 = int(common[len(common) // 2])
                best = (int(a), int(b), f0)
                return best
    raise AssertionError("no pair of co-visible tracks")


@pytest.mark.parametrize("seq", SEQS)
def test_swapping_two_ids_mid_track_counts_id_switches(labels_only_root, tmp_path, seq):
    gt = read_labels(LABELS / f"{seq}.txt")
    a, b, f0 = two_overlapping_tracks(gt)
    swapped = read_labels(LABELS / f"{seq}.txt")
    later = swapped.frame >= f0
    ta, tb = later & (swapped.track_id == a), later & (swapped.track_id == b)
    swapped.track_id[ta], swapped.track_id[tb] = b, a
    m = evaluate(labels_only_root, tmp_path, seq, swapped)
    n_gt = easy_cars(gt).sum()
    for mode in ("2d", "bv", "3d"):
        mot = m.mot[mode]
        assert (mot.idsw, mot.fp, mot.fn, mot.frag) == (2, 0, 0, 0)
        assert mot.mota == pytest.approx(100.0 * (1 - 2 / n_gt))
        assert mot.motp == pytest.approx(100.0)


def test_no_ground_truth_poses_warns_once_and_uses_camera_frame(labels_only_root, tmp_path):
    gt = read_labels(LABELS / "0001.txt")
    write_tracking_results(tmp_path / "tracking" / "0001.txt", gt)
    with pytest.warns(UserWarning) as record:
        m = evaluate_sequence(open_dataset(labels_only_root, "0001"), tmp_path)
    assert len([w for w in record if "T_w_c = I" in str(w.message)]) == 1
    assert m.world_frame == "camera frame" and m.camera is None


def test_results_without_image_boxes_are_projected(labels_only_root, tmp_path):
    """Rows with ``-1`` image boxes get their 3D box projected through P2 (the paper's 2D)."""
    gt = read_labels(LABELS / "0001.txt")
    no_2d = read_labels(LABELS / "0001.txt")
    no_2d.box_2d[:] = -1
    m = evaluate(labels_only_root, tmp_path, "0001", no_2d)
    assert m.mot["3d"].motp == pytest.approx(100.0) and m.mot["bv"].motp == pytest.approx(100.0)
    # projected 3D boxes are close to, not equal to, the annotated image boxes
    mot = m.mot["2d"]
    assert mot.tp_rate > 90.0 and 60.0 < mot.motp < 99.0

    from twistslam.eval.sequence import fill_missing_box_2d

    dataset = open_dataset(ROOT, "0001")
    filled = fill_missing_box_2d(no_2d, dataset)
    cars = gt.cls == "Car"
    expected = geometry.project_boxes(gt.box_3d[cars], dataset.calib.P2, 1242, 375)
    np.testing.assert_allclose(filled.box_2d[cars], expected)
    assert read_labels(LABELS / "0001.txt").box_2d is not filled.box_2d
