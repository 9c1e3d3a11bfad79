"""HOTA, DetA, AssA: hand-worked cases, TrackEval (PyPI ``trackeval``, Luiten's
implementation) on random and real inputs, and which boxes take part."""

from __future__ import annotations

import contextlib
import importlib
import io

import numpy as np
import pytest
from test_eval_devkit import SEQS

from twistslam.datasets import ObjectTable
from twistslam.eval.difficulty import DIFFICULTIES, get_difficulty
from twistslam.eval.hota import ALPHAS, HotaFrames, hota, hota_frames, pool_hota
from twistslam.eval.matching import iou_function, match_sequence, sequence_overlaps
from twistslam.eval.results import load_results
from twistslam.eval.sequence import fill_missing_box_2d, open_dataset


@pytest.fixture(scope="module")
def trackeval_hota():
    """TrackEval's HOTA metric (its package prints a notice about optional datasets)."""
    with contextlib.redirect_stdout(io.StringIO()):
        metrics = importlib.import_module("trackeval.metrics")
    return metrics.HOTA()


def trackeval_input(f: HotaFrames) -> dict:
    return {
        "num_gt_dets": sum(len(g) for g in f.gt_tracks),
        "num_tracker_dets": sum(len(e) for e in f.est_tracks),
        "num_gt_ids": f.n_gt_tracks, "num_tracker_ids": f.n_est_tracks,
        "gt_ids": f.gt_tracks, "tracker_ids": f.est_tracks,
        "similarity_scores": f.similarity, "num_timesteps": len(f.gt_tracks),
    }


def assert_equal_to_trackeval(ours, ref: dict) -> None:
    for field, value in (("HOTA_TP", ours.tp), ("HOTA_FN", ours.fn), ("HOTA_FP", ours.fp),
                         ("AssA", ours.assa_alpha), ("LocA", ours.loca_alpha),
                         ("DetA", ours.deta_alpha), ("HOTA", ours.hota_alpha)):
        np.testing.assert_allclose(value, ref[field], rtol=0, atol=1e-12, err_msg=field)
    assert ours.hota == pytest.approx(100 * ref["HOTA"].mean(), abs=1e-10)


def frames(gt: list[list[int]], est: list[list[int]], sim: list[list[list[float]]]):
    arrays = [np.array(x, dtype=np.int64) for x in gt], [np.array(x, dtype=np.int64) for x in est]
    sims = [np.array(s, dtype=float).reshape(len(g), len(e)) for s, g, e in zip(sim, gt, est)]
    return HotaFrames(*arrays, sims, max(map(max, filter(None, gt))) + 1,
                      max(map(max, filter(None, est))) + 1)


def test_hota_hand_worked():
    # One ground-truth track over two frames, found by tracker track 0 in frame 0 and by
    # track 1 in frame 1, both exactly (S = 1). Every alpha: TP 2, FN = FP = 0, DetA = 1.
    # Each pair's tracks share TPA = 1 of n_g = 2 and n_e = 1 boxes: 1 / (2 + 1 - 1) = 1/2,
    # so AssA = (1/2 + 1/2) / 2 = 1/2 and HOTA = sqrt(1/2).
    h = hota(frames([[0], [0]], [[0], [1]], [[[1.0]], [[1.0]]]))
    assert (h.deta, h.assa, h.hota) == pytest.approx((100.0, 50.0, 100 * np.sqrt(0.5)))
    # One box, one tracker box, IoU 0.5: a true positive for the 10 alphas 0.05 .. 0.50
    # (DetA = AssA = 1), a miss plus a false positive for the 9 alphas 0.55 .. 0.95 (0).
    h = hota(frames([[0]], [[0]], [[[0.5]]]))
    assert len(ALPHAS) == 19
    assert (h.deta, h.assa, h.hota) == pytest.approx((1000 / 19,) * 3)
    # Nothing tracked: only misses
    h = hota(HotaFrames([np.array([0])], [np.zeros(0, dtype=np.int64)], [np.zeros((1, 0))], 1, 0))
    assert (h.hota, h.fn.tolist()) == (0.0, [1.0] * 19)


