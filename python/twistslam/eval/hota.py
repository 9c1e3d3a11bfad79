"""HOTA, DetA and AssA (Luiten et al., "HOTA: A Higher Order Metric for Evaluating
Multi-Object Tracking", IJCV 2021), as TrackEval computes them for the KITTI leaderboard.

For each localisation threshold ``alpha`` in 0.05, 0.10, ..., 0.95:

- Matching, per frame: Hungarian assignment maximising ``A(g, e) * S(g, e)``, ``S`` the
  similarity (IoU) of two boxes and ``A`` the global alignment of their two *tracks* over
  the sequence: ``A = P / (n_g + n_e - P)``, ``n_g`` / ``n_e`` the numbers of boxes of each
  track and ``P`` the sum over frames of ``S / (row sum + column sum - S)`` of ``S``'s
  frame matrix (a soft count of frames where the two are paired). A pair is a true
  positive at ``alpha`` when ``S >= alpha``; other boxes are FN / FP.
- ``DetA = TP / (TP + FN + FP)``.
- ``AssA = (1 / TP) sum over TP pairs of TPA / (TPA + FNA + FPA)``: ``TPA`` the number of
  true positives linking the pair's two tracks, ``FNA = n_g - TPA``, ``FPA = n_e - TPA``.
- ``HOTA_alpha = sqrt(DetA * AssA)``.

Reported HOTA, DetA and AssA are the means over the 19 alphas. Sequences pool by summing
TP / FN / FP per alpha and weighting AssA by TP, as TrackEval combines sequences.

Which boxes take part is decided by the evaluator's protocol (:func:`hota_frames`): the
counted (not ignored) ground truth of the evaluated class, and the tracker boxes that are
neither ignored nor matched (in CLEAR MOT's matching) to ignored ground truth, as
TrackEval's KITTI preprocessing removes them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from .matching import Matching

#: TrackEval's localisation thresholds
ALPHAS = np.arange(0.05, 0.99, 0.05)
_EPS = np.finfo(float).eps


@dataclass
class HotaFrames:
    """HOTA's input for one sequence: per frame the track indices of its ground-truth and
    tracker boxes (``0..n_gt_tracks-1`` and ``0..n_est_tracks-1``) and their similarity
    matrix ``(len(gt_tracks[t]), len(est_tracks[t]))``."""

    gt_tracks: list[np.ndarray]
    est_tracks: list[np.ndarray]
    similarity: list[np.ndarray]
    n_gt_tracks: int
    n_est_tracks: int


@dataclass
class HotaResult:
    """Per-alpha counts and scores (arrays over :data:`ALPHAS`) of one or several sequences.

    ``hota``, ``deta``, ``assa`` and ``loca`` are the means over alpha, in percent.
    """

    tp: np.ndarray
    fn: np.ndarray
    fp: np.ndarray
    assa_alpha: np.ndarray  # in [0, 1]
    loca_alpha: np.ndarray  # mean similarity of the true positives, in [0, 1]

    @property
    def deta_alpha(self) -> np.ndarray:
        return self.tp / np.maximum(1.0, self.tp + self.fn + self.fp)

    @property
    def hota_alpha(self) -> np.ndarray:
        return np.sqrt(self.deta_alpha * self.assa_alpha)

    @property
    def hota(self) -> float:
        return 100.0 * float(np.mean(self.hota_alpha))

    @property
    def deta(self) -> float:
        return 100.0 * float(np.mean(self.deta_alpha))

    @property
    def assa(self) -> float:
        return 100.0 * float(np.mean(self.assa_alpha))

    @property
    def loca(self) -> float:
        return 100.0 * float(np.mean(self.loca_alpha))


def _dense_ids(ids: np.ndarray) -> tuple[np.ndarray, int]:
    uniq, dense = np.unique(ids, return_inverse=True)
    return dense.astype(np.int64), len(uniq)


def hota_frames(m: Matching) -> HotaFrames:
    """The boxes of a :class:`Matching` that HOTA evaluates (module docstring), with the
    matching's IoUs as similarities."""
    gt_keep = m.gt_target & ~m.gt_ignored
    to_ignored = np.zeros(len(m.est), dtype=bool)
    matched = m.est_match >= 0
    to_ignored[matched] = m.gt_ignored[m.est_match[matched]]
    est_keep = ~m.est_ignored & ~to_ignored
    gt_track, n_gt_tracks = _dense_ids(m.gt.track_id[gt_keep])
    est_track, n_est_tracks = _dense_ids(m.est.track_id[est_keep])
    gt_index = np.full(len(m.gt), -1)
    gt_index[gt_keep] = gt_track
    est_index = np.full(len(m.est), -1)
    est_index[est_keep] = est_track

    iou_of_frame = {int(m.gt.frame[gi[0]]): (gi, ei, iou) for gi, ei, iou in m.frame_iou}
    frames = np.union1d(m.gt.frame[gt_keep], m.est.frame[est_keep])
    out = HotaFrames([], [], [], n_gt_tracks, n_est_tracks)
    for frame in frames:
        if frame in iou_of_frame:
            gi, ei, iou = iou_of_frame[frame]
            g, e = gt_keep[gi], est_keep[ei]
            gi, ei, sim = gi[g], ei[e], iou[np.ix_(g, e)]
        else:  # boxes on one side only
            gi = np.flatnonzero(gt_keep & (m.gt.frame == frame))
            ei = np.flatnonzero(est_keep & (m.est.frame == frame))
            sim = np.zeros((len(gi), len(ei)))
        out.gt_tracks.append(gt_index[gi])
        out.est_tracks.append(est_index[ei])
        out.similarity.append(sim)
    return out


