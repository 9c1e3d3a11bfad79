"""sAMOTA, AMOTA and AMOTP: CLEAR MOT averaged over score thresholds sampled along recall.

The definitions of AB3DMOT (Weng et al., "3D Multi-Object Tracking: A Baseline and New
Evaluation Metrics", IROS 2020), as its ``scripts/KITTI/evaluate.py`` computes them, which
3D MOT papers report:

1. Score of a track: the mean score of its boxes. Evaluate with every track; the scores
   of the tracks behind the matches (:meth:`.Protocol.matched_for_precision`) are the
   candidate thresholds, ``n = matches + FN`` the recall denominator.
2. Sort those scores in decreasing order; the k-th score reaches recall ``(k + 1) / n``.
   Walk the targets ``r = 0, 1/40, 2/40, ...``: each target takes the first score (after
   the one the previous target took) whose recall is at least as close to ``r`` as the
   next score's; the last score always closes the walk. The ``r = 0`` point is dropped.
3. At each (threshold ``t``, target recall ``r``): keep the tracks with mean score
   ``>= t``, match again and count ``FN, FP, IDSW`` and ``n_gt`` under the protocol;
   ``sMOTA_r = clip(1 - (FN + FP + IDSW - (1 - r) n_gt) / (r n_gt), 0, 1)``.
4. ``sAMOTA = sum(sMOTA_r) / 40``, ``AMOTA = sum(MOTA_r) / 40``, ``AMOTP = sum(MOTP_r) / 40``
   (a MOTP without matches counts 0). Recalls the tracker never reaches contribute 0.

With several sequences the thresholds come from all of them and the counts are summed
before each ratio, as AB3DMOT evaluates a split. Numbers are reported in percent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .clear_mot import pool_mot
from .matching import SequenceOverlaps
from .protocol import Protocol, get_protocol

#: recall points of the average (AB3DMOT's 41 sample points, the zero-recall one dropped)
N_RECALL_POINTS = 40


@dataclass
class ScoreSweep:
    """The recall-sampled averages and the curve behind them.

    Attributes
    ----------
    samota, amota, amotp : in percent (NaN without any counted ground truth).
    thresholds : (K,) score thresholds, decreasing; recalls : (K,) their target recalls.
    smota, mota, motp : (K,) the values at each point, in percent.
    protocol : name of the protocol that counted each point.
    """

    samota: float
    amota: float
    amotp: float
    thresholds: np.ndarray
    recalls: np.ndarray
    smota: np.ndarray
    mota: np.ndarray
    motp: np.ndarray
    protocol: str


def recall_thresholds(
    scores: np.ndarray, n_gt: int, n_points: int = N_RECALL_POINTS
) -> tuple[np.ndarray, np.ndarray]:
    """Score thresholds and the target recalls they stand for (step 2 of the module
    docstring).

    Parameters
    ----------
    scores : scores of the matched tracks, one per match, any order.
    n_gt : recall denominator (matches plus misses).
    n_points : recall points between 0 and 1.

    Returns
    -------
    (thresholds, recalls) : decreasing thresholds and their target recalls ``k / n_points``
        (accumulated in steps of ``1 / n_points``), the zero-recall point dropped.
    """
    ordered = np.sort(np.asarray(scores, dtype=np.float64))[::-1]
    last = len(ordered) - 1
    step = 1.0 / n_points
    target, picked, targets = 0.0, [], []
    for i, score in enumerate(ordered):
        reached = (i + 1) / n_gt
        if i < last and (i + 2) / n_gt - target < target - reached:
            continue  # the next score lands nearer to the target recall
        picked.append(score)
        targets.append(target)
        target += step
    return np.asarray(picked[1:]), np.asarray(targets[1:])


def score_sweep(
    overlaps: SequenceOverlaps | list[SequenceOverlaps], protocol: str | Protocol = "kitti",
    n_points: int = N_RECALL_POINTS,
) -> ScoreSweep:
    """sAMOTA, AMOTA and AMOTP of one or several sequences (pooled, see module docstring).

    Parameters
    ----------
    overlaps : the sequences' :class:`~.matching.SequenceOverlaps` (one mode), built with
        the protocol's ``gt_min_height``.
    protocol : ``"kitti"`` (AB3DMOT's numbers) or ``"clear"``.
    """
    protocol = get_protocol(protocol)
    seqs = [overlaps] if isinstance(overlaps, SequenceOverlaps) else list(overlaps)
    full = [o.match() for o in seqs]
    scores = np.concatenate([np.zeros(0)] + [
        o.est_track_score[m.gt_match[protocol.matched_for_precision(m)]]
        for o, m in zip(seqs, full)
    ])
    counts = pool_mot([protocol.count(m) for m in full])
    n_recall = counts.n_motp + counts.fn
    nan = float("nan")
    if counts.n_gt == 0 or n_recall == 0:
        empty = np.zeros(0)
        return ScoreSweep(nan, nan, nan, empty, empty, empty, empty, empty, protocol.name)

    thresholds, recalls = recall_thresholds(scores, n_recall, n_points)
    smota, mota, motp = (np.zeros(len(thresholds)) for _ in range(3))
    for k, (threshold, recall) in enumerate(zip(thresholds, recalls)):
        c = pool_mot([
            protocol.count(o.match(o.est_track_score >= threshold)) for o in seqs
        ])
        errors = c.fn + c.fp + c.idsw
        mota[k] = 1.0 - errors / c.n_gt
        smota[k] = min(1.0, max(0.0, 1.0 - (errors - (1.0 - recall) * c.n_gt) / (recall * c.n_gt)))
        motp[k] = c.iou_sum / c.n_motp if c.n_motp else 0.0
    return ScoreSweep(
        samota=100.0 * smota.sum() / n_points, amota=100.0 * mota.sum() / n_points,
        amotp=100.0 * motp.sum() / n_points, thresholds=thresholds, recalls=recalls,
        smota=100.0 * smota, mota=100.0 * mota, motp=100.0 * motp, protocol=protocol.name,
    )
