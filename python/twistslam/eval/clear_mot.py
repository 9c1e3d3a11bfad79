"""Sequence-level CLEAR MOT (Bernardin & Stiefelhagen 2008) and MT / ML (Li et al. 2009).

Matching and ignore rules are the KITTI tracking devkit's (see :mod:`.matching`). Where the
devkit's bookkeeping departs from the CLEAR MOT definitions we follow the definitions (and
motmetrics, which the tests compare against):

- ID switch: whenever a ground-truth track's matched tracker id differs from the id it was
  *last* matched to, also across missed frames (the devkit only counts it when the previous
  frame was matched, and forgets the last id after an ignored frame).
- Fragmentation: each re-acquisition of a track after a miss (matched, lost, matched
  again); the devkit also counts direct id changes and looks one frame ahead.
- MOTP: mean IoU over *counted* true positives; the devkit's also averages the overlaps of
  tracker boxes matched to ignored ground truth.
- MT / ML: in percent of the tracks that are not entirely ignored, with the tracked ratio
  over the track's non-ignored frames only.
- MOTA / MOTP without any counted ground truth / true positive: NaN (devkit: -inf / inf).

Frames where a ground-truth box is ignored are left out of its history altogether.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from .matching import Matching


@dataclass
class MotMetrics:
    """CLEAR MOT of one sequence in one overlap mode; rates in percent (0-100).

    Attributes
    ----------
    mota : ``100 (1 - (FN + FP + IDSW) / n_gt)``, ``n_gt`` the non-ignored ground truth.
    motp : mean IoU over counted true positives, in percent (100 = every box exact).
    idsw : ID switches: a ground-truth track is matched to a tracker id that differs from
        the id it was last matched to (also across frames where it was missed).
    frag : fragmentations: a ground-truth track is matched, lost, and matched again.
    fp, fn, tp : false positives, false negatives (misses), counted true positives.
    mt, ml : mostly tracked (> 80 % of its frames matched) / mostly lost (< 20 %) ground-truth
        tracks, in percent of the tracks that are not entirely ignored.
    tp_rate : ``100 TP / n_gt`` (recall): the sequence's TP rate.
    n_gt : ground-truth boxes counted (not ignored); n_tracks : ground-truth tracks counted.
    """

    mota: float
    motp: float
    idsw: int
    frag: int
    fp: int
    fn: int
    mt: float
    ml: float
    tp: int
    tp_rate: float
    n_gt: int
    n_tracks: int

    def to_dict(self) -> dict[str, float]:
        """One entry of the ``mot`` section of ``metrics.json``."""
        keys = ("mota", "motp", "idsw", "frag", "fp", "fn", "mt", "ml")
        return {k: getattr(self, k) for k in keys}


def track_histories(m: Matching) -> Iterator[tuple[int, np.ndarray]]:
    """Yield ``(gt_track_id, matched tracker ids)`` per ground-truth track of the evaluated
    class, over its *non-ignored* frames in frame order (-1 where missed).

    Ignored frames are left out entirely: they neither count as a miss nor as the last
    matched id, so a switch across an ignored stretch is still a switch.
    """
    ids = m.matched_track_id
    keep = m.gt_target & ~m.gt_ignored
    rows = np.flatnonzero(keep)
    rows = rows[np.lexsort((m.gt.frame[rows], m.gt.track_id[rows]))]
    tracks = m.gt.track_id[rows]
    for tid in np.unique(tracks):
        yield int(tid), ids[rows[tracks == tid]]


def count_switches(history: np.ndarray) -> tuple[int, int]:
    """ID switches and fragmentations of one ground-truth track's matched-id history."""
    matched = history[history >= 0]
    idsw = int(np.count_nonzero(matched[1:] != matched[:-1]))
    hit = history >= 0
    # a re-acquisition: matched now, missed just before, matched at some earlier frame
    seen_before = np.cumsum(hit) - hit > 0
    frag = int(np.count_nonzero(hit[1:] & ~hit[:-1] & seen_before[1:]))
    return idsw, frag


def clear_mot(m: Matching) -> MotMetrics:
    """CLEAR MOT, MT and ML of a :class:`Matching`."""
    tp, fn, fp = m.tp, m.fn, m.fp
    n_gt = int((~m.gt_ignored).sum())
    idsw = frag = mt = ml = n_tracks = 0
    for _, history in track_histories(m):
        s, f = count_switches(history)
        idsw, frag = idsw + s, frag + f
        ratio = float(np.mean(history >= 0))
        mt += int(ratio > 0.8)
        ml += int(ratio < 0.2)
        n_tracks += 1
    n_fp, n_fn, n_tp = int(fp.sum()), int(fn.sum()), int(tp.sum())
    nan = float("nan")
    return MotMetrics(
        mota=100.0 * (1.0 - (n_fn + n_fp + idsw) / n_gt) if n_gt else nan,
        motp=100.0 * float(np.mean(m.gt_iou[tp])) if n_tp else nan,
        idsw=idsw, frag=frag, fp=n_fp, fn=n_fn,
        mt=100.0 * mt / n_tracks if n_tracks else nan,
        ml=100.0 * ml / n_tracks if n_tracks else nan,
        tp=n_tp, tp_rate=100.0 * n_tp / n_gt if n_gt else nan,
        n_gt=n_gt, n_tracks=n_tracks,
    )
