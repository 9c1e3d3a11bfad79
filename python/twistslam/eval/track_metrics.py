"""Per ground-truth track detection quality (TP rate, MOTP) and track pairing."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .matching import Matching


@dataclass
class TrackDetection:
    """How well one ground-truth track is covered in one overlap mode.

    Attributes
    ----------
    n_frames : frames where the track is inside the difficulty level (not ignored).
    n_tp : those frames where it is matched (IoU >= threshold).
    tp_rate : ``100 n_tp / n_frames`` (NaN when the track is never evaluated).
    motp : mean IoU over its true positives, in percent (NaN without any).
    """

    n_frames: int
    n_tp: int
    tp_rate: float
    motp: float


def track_detection(m: Matching) -> dict[int, TrackDetection]:
    """:class:`TrackDetection` for every ground-truth track of the evaluated class that is
    not ignored in at least one frame, keyed by its track id."""
    out: dict[int, TrackDetection] = {}
    counted = m.gt_target & ~m.gt_ignored
    tp = m.tp
    for tid in np.unique(m.gt.track_id[counted]):
        rows = counted & (m.gt.track_id == tid)
        n, hits = int(rows.sum()), rows & tp
        n_tp = int(hits.sum())
        out[int(tid)] = TrackDetection(
            n_frames=n, n_tp=n_tp, tp_rate=100.0 * n_tp / n,
            motp=100.0 * float(np.mean(m.gt_iou[hits])) if n_tp else float("nan"),
        )
    return out


def pair_tracks(m: Matching) -> dict[int, int]:
    """Ground-truth track id -> the tracker track id matched to it most often.

    Every matched frame counts, ignored ones included: pairing decides whose *poses* are
    compared, and pose accuracy does not depend on the difficulty level. Ties go to the
    tracker id matched first. Tracks never matched are absent.
    """
    ids = m.matched_track_id
    pairs: dict[int, int] = {}
    for tid in np.unique(m.gt.track_id[m.gt_target]):
        rows = np.flatnonzero(m.gt_target & (m.gt.track_id == tid) & (ids >= 0))
        if not len(rows):
            continue
        rows = rows[np.argsort(m.gt.frame[rows], kind="stable")]
        cand, first, counts = np.unique(ids[rows], return_index=True, return_counts=True)
        best = np.lexsort((first, -counts))[0]
        pairs[int(tid)] = int(cand[best])
    return pairs