def _global_alignment(f: HotaFrames) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, boxes per gt track, boxes per tracker track)."""
    soft = np.zeros((f.n_gt_tracks, f.n_est_tracks))
    n_g, n_e = np.zeros(f.n_gt_tracks), np.zeros(f.n_est_tracks)
    for g, e, s in zip(f.gt_tracks, f.est_tracks, f.similarity):
        union = s.sum(axis=0)[None, :] + s.sum(axis=1)[:, None] - s
        share = np.divide(s, union, out=np.zeros_like(s), where=union > _EPS)
        soft[np.ix_(g, e)] += share  # a track has at most one box per frame
        n_g[g] += 1
        n_e[e] += 1
    alignment = soft / (n_g[:, None] + n_e[None, :] - soft)
    return alignment, n_g, n_e


def hota(frames: HotaFrames) -> HotaResult:
    """HOTA of one sequence (see the module docstring)."""
    n_alpha = len(ALPHAS)
    n_gt_boxes = sum(len(g) for g in frames.gt_tracks)
    n_est_boxes = sum(len(e) for e in frames.est_tracks)
    zeros = np.zeros(n_alpha)
    if n_gt_boxes == 0 or n_est_boxes == 0:  # nothing to match: perfect localisation
        return HotaResult(zeros.copy(), np.full(n_alpha, float(n_gt_boxes)),
                          np.full(n_alpha, float(n_est_boxes)), zeros.copy(), np.ones(n_alpha))

    alignment, n_g, n_e = _global_alignment(frames)
    tp, fn, fp, loc = zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy()
    pairs = np.zeros((n_alpha, frames.n_gt_tracks, frames.n_est_tracks))
    for g, e, s in zip(frames.gt_tracks, frames.est_tracks, frames.similarity):
        if len(g) == 0 or len(e) == 0:
            fn += len(g)
            fp += len(e)
            continue
        rows, cols = linear_sum_assignment(-(alignment[np.ix_(g, e)] * s))
        sim = s[rows, cols]
        ok = sim[None, :] >= ALPHAS[:, None] - _EPS  # (n_alpha, n_pairs)
        hits = ok.sum(axis=1)
        tp += hits
        fn += len(g) - hits
        fp += len(e) - hits
        loc += (ok * sim[None, :]).sum(axis=1)
        a, k = np.nonzero(ok)
        np.add.at(pairs, (a, g[rows[k]], e[cols[k]]), 1.0)

    union = n_g[None, :, None] + n_e[None, None, :] - pairs
    assa = (pairs * pairs / np.maximum(1.0, union)).sum(axis=(1, 2)) / np.maximum(1.0, tp)
    return HotaResult(tp, fn, fp, assa, np.maximum(1e-10, loc) / np.maximum(1e-10, tp))


def pool_hota(results: list[HotaResult]) -> HotaResult:
    """HOTA of several sequences together: counts summed, AssA and LocA weighted by TP."""
    tp = sum(r.tp for r in results)
    weight = np.maximum(1e-10, tp)
    return HotaResult(
        tp=tp, fn=sum(r.fn for r in results), fp=sum(r.fp for r in results),
        assa_alpha=sum(r.assa_alpha * r.tp for r in results) / np.maximum(1.0, tp),
        loca_alpha=np.maximum(1e-10, sum(r.loca_alpha * r.tp for r in results)) / weight,
    )
