"""The KITTI object benchmark's rules for one frame: which boxes count and how they match.

The rules are those of ``evaluate_object`` in the KITTI object devkit (its ``cleanData``,
``computeStatistics`` and ``getThresholds``), reimplemented here:

* Ground truth of the evaluated class inside the difficulty level is *evaluated* (a miss is a
  false negative). Outside the level (too small, too occluded, too truncated), or of the
  neighbouring class (``Van`` for ``Car``, ``Person_sitting`` for ``Pedestrian``), it is
  *ignored*: a detection matched to it is neither a true nor a false positive. Every other
  class plays no part.
* A detection whose image box is lower than the level's minimum height (in whole pixels, as
  the devkit truncates it to an integer) is *ignored* whatever its class -- a devkit quirk
  kept on purpose, so that our numbers are the devkit's. Other detections of the evaluated
  class are evaluated; detections of other classes play no part.
* For the score thresholds, each ground-truth box takes the highest-scored free detection
  with IoU above the threshold; for the precision / recall counts it takes the free evaluated
  detection of largest IoU (an ignored one only when no evaluated one overlaps).
* In the image (``2d``) metric a detection left unmatched that covers a ``DontCare`` region
  (intersection over the detection's area above the IoU threshold) is not a false positive.
  The devkit runs the same test on the bird-view / 3D boxes of the regions, which KITTI
  writes as placeholders far behind the camera, so there it never fires; we skip it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..datasets.objects import DONT_CARE, ObjectTable
from .difficulty import Difficulty, class_masks

#: state of a box in the evaluation of one class at one difficulty (the devkit's -1 / 0 / 1)
EVALUATED, IGNORED = 0, 1

#: the alpha KITTI files write where the observation angle is unknown (DontCare rows)
UNKNOWN_ALPHA = -10.0

#: score-threshold sample points along recall: 0, 1/40, ..., 1 (the devkit's N_SAMPLE_PTS)
N_SAMPLE_POINTS = 41


@dataclass(frozen=True)
class FrameBoxes:
    """One frame reduced to the boxes that take part in one (class, difficulty) evaluation.

    Attributes
    ----------
    gt_state : (G,) int, ``EVALUATED`` or ``IGNORED`` per ground-truth box, file order.
    det_state : (D,) int, ``EVALUATED`` or ``IGNORED`` per detection, file order.
    det_scores : (D,) float, detector confidences.
    overlaps : (D, G) float, IoU of each detection with each ground-truth box.
    covers_dont_care : (D,) bool, the detection lies over a DontCare region (2D metric only).
    gt_alpha, det_alpha : (G,) and (D,) float, observation angles (rad; ``UNKNOWN_ALPHA``
        where the file has none), for the orientation similarity of the matched pairs.
    """

    gt_state: np.ndarray
    det_state: np.ndarray
    det_scores: np.ndarray
    overlaps: np.ndarray
    covers_dont_care: np.ndarray
    gt_alpha: np.ndarray | None = None
    det_alpha: np.ndarray | None = None

    def __post_init__(self) -> None:
        # without angles every one is unknown (no orientation similarity)
        if self.gt_alpha is None:
            object.__setattr__(self, "gt_alpha", np.full(len(self.gt_state), UNKNOWN_ALPHA))
        if self.det_alpha is None:
            object.__setattr__(self, "det_alpha", np.full(len(self.det_state), UNKNOWN_ALPHA))

    @property
    def n_evaluated_gt(self) -> int:
        """Recall denominator contributed by this frame."""
        return int(np.count_nonzero(self.gt_state == EVALUATED))

    def detections(self, keep: np.ndarray) -> "FrameBoxes":
        """The same frame with only the detections ``keep`` (mask or indices), in order."""
        return FrameBoxes(gt_state=self.gt_state, det_state=self.det_state[keep],
                          det_scores=self.det_scores[keep], overlaps=self.overlaps[keep],
                          covers_dont_care=self.covers_dont_care[keep], gt_alpha=self.gt_alpha,
                          det_alpha=self.det_alpha[keep])


@dataclass(frozen=True)
class FrameCounts:
    """True positives, false positives and misses of one frame at one score threshold."""

    tp: int
    fp: int
    fn: int
    tp_scores: np.ndarray  # (tp,) scores of the detections counted as true positives
    # sum over the true positives of (1 + cos(alpha_det - alpha_gt)) / 2, the devkit's
    # orientation similarity (NaN when a true positive's angle is unknown)
    similarity: float = 0.0


def ground_truth_states(gt: ObjectTable, cls: str, difficulty: Difficulty) -> np.ndarray:
    """(N,) state of each ground-truth row: ``EVALUATED``, ``IGNORED`` or -1 (no part)."""
    target, neighbour, _ = class_masks(gt, cls)
    inside = difficulty.accepts(gt)
    state = np.full(len(gt), -1, dtype=np.int64)
    state[neighbour | (target & ~inside)] = IGNORED
    state[target & inside] = EVALUATED
    return state


def detection_states(det: ObjectTable, cls: str, difficulty: Difficulty) -> np.ndarray:
    """(N,) state of each detection row: ``EVALUATED``, ``IGNORED`` (too small) or -1."""
    target, _, _ = class_masks(det, cls)
    # the devkit stores the height in an int32: 24.9 px is 24 px, below a 25 px minimum
    height_px = np.trunc(np.abs(det.box_2d[:, 3] - det.box_2d[:, 1]))
    state = np.full(len(det), -1, dtype=np.int64)
    state[target] = EVALUATED
    state[height_px < difficulty.min_height] = IGNORED
    return state


def dont_care_cover(det_boxes_2d: np.ndarray, dont_care_2d: np.ndarray,
                    min_overlap: float) -> np.ndarray:
    """(D,) bool: some DontCare region holds more than ``min_overlap`` of the detection's
    image box (intersection over the detection's own area, the devkit's criterion 0)."""
    if not len(det_boxes_2d) or not len(dont_care_2d):
        return np.zeros(len(det_boxes_2d), dtype=bool)
    d, r = det_boxes_2d[:, None, :], dont_care_2d[None, :, :]
    width = np.minimum(d[..., 2], r[..., 2]) - np.maximum(d[..., 0], r[..., 0])
    height = np.minimum(d[..., 3], r[..., 3]) - np.maximum(d[..., 1], r[..., 1])
    inter = np.clip(width, 0.0, None) * np.clip(height, 0.0, None)
    area = (d[..., 2] - d[..., 0]) * (d[..., 3] - d[..., 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(area > 0, inter / area, 0.0)
    return (share > min_overlap).any(axis=1)


def frame_boxes(gt: ObjectTable, det: ObjectTable, gt_state: np.ndarray,
                det_state: np.ndarray, overlaps: np.ndarray, metric: str,
                min_overlap: float) -> FrameBoxes:
    """The rows of one frame that take part (state >= 0), with their overlaps and, in the
    image metric, whether each detection covers a DontCare region."""
    g, d = gt_state >= 0, det_state >= 0
    if metric == "2d":
        regions = gt.box_2d[np.char.lower(gt.cls.astype(str)) == DONT_CARE.lower()]
        covers = dont_care_cover(det.box_2d[d], regions, min_overlap)
    else:
        covers = np.zeros(int(d.sum()), dtype=bool)
    return FrameBoxes(gt_state=gt_state[g], det_state=det_state[d], det_scores=det.score[d],
                      overlaps=overlaps[np.ix_(d, g)], covers_dont_care=covers,
                      gt_alpha=gt.alpha[g], det_alpha=det.alpha[d])


def frame_overlaps(gt: ObjectTable, det: ObjectTable, metric: str) -> np.ndarray:
    """(D, G) IoU matrix of one frame in ``metric``."""
    if not len(gt) or not len(det):
        return np.zeros((len(det), len(gt)))
    from .. import geometry  # the C++ core: imported only when boxes are compared

    if metric == "2d":
        return geometry.box_iou_2d(det.box_2d, gt.box_2d)
    if metric == "bev":
        return geometry.box_iou_bev(det.box_3d, gt.box_3d)
    return geometry.box_iou_3d(det.box_3d, gt.box_3d)


def frame_counts(frame: FrameBoxes, min_overlap: float,
                 score_threshold: float | None = None) -> FrameCounts:
    """Match one frame's detections to its ground truth, greedily in ground-truth order.

    Parameters
    ----------
    frame : the frame's boxes for the evaluated class and difficulty.
    min_overlap : a pair matches when its IoU is strictly above this.
    score_threshold : ``None`` gathers the true-positive scores that define the thresholds
        (each box takes its highest-scored candidate, false positives are not counted);
        a number keeps the detections scoring at least that much and counts TP / FP / FN
        (each box takes its candidate of largest IoU).

    Returns
    -------
    FrameCounts
    """
    counting = score_threshold is not None
    n_det = len(frame.det_state)
    free = np.ones(n_det, dtype=bool)
    if counting:
        free &= frame.det_scores >= score_threshold
    kept = free.copy()  # the detections in play at this threshold
    tp = fn = 0
    tp_scores = []
    similarity = 0.0
    for i, gt_state in enumerate(frame.gt_state):
        candidates = np.flatnonzero(free & (frame.overlaps[:, i] > min_overlap))
        match = -1
        if len(candidates) and not counting:
            match = candidates[np.argmax(frame.det_scores[candidates])]  # first of equal scores
        elif len(candidates):
            evaluated = candidates[frame.det_state[candidates] == EVALUATED]
            if len(evaluated):
                match = evaluated[np.argmax(frame.overlaps[evaluated, i])]
            else:
                match = candidates[0]  # an ignored (too small) detection, the first one
        if match < 0:
            fn += int(gt_state == EVALUATED)
            continue
        free[match] = False
        if gt_state == EVALUATED and frame.det_state[match] == EVALUATED:
            tp += 1
            tp_scores.append(frame.det_scores[match])
            similarity += orientation_similarity(frame.det_alpha[match], frame.gt_alpha[i])
    fp = 0
    if counting:
        unmatched = free & kept & (frame.det_state == EVALUATED) & ~frame.covers_dont_care
        fp = int(np.count_nonzero(unmatched))
    return FrameCounts(tp=tp, fp=fp, fn=fn, tp_scores=np.asarray(tp_scores, dtype=np.float64),
                       similarity=similarity)


def orientation_similarity(alpha_det: float, alpha_gt: float) -> float:
    """(1 + cos(alpha_det - alpha_gt)) / 2: 1 for the same heading, 0 for a box turned
    around (the devkit's AOS term); NaN when either angle is unknown (``UNKNOWN_ALPHA``)."""
    if alpha_det == UNKNOWN_ALPHA or alpha_gt == UNKNOWN_ALPHA:
        return float("nan")
    return 0.5 * (1.0 + float(np.cos(alpha_det - alpha_gt)))


def score_thresholds(tp_scores: np.ndarray, n_gt: int,
                     n_points: int = N_SAMPLE_POINTS) -> np.ndarray:
    """Score thresholds at which to sample precision, one per recall step ``1 / (n_points-1)``.

    Walking the true-positive scores from the highest down, the k-th score reaches recall
    ``(k+1) / n_gt``. A score is taken when its recall is at least as close to the current
    target recall as the next score's would be (the last score is always taken); each taken
    score moves the target one step up.

    Returns
    -------
    (K,) ndarray, decreasing, ``K <= n_points``.
    """
    scores = np.sort(np.asarray(tp_scores, dtype=np.float64))[::-1]
    if n_gt <= 0:
        return np.zeros(0)
    taken = []
    target = 0.0
    step = 1.0 / (n_points - 1.0)
    for k, score in enumerate(scores):
        last = k == len(scores) - 1
        recall_here = (k + 1) / n_gt
        recall_next = recall_here if last else (k + 2) / n_gt
        if not last and (recall_next - target) < (target - recall_here):
            continue  # the next score lands closer to the target recall
        taken.append(score)
        target += step
    return np.asarray(taken, dtype=np.float64)
