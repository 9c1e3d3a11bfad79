"""CLEAR MOT as the KITTI tracking devkit counts it: the ``kitti`` protocol.

3D multi-object tracking papers report the devkit's numbers as AB3DMOT's
``scripts/KITTI/evaluate.py`` computes them (3D IoU instead of image boxes, otherwise the
devkit's bookkeeping). Matching, false positives and false negatives are those of
:mod:`.matching` with ``gt_min_height=False``; what this module adds is the devkit's
counting where it departs from the CLEAR MOT definitions of :mod:`.clear_mot`:

- Ground truth under the minimum height is *not* ignored (the height rule applies only to
  unmatched tracker boxes): that is the matching's ``gt_min_height=False``.
- ID switch: at a frame where a ground-truth track is matched to a tracker id other than
  the one it was matched to *in the previous frame* (both frames matched, the previous one
  not ignored). A new id after a gap of misses is no switch.
- Fragmentation: at a frame where the track is matched, its matched id differs from the
  previous frame's (a miss, or another id), it was matched before (the last non-ignored
  match, forgotten after an ignored frame) and it is also matched in the *next* frame; on
  the track's last frame any change to a matched id counts, even a first match.
- MOTP: mean IoU over every match, matches to ignored ground truth included.
- MT / ML: the tracked ratio counts the first frame when it is matched even if ignored,
  and is divided by the number of non-ignored frames.

Ground-truth tracks whose every frame is ignored (the neighbour class, or always too
occluded) do not count at all.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from .clear_mot import MotMetrics, mot_from_counts
from .matching import Matching


def devkit_histories(m: Matching) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """Yield ``(gt_track_id, matched tracker ids, ignored)`` per ground-truth track, over
    *all* its frames in frame order (-1 where missed), the neighbour class included."""
    ids = m.matched_track_id
    order = np.lexsort((m.gt.frame, m.gt.track_id))
    if len(order) == 0:  # a sequence without a box of the class (e.g. 0017 has no car)
        return
    tracks = m.gt.track_id[order]
    starts = np.flatnonzero(np.r_[True, tracks[1:] != tracks[:-1]])
    for rows in np.split(order, starts[1:]):
        yield int(m.gt.track_id[rows[0]]), ids[rows], m.gt_ignored[rows]


def count_devkit_switches(history: np.ndarray, ignored: np.ndarray) -> tuple[int, int, int]:
    """ID switches, fragmentations and tracked frames of one ground-truth track, by the
    devkit's rules (module docstring).

    Parameters
    ----------
    history : (K,) matched tracker id per frame of the track, -1 where missed.
    ignored : (K,) bool, the frame's ground-truth box is ignored.

    Returns
    -------
    (idsw, frag, tracked) : ``tracked`` counts the first frame when matched (ignored or
        not) and every later non-ignored matched frame.
    """
    h = [int(x) for x in history]
    n = len(h)
    last = h[0]  # last matched id of a non-ignored frame; -1 after an ignored frame
    tracked = int(h[0] >= 0)
    idsw = frag = 0
    for f in range(1, n):
        if ignored[f]:
            last = -1
            continue
        changed = h[f - 1] != h[f]
        if last not in (-1, h[f]) and h[f] != -1 and h[f - 1] != -1:
            idsw += 1
        if f < n - 1 and changed and last != -1 and h[f] != -1 and h[f + 1] != -1:
            frag += 1
        if h[f] != -1:
            tracked += 1
            last = h[f]
    if n > 1 and h[-2] != h[-1] and last != -1 and h[-1] != -1 and not ignored[-1]:
        frag += 1
    return idsw, frag, tracked


def devkit_mot(m: Matching) -> MotMetrics:
    """CLEAR MOT, MT and ML of a :class:`Matching` by the devkit's rules (the ``kitti``
    protocol); ``m`` should come from a matching with ``gt_min_height=False``."""
    idsw = frag = n_mt = n_ml = n_tracks = 0
    for _, history, ignored in devkit_histories(m):
        if ignored.all():
            continue
        s, f, tracked = count_devkit_switches(history, ignored)
        idsw, frag, n_tracks = idsw + s, frag + f, n_tracks + 1
        ratio = tracked / np.count_nonzero(~ignored)
        n_mt += int(ratio > 0.8)
        n_ml += int(ratio < 0.2)
    matched = m.gt_match >= 0
    return mot_from_counts(
        fp=int(m.fp.sum()), fn=int(m.fn.sum()), tp=int(m.tp.sum()), idsw=idsw, frag=frag,
        n_gt=int((~m.gt_ignored).sum()), n_tracks=n_tracks, n_mt=n_mt, n_ml=n_ml,
        iou_sum=float(m.gt_iou[matched].sum()), n_motp=int(matched.sum()), protocol="kitti",
    )