def random_frames(seed: int, n_frames: int = 60) -> HotaFrames:
    """Random tracks with switches, misses, false positives and noisy similarities."""
    rng = np.random.default_rng(seed)
    n_gt, n_est = 6, 12
    gt, est, sim = [], [], []
    owner = rng.integers(0, n_est, n_gt)  # tracker track following each ground-truth track
    for _ in range(n_frames):
        if rng.random() < 0.1:
            owner[rng.integers(n_gt)] = rng.integers(n_est)
        g = np.flatnonzero(rng.random(n_gt) < 0.7)
        e = np.unique(np.r_[owner[g][rng.random(len(g)) < 0.85],
                            rng.integers(0, n_est, rng.integers(0, 3))])
        shape = (len(g), len(e))
        s = np.where(rng.random(shape) < 0.15, rng.uniform(0, 0.6, shape), 0.0)
        for i, track in enumerate(g):
            s[i, e == owner[track]] = rng.uniform(0.3, 1.0)
        gt.append(g)
        est.append(e)
        sim.append(s)
    return HotaFrames(gt, est, sim, n_gt, n_est)


def test_hota_equals_trackeval_on_random_sequences(trackeval_hota):
    ours, refs = [], {}
    for seed in range(6):
        f = random_frames(seed)
        ours.append(hota(f))
        refs[seed] = trackeval_hota.eval_sequence(trackeval_input(f))
        assert_equal_to_trackeval(ours[-1], refs[seed])
        assert 5 < ours[-1].assa < 95  # association is neither perfect nor absent
    assert_equal_to_trackeval(pool_hota(ours), trackeval_hota.combine_sequences(refs))


CAR, VAN = (100, 100, 200, 180), (300, 100, 400, 180)
FAR, SMALL = (600, 100, 700, 180), (800, 100, 900, 115)  # SMALL: 15 px high


def _table(rows) -> ObjectTable:
    """rows: ``(frame, track_id, cls, x1, y1, x2, y2)``, image boxes only."""
    n = len(rows)
    return ObjectTable(
        frame=[r[0] for r in rows], track_id=[r[1] for r in rows], cls=[r[2] for r in rows],
        truncation=np.zeros(n), occlusion=np.zeros(n), alpha=np.zeros(n),
        box_2d=[r[3:7] for r in rows], box_3d=np.zeros((n, 7)), score=np.ones(n),
    )


def test_hota_boxes_are_the_counted_ones():
    gt = _table([(0, 1, "Car", *CAR), (0, 2, "Van", *VAN), (1, 1, "Car", *CAR)])
    est = _table([(0, 7, "Car", *CAR), (0, 8, "Car", *VAN), (0, 9, "Car", *SMALL),
                  (0, 5, "Car", *FAR), (1, 6, "Car", *CAR)])
    m = match_sequence(gt, est, iou_function("2d"), cls="car", difficulty=DIFFICULTIES["hard"],
                       threshold=0.5, mode="2d")
    f = hota_frames(m)
    # the Van (ignored) and the box matched to it leave, as does the unmatched 15 px box;
    # the far false positive stays. Tracks are renumbered 0..n-1 in id order (5, 6, 7 ->
    # 0, 1, 2), boxes keep the file order (7 then 5 in frame 0)
    assert (f.n_gt_tracks, f.n_est_tracks) == (1, 3)
    assert [g.tolist() for g in f.gt_tracks] == [[0], [0]]
    assert [e.tolist() for e in f.est_tracks] == [[2, 0], [1]]
    np.testing.assert_allclose(f.similarity[0], [[1.0, 0.0]])
    h = hota(f)  # 2 TP, 1 FP at every alpha; each TP pair shares 1 of 2 and 1 boxes
    assert (h.deta, h.assa) == pytest.approx((100 * 2 / 3, 50.0))


def test_ab3dmot_raw_hota_equals_trackeval(kitti_tracking, ab3dmot_outputs, trackeval_hota,
                                           capsys):
    ours, refs = [], {}
    with capsys.disabled():
        print("\nAB3DMOT raw, kitti protocol, 3D IoU 0.25, car: HOTA DetA AssA (ours)")
    for seq in SEQS:
        dataset = open_dataset(kitti_tracking, seq)
        est = fill_missing_box_2d(load_results(ab3dmot_outputs / "raw", seq).tracking, dataset)
        o = sequence_overlaps(dataset.gt_objects, est, iou_function("3d"), cls="car",
                              difficulty=get_difficulty("hard"), threshold=0.25, mode="3d",
                              gt_min_height=False)
        f = hota_frames(o.match())
        ours.append(hota(f))
        refs[seq] = trackeval_hota.eval_sequence(trackeval_input(f))
        assert_equal_to_trackeval(ours[-1], refs[seq])
        with capsys.disabled():
            print(f"  {seq}: {ours[-1].hota:.2f} {ours[-1].deta:.2f} {ours[-1].assa:.2f}")
    pooled = pool_hota(ours)
    assert_equal_to_trackeval(pooled, trackeval_hota.combine_sequences(refs))
    with capsys.disabled():
        print(f"  all: {pooled.hota:.2f} {pooled.deta:.2f} {pooled.assa:.2f}")
