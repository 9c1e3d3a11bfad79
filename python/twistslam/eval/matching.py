"""Per-frame association of tracker boxes with ground truth, as the KITTI tracking devkit does.

In every frame, ground-truth boxes (the evaluated class *and* its neighbour class, whatever
their difficulty) are assigned to tracker boxes by the Hungarian method on ``1 - IoU``;
pairs whose IoU is below the threshold are forbidden. Then, as in the devkit:

- a ground-truth box of the neighbour class (Van for Car) or outside the difficulty level
  is *ignored*: matched, its tracker box is neither a true nor a false positive; unmatched,
  it is no miss. By default (``gt_min_height=True``, the ``clear`` protocol) the
  difficulty's minimum image height applies to ground truth too (the KITTI object
  benchmark's definition of easy / moderate / hard); the tracking devkit (the ``kitti``
  protocol) only filters tracker boxes by height;
- an unmatched tracker box is no false positive when it is of the neighbour class, at most
  the minimum height tall, or lies more than half inside a DontCare region (the share of
  its own area, not an IoU) -- always judged on image boxes, whatever the overlap mode;
- tracker rows of other classes, and rows without a track id (-1), are not evaluated.

The result is columnar (:class:`Matching`): for each ground-truth row its tracker row, IoU
and whether it is ignored; for each tracker row its ground-truth row and whether it is
ignored. CLEAR MOT and the per-track rates are then plain array arithmetic on it
(:mod:`.clear_mot`, :mod:`.devkit`, :mod:`.track_metrics`). The IoU matrices are computed
once per sequence (:class:`SequenceOverlaps`), so that the score sweeps of sAMOTA
(:mod:`.amota`) re-assign subsets of tracker rows without recomputing them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..datasets.objects import ObjectTable
from .difficulty import Difficulty, class_masks

IouFunction = Callable[[ObjectTable, ObjectTable], np.ndarray]

#: how overlap is measured: image boxes, rotated bird-view rectangles, 3D boxes
MODES = ("2d", "bv", "3d")


def _geometry():
    try:
        from .. import geometry
    except ImportError as exc:  # the C++ extension is not built
        raise ImportError(
            "twistslam.geometry (the C++ core) is needed for box IoUs; build the package "
            "with `pip install -e .`"
        ) from exc
    return geometry


def iou_function(mode: str) -> IouFunction:
    """IoU matrix ``(n_gt, n_est)`` of two tables for ``mode`` in :data:`MODES`."""
    if mode == "2d":
        return lambda a, b: _geometry().box_iou_2d(a.box_2d, b.box_2d)
    if mode == "bv":
        return lambda a, b: _geometry().box_iou_bev(a.box_3d, b.box_3d)
    if mode == "3d":
        return lambda a, b: _geometry().box_iou_3d(a.box_3d, b.box_3d)
    raise ValueError(f"unknown overlap mode {mode!r}; choose one of {MODES}")


def assign(iou: np.ndarray, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """Hungarian assignment maximising matches, then total IoU; pairs with IoU < threshold
    are never returned.

    Forbidden pairs get a cost larger than any sum of allowed costs (each <= 1), so the
    optimum first minimises the number of forbidden pairs, i.e. maximises the number of
    valid matches, exactly as the devkit's 1e9 gating does (but without float round-off).
    """
    n, m = iou.shape
    if n == 0 or m == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    allowed = iou >= threshold
    cost = np.where(allowed, 1.0 - iou, min(n, m) + 1.0)
    rows, cols = linear_sum_assignment(cost)
    keep = allowed[rows, cols]
    return rows[keep].astype(np.int64), cols[keep].astype(np.int64)


def overlap_ratio_2d(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, M) intersection area / area of ``a`` for image boxes ``x1 y1 x2 y2``.

    This is the devkit's test of a tracker box against a DontCare region: the share of the
    *tracker box* that lies inside the region, not an IoU.
    """
    w = np.minimum(a[:, None, 2], b[None, :, 2]) - np.maximum(a[:, None, 0], b[None, :, 0])
    h = np.minimum(a[:, None, 3], b[None, :, 3]) - np.maximum(a[:, None, 1], b[None, :, 1])
    inter = np.clip(w, 0, None) * np.clip(h, 0, None)
    area = (a[:, 2] - a[:, 0]) * (a[:, 3] - a[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(area[:, None] > 0, inter / area[:, None], 0.0)


@dataclass
class Matching:
    """Association of one sequence in one overlap mode.

    ``gt`` holds the evaluated and neighbour classes (no DontCare); ``est`` the tracker rows
    of those classes with a track id (those kept by a score threshold, when one is applied).
    Indices in ``gt_match`` / ``est_match`` are rows of the other table, -1 when unmatched.
    ``frame_iou`` keeps, per frame with boxes on both sides, the full IoU matrix of its
    ``gt`` rows against its ``est`` rows (what HOTA re-matches at every alpha).
    """

    mode: str
    threshold: float
    gt: ObjectTable
    gt_target: np.ndarray  # (N,) bool: row of the evaluated class (not the neighbour)
    gt_ignored: np.ndarray  # (N,) bool: neighbour class or outside the difficulty level
    gt_match: np.ndarray  # (N,) int64 row of est or -1
    gt_iou: np.ndarray  # (N,) IoU with the matched tracker box, NaN when unmatched
    est: ObjectTable
    est_match: np.ndarray  # (M,) int64 row of gt or -1
    est_ignored: np.ndarray  # (M,) bool: unmatched but neighbour class / too small / DontCare
    #: (gt rows, est rows, IoU matrix) per frame where both sides have boxes
    frame_iou: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=list)

    @property
    def tp(self) -> np.ndarray:
        """(N,) bool: counted true positives (matched, ground truth not ignored)."""
        return (self.gt_match >= 0) & ~self.gt_ignored

    @property
    def fn(self) -> np.ndarray:
        return (self.gt_match < 0) & ~self.gt_ignored

    @property
    def fp(self) -> np.ndarray:
        """(M,) bool: unmatched tracker rows that are not ignored."""
        return (self.est_match < 0) & ~self.est_ignored

    @property
    def matched_track_id(self) -> np.ndarray:
        """(N,) tracker track id matched to each ground-truth row, -1 when unmatched."""
        ids = np.full(len(self.gt), -1, dtype=np.int64)
        hit = self.gt_match >= 0
        ids[hit] = self.est.track_id[self.gt_match[hit]]
        return ids


def track_mean_scores(table: ObjectTable) -> np.ndarray:
    """(N,) mean score of each row's track over all rows of that track id (AB3DMOT's and the
    3D MOT papers' score of a *track*, what score thresholds compare against)."""
    if not len(table):
        return np.zeros(0)
    ids, inverse = np.unique(table.track_id, return_inverse=True)
    sums = np.bincount(inverse, weights=table.score, minlength=len(ids))
    return (sums / np.bincount(inverse, minlength=len(ids)))[inverse]


@dataclass
class SequenceOverlaps:
    """Everything of a sequence's association that does not depend on which tracker rows
    are kept: the evaluated rows, their ignore flags and the per-frame IoU matrices.

    Built once by :func:`sequence_overlaps`; :meth:`match` then assigns frame by frame for
    any subset of tracker rows (a score threshold) without recomputing a single IoU.
    """

    mode: str
    threshold: float
    gt: ObjectTable
    gt_target: np.ndarray
    gt_ignored: np.ndarray
    est: ObjectTable
    est_ignorable: np.ndarray  # (M,) bool: not a false positive when left unmatched
    est_track_score: np.ndarray  # (M,) mean score of the row's track
    frame_iou: list[tuple[np.ndarray, np.ndarray, np.ndarray]]
    _full: Matching | None = field(default=None, repr=False)

    def match(self, keep: np.ndarray | None = None) -> Matching:
        """Per-frame Hungarian assignment of the tracker rows ``keep`` selects (bool mask
        over :attr:`est`; all of them when None)."""
        if keep is None:
            if self._full is None:
                self._full = self._assign(np.ones(len(self.est), dtype=bool))
            return self._full
        return self._assign(np.asarray(keep, dtype=bool))

    def _assign(self, keep: np.ndarray) -> Matching:
        kept = np.flatnonzero(keep)
        new_row = np.full(len(self.est), -1, dtype=np.int64)
        new_row[kept] = np.arange(len(kept))
        gt_match = np.full(len(self.gt), -1, dtype=np.int64)
        gt_iou = np.full(len(self.gt), np.nan)
        est_match = np.full(len(kept), -1, dtype=np.int64)
        frame_iou = []
        for gi, ei, iou in self.frame_iou:
            k = keep[ei]
            if not k.any():
                continue
            ei, iou = new_row[ei[k]], iou[:, k]
            frame_iou.append((gi, ei, iou))
            rows, cols = assign(iou, self.threshold)
            gt_match[gi[rows]] = ei[cols]
            gt_iou[gi[rows]] = iou[rows, cols]
            est_match[ei[cols]] = gi[rows]
        return Matching(
            mode=self.mode, threshold=self.threshold, gt=self.gt, gt_target=self.gt_target,
            gt_ignored=self.gt_ignored, gt_match=gt_match, gt_iou=gt_iou,
            est=self.est.select(kept), est_match=est_match,
            est_ignored=(est_match < 0) & self.est_ignorable[kept], frame_iou=frame_iou,
        )


def sequence_overlaps(
    gt: ObjectTable,
    est: ObjectTable,
    iou_fn: IouFunction,
    *,
    cls: str = "car",
    difficulty: Difficulty,
    threshold: float = 0.25,
    mode: str = "",
    gt_min_height: bool = True,
) -> SequenceOverlaps:
    """The rows, ignore flags and IoU matrices of one sequence (see the module docstring).

    Parameters
    ----------
    gt : ground-truth labels of the sequence, all classes and DontCare regions.
    est : tracker output, all classes; rows with ``track_id < 0`` are dropped as the devkit
        does (an untracked detection cannot be a track).
    iou_fn : IoU matrix of two tables, e.g. :func:`iou_function` ``("3d")``.
    gt_min_height : whether ground truth lower than the difficulty's minimum height is
        ignored (the object benchmark's definition); the tracking devkit does not.
    """
    target, neighbour, dont_care = class_masks(gt, cls)
    g = gt.select(target | neighbour)
    dc = gt.select(dont_care)
    e_target, e_neighbour, _ = class_masks(est, cls)
    e = est.select((e_target | e_neighbour) & (est.track_id >= 0))
    e_neighbour = class_masks(e, cls)[1]

    g_target, g_neighbour, _ = class_masks(g, cls)
    gt_ignored = g_neighbour | ~difficulty.accepts(g, check_height=gt_min_height)
    frame_iou = []
    for frame in np.intersect1d(g.frames, e.frames):
        gi = np.flatnonzero(g.frame == frame)
        ei = np.flatnonzero(e.frame == frame)
        iou = np.asarray(iou_fn(g.select(gi), e.select(ei)), dtype=np.float64)
        frame_iou.append((gi, ei, iou))

    # unmatched tracker boxes the devkit does not count as false positives
    height = e.box_2d[:, 3] - e.box_2d[:, 1]
    in_dont_care = np.zeros(len(e), dtype=bool)
    for frame in np.intersect1d(dc.frames, e.frames):
        ei = np.flatnonzero(e.frame == frame)
        ratio = overlap_ratio_2d(e.box_2d[ei], dc.box_2d[dc.frame == frame])
        in_dont_care[ei] = (ratio > 0.5).any(axis=1)
    too_small = height <= difficulty.min_height

    return SequenceOverlaps(
        mode=mode, threshold=threshold, gt=g, gt_target=g_target, gt_ignored=gt_ignored,
        est=e, est_ignorable=e_neighbour | too_small | in_dont_care,
        est_track_score=track_mean_scores(e), frame_iou=frame_iou,
    )


def match_sequence(
    gt: ObjectTable,
    est: ObjectTable,
    iou_fn: IouFunction,
    *,
    cls: str = "car",
    difficulty: Difficulty,
    threshold: float = 0.25,
    mode: str = "",
    gt_min_height: bool = True,
) -> Matching:
    """Associate ``est`` with ``gt`` frame by frame: :func:`sequence_overlaps` (same
    parameters) followed by :meth:`SequenceOverlaps.match` of every tracker row."""
    return sequence_overlaps(
        gt, est, iou_fn, cls=cls, difficulty=difficulty, threshold=threshold, mode=mode,
        gt_min_height=gt_min_height,
    ).match()
