"""Sequence-level CLEAR MOT (Bernardin & Stiefelhagen 2008) and MT / ML (Li et al. 2009).

This is the ``clear`` protocol (:mod:`.protocol`), the default and the paper's object
tables' setting. Matching and ignore rules are the KITTI tracking devkit's (see
:mod:`.matching`). Where the devkit's bookkeeping departs from the CLEAR MOT definitions we
follow the definitions (and motmetrics, which the tests compare against); the ``kitti``
protocol (:mod:`.devkit`) follows the devkit instead:

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


NAN = float("nan")

#: keys of one ``mot`` entry of ``metrics.json``, in the report's column order
MOT_KEYS = (
    "mota", "motp", "idsw", "frag", "fp", "fn", "mt", "ml",
    "samota", "amota", "amotp", "hota", "deta", "assa",
)


@dataclass
class MotMetrics:
    """CLEAR MOT of one sequence (or several, pooled) in one overlap mode; rates in percent.

    Attributes
    ----------
    mota : ``100 (1 - (FN + FP + IDSW) / n_gt)``, ``n_gt`` the non-ignored ground truth.
    motp : mean IoU of the matches the protocol averages (``clear``: counted true
        positives; ``kitti``: every match, ignored ground truth included), in percent.
    idsw : ID switches, frag : fragmentations, as the protocol counts them.
    fp, fn, tp : false positives, false negatives (misses), counted true positives.
    mt, ml : mostly tracked (> 80 % of its frames matched) / mostly lost (< 20 %) ground-truth
        tracks, in percent of the tracks that are not entirely ignored.
    tp_rate : ``100 TP / n_gt`` (recall): the sequence's TP rate.
    n_gt : ground-truth boxes counted (not ignored); n_tracks : ground-truth tracks counted.
    n_mt, n_ml : the mostly tracked / mostly lost tracks (counts, for pooling).
    iou_sum, n_motp : sum and number of the IoUs MOTP averages (for pooling).
    samota, amota, amotp : AB3DMOT's recall-sampled averages over score thresholds
        (:mod:`.amota`), in percent; NaN when not computed.
    hota, deta, assa : HOTA and its detection / association accuracy (:mod:`.hota`), in
        percent; NaN when not computed.
    protocol : name of the protocol whose rules produced these numbers (:mod:`.protocol`).
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
    n_mt: int = 0
    n_ml: int = 0
    iou_sum: float = 0.0
    n_motp: int = 0
    samota: float = NAN
    amota: float = NAN
    amotp: float = NAN
    hota: float = NAN
    deta: float = NAN
    assa: float = NAN
    protocol: str = "clear"

    def to_dict(self) -> dict[str, float | str]:
        """One entry of the ``mot`` section of ``metrics.json``: the protocol, then
        :data:`MOT_KEYS`."""
        return {"protocol": self.protocol} | {k: getattr(self, k) for k in MOT_KEYS}


def mot_from_counts(
    *, fp: int, fn: int, tp: int, idsw: int, frag: int, n_gt: int, n_tracks: int,
    n_mt: int, n_ml: int, iou_sum: float, n_motp: int, protocol: str,
) -> MotMetrics:
    """:class:`MotMetrics` from its counts (NaN rates where a denominator is zero)."""
    return MotMetrics(
        mota=100.0 * (1.0 - (fn + fp + idsw) / n_gt) if n_gt else NAN,
        motp=100.0 * iou_sum / n_motp if n_motp else NAN,
        idsw=idsw, frag=frag, fp=fp, fn=fn,
        mt=100.0 * n_mt / n_tracks if n_tracks else NAN,
        ml=100.0 * n_ml / n_tracks if n_tracks else NAN,
        tp=tp, tp_rate=100.0 * tp / n_gt if n_gt else NAN, n_gt=n_gt, n_tracks=n_tracks,
        n_mt=n_mt, n_ml=n_ml, iou_sum=iou_sum, n_motp=n_motp, protocol=protocol,
    )


#: the counts of :class:`MotMetrics` that add up over sequences
SUMMED = ("fp", "fn", "tp", "idsw", "frag", "n_gt", "n_tracks", "n_mt", "n_ml", "iou_sum",
          "n_motp")


def pool_mot(parts: list[MotMetrics]) -> MotMetrics:
    """CLEAR MOT of several sequences together: counts summed, rates recomputed from the
    sums (as the devkit reports a set of sequences). Score-sweep metrics and HOTA do not
    pool from per-sequence values and are left NaN (see :mod:`.amota`, :mod:`.hota`)."""
    protocols = {p.protocol for p in parts}
    if len(protocols) > 1:
        raise ValueError(f"cannot pool metrics of different protocols: {sorted(protocols)}")
    totals = {k: sum(getattr(p, k) for p in parts) for k in SUMMED}
    return mot_from_counts(**totals, protocol=protocols.pop() if protocols else "clear")


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
    """CLEAR MOT, MT and ML of a :class:`Matching` by the definitions (the ``clear``
    protocol)."""
    tp = m.tp
    idsw = frag = n_mt = n_ml = n_tracks = 0
    for _, history in track_histories(m):
        s, f = count_switches(history)
        idsw, frag = idsw + s, frag + f
        ratio = float(np.mean(history >= 0))
        n_mt += int(ratio > 0.8)
        n_ml += int(ratio < 0.2)
        n_tracks += 1
    return mot_from_counts(
        fp=int(m.fp.sum()), fn=int(m.fn.sum()), tp=int(tp.sum()), idsw=idsw, frag=frag,
        n_gt=int((~m.gt_ignored).sum()), n_tracks=n_tracks, n_mt=n_mt, n_ml=n_ml,
        iou_sum=float(m.gt_iou[tp].sum()), n_motp=int(tp.sum()), protocol="clear",
    )
