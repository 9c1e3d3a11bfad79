"""Object detection AP with the KITTI object benchmark's rules (AP_R40, also AP_R11).

For each class, difficulty level (easy / moderate / hard), overlap metric (image box ``2d``,
bird view ``bev``, ``3d``) and IoU threshold, every frame is matched with the devkit's rules
(:mod:`.detection_matching`), then precision ``TP / (TP + FP)`` and recall ``TP / (TP + FN)``,
summed over the frames, are sampled at score thresholds, and the interpolated precision
``p(r) = max {precision at recall >= r}`` is averaged over the recall points
``r = 1/40, 2/40, ..., 1`` (``AP_R40``) or ``r = 0, 0.1, ..., 1`` (``AP_R11``), in percent.
Two samplings (``sampling=``):

``"exact"`` (default)
    Thresholds at every distinct true-positive score (the whole precision / recall curve);
    ``p(r)`` read at the true recall. This is the definition of AP_R40 (Simonelli et al.,
    ICCV 2019): labels against themselves give 100 on any number of boxes.
``"devkit"``
    The devkit's shortcut: at most 41 thresholds picked along recall by
    :func:`~.detection_matching.score_thresholds`, the k-th taken as the point of recall
    ``k / 40``. The devkit's (and OpenPCDet's ``AP_R40``) algorithm, but wrong with
    fewer than about 40 evaluated boxes: perfect detections of 9 boxes score
    ``8 / 40 = 20 %``. On many boxes the two differ by at most one recall point's share
    (up to 2.5 points): the devkit credits a recall just short of ``k / 40`` to point ``k``
    (real PointRCNN on sequence 0001, 1432 moderate cars: 2D@0.7 95.55 devkit, 93.90 exact).

A (class, difficulty) without any evaluated ground-truth box has no AP: NaN (shown ``-``).

>>> r = evaluate_detections(labels, detections, classes=("Car",))  # doctest: +SKIP
>>> r.ap("Car", "moderate", "3d", 0.7)  # doctest: +SKIP
>>> print(r.table())  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..datasets.objects import ObjectTable
from .detection_matching import (
    EVALUATED, N_SAMPLE_POINTS, FrameBoxes, detection_states, frame_boxes, frame_counts,
    frame_overlaps, ground_truth_states, score_thresholds,
)
from .difficulty import DIFFICULTIES

#: overlap metrics: image boxes, rotated bird-view rectangles, 3D boxes
METRICS = ("2d", "bev", "3d")
#: the benchmark's classes, evaluated by default
CLASSES = ("Car", "Pedestrian", "Cyclist")
#: IoU thresholds per class (lower case): the benchmark's strict one, then the loose one
#: most 3D detection papers print beside it (Car 0.7 / 0.5, Pedestrian / Cyclist 0.5 / 0.25)
IOU_THRESHOLDS: dict[str, tuple[float, ...]] = {
    "car": (0.7, 0.5), "pedestrian": (0.5, 0.25), "cyclist": (0.5, 0.25),
}

#: how precision is sampled along recall (see the module docstring)
SAMPLINGS = ("exact", "devkit")
#: recall points of AP_R40 (1/40 .. 1) and AP_R11 (0, 0.1, .. 1) on the 41-point grid
RECALL_GRID = np.linspace(0.0, 1.0, N_SAMPLE_POINTS)
R40_POINTS, R11_POINTS = np.arange(1, N_SAMPLE_POINTS), np.arange(0, N_SAMPLE_POINTS, 4)
#: a recall of exactly k / 40 computed as tp / n may land 1 ulp below the grid point
RECALL_ROUND_OFF = 1e-12

Tables = ObjectTable | Mapping[int, ObjectTable]


@dataclass(frozen=True)
class APCurve:
    """Precision / recall curve and AP of one (class, difficulty, metric, IoU threshold).

    Attributes
    ----------
    ap_r40, ap_r11 : AP in percent over 40 / 11 recall points; NaN when ``n_gt == 0``.
    precision : (41,) interpolated precision at the 41 sample points (0 where never reached).
    recall : (41,) recall of the sample points: the grid 0, 1/40, ..., 1 (``exact``), the
        recall reached at each threshold (``devkit``, 0 past the last).
    thresholds : (K,) score thresholds, decreasing (``K <= 41`` with ``devkit``).
    n_gt : evaluated ground-truth boxes (the recall denominator).
    aos_r40 : average orientation similarity in percent (the devkit's AOS, on the same
        recall points): precision with each true positive weighted by
        ``(1 + cos(alpha_det - alpha_gt)) / 2``, so a box turned around counts 0. At most
        ``ap_r40``; equal when every matched box faces its label's way. NaN without ground
        truth or when a matched box has no observation angle (alpha -10).
    """

    cls: str
    difficulty: str
    metric: str
    min_overlap: float
    ap_r40: float
    ap_r11: float
    precision: np.ndarray
    recall: np.ndarray
    thresholds: np.ndarray
    n_gt: int
    aos_r40: float = float("nan")

    def to_dict(self) -> dict:
        return {
            "class": self.cls, "difficulty": self.difficulty, "metric": self.metric,
            "iou": self.min_overlap, "ap_r40": _json_float(self.ap_r40),
            "ap_r11": _json_float(self.ap_r11), "aos_r40": _json_float(self.aos_r40),
            "n_gt": self.n_gt,
            "precision": [float(v) for v in self.precision],
            "recall": [float(v) for v in self.recall],
            "thresholds": [float(v) for v in self.thresholds],
        }


@dataclass(frozen=True)
class DetectionAPResult:
    """Every curve of one evaluation; :meth:`ap` picks one number, :meth:`table` prints."""

    curves: tuple[APCurve, ...]
    n_frames: int
    sampling: str = "exact"

    def curve(self, cls: str, difficulty: str, metric: str, iou: float) -> APCurve:
        """The curve of one (class, difficulty, metric, IoU); ``KeyError`` when not computed."""
        for c in self.curves:
            if (c.cls.lower() == cls.lower() and c.difficulty == difficulty.lower()
                    and c.metric == metric.lower() and np.isclose(c.min_overlap, iou)):
                return c
        raise KeyError(f"no AP computed for {cls} {difficulty} {metric} IoU {iou}")

    def ap(self, cls: str, difficulty: str, metric: str, iou: float) -> float:
        """AP_R40 in percent of one (class, difficulty, metric, IoU)."""
        return self.curve(cls, difficulty, metric, iou).ap_r40

    def aos(self, cls: str, difficulty: str, iou: float) -> float:
        """AOS_R40 in percent of one (class, difficulty) on the image boxes at ``iou`` (the
        devkit's orientation score)."""
        return self.curve(cls, difficulty, "2d", iou).aos_r40

    def table(self) -> str:
        """AP_R40 (%) as text: a block per class, a row per difficulty, a column per
        (metric, IoU), ``AOS@iou`` after the image-box columns (the devkit's orientation
        score), and the number of evaluated ground-truth boxes."""
        lines = [f"AP_R40 (%) over {self.n_frames} frames, KITTI object benchmark rules, "
                 f"{self.sampling} recall sampling; AOS: orientation similarity on the image boxes"]
        for cls in dict.fromkeys(c.cls for c in self.curves):
            mine = [c for c in self.curves if c.cls == cls]
            columns = list(dict.fromkeys((c.metric, c.min_overlap) for c in mine))
            columns += [("aos", iou) for m, iou in columns if m == "2d"]
            header = [f"{m.upper()}@{iou:g}" for m, iou in columns]
            lines.append(f"{cls:<12}" + "".join(f"{h:>10}" for h in header) + f"{'n_gt':>7}")
            for difficulty in dict.fromkeys(c.difficulty for c in mine):
                row = [c for c in mine if c.difficulty == difficulty]
                cells = "".join(f"{_cell(self._value(cls, difficulty, m, iou)):>10}"
                                for m, iou in columns)
                lines.append(f"  {difficulty:<10}{cells}{row[0].n_gt:>7}")
        return "\n".join(lines) + "\n"

    def _value(self, cls: str, difficulty: str, column: str, iou: float) -> float:
        if column == "aos":
            return self.aos(cls, difficulty, iou)
        return self.ap(cls, difficulty, column, iou)

    def to_dict(self) -> dict:
        """JSON-ready dict (NaN written as ``null``)."""
        return {"ap": "R40", "sampling": self.sampling, "n_frames": self.n_frames,
                "curves": [c.to_dict() for c in self.curves]}


def evaluate_detections(
    gt: Tables,
    dets: Tables,
    classes: Iterable[str] = CLASSES,
    metrics: Iterable[str] = ("2d", "bev", "3d"),
    iou: float | Sequence[float] | Mapping[str, Sequence[float]] | None = None,
    difficulties: Iterable[str] = ("easy", "moderate", "hard"),
    frames: Iterable[int] | None = None,
    sampling: str = "exact",
) -> DetectionAPResult:
    """AP of ``dets`` against ``gt`` under the KITTI object benchmark's rules.

    Parameters
    ----------
    gt, dets : ObjectTable (frames from its ``frame`` column) or ``{frame: ObjectTable}``.
        Ground truth needs ``box_2d``, ``truncation`` and ``occlusion`` (difficulty) and
        its DontCare rows; detections need ``box_2d`` (minimum height) and ``score``.
    classes : evaluated classes (compared case-insensitively).
    metrics : any of ``"2d"``, ``"bev"``, ``"3d"``.
    iou : ``None``: each class's thresholds of :data:`IOU_THRESHOLDS`; a number or a list:
        the same thresholds for every class; a mapping class -> list.
    difficulties : any of ``"easy"``, ``"moderate"``, ``"hard"``.
    frames : frames to evaluate; default every frame present in ``gt`` or ``dets`` (a
        frame missing from one side has no boxes there).
    sampling : ``"exact"`` or ``"devkit"`` (see the module docstring).

    Returns
    -------
    DetectionAPResult
    """
    # a single name is one class / metric / level, not a sequence of letters
    classes, metrics, difficulties = (
        [v] if isinstance(v, str) else list(v) for v in (classes, metrics, difficulties))
    _known(sampling, SAMPLINGS, "sampling")
    metrics = [m.lower() for m in metrics]
    for m in metrics:
        if m not in METRICS:
            raise ValueError(f"unknown metric {m!r}; choose among {METRICS}")
    levels = [DIFFICULTIES[_known(d.lower(), DIFFICULTIES, "difficulty")] for d in difficulties]
    thresholds = {cls: _class_thresholds(cls, iou) for cls in classes}
    gt_frames, det_frames = _by_frame(gt, "gt"), _by_frame(dets, "dets")
    frame_ids = sorted(set(gt_frames) | set(det_frames) if frames is None else set(frames))
    empty = ObjectTable.empty()
    pairs = [(gt_frames.get(f, empty), det_frames.get(f, empty)) for f in frame_ids]
    overlaps = {m: [frame_overlaps(g, d, m) for g, d in pairs] for m in metrics}

    curves = []
    for cls in classes:
        for level in levels:
            states = [(ground_truth_states(g, cls, level), detection_states(d, cls, level))
                      for g, d in pairs]
            for metric in metrics:
                for min_overlap in thresholds[cls]:
                    boxes = [
                        frame_boxes(g, d, gs, ds, ov, metric, min_overlap)
                        for (g, d), (gs, ds), ov in zip(pairs, states, overlaps[metric])
                    ]
                    curves.append(_curve(boxes, cls, level.name, metric, min_overlap,
                                         sampling))
    return DetectionAPResult(curves=tuple(curves), n_frames=len(frame_ids), sampling=sampling)


def _curve(frames: list[FrameBoxes], cls: str, difficulty: str, metric: str,
           min_overlap: float, sampling: str) -> APCurve:
    n_gt = sum(f.n_evaluated_gt for f in frames)
    scores = [frame_counts(f, min_overlap).tp_scores for f in frames]
    scores = np.concatenate(scores) if scores else np.zeros(0)
    if sampling == "devkit":
        thresholds = score_thresholds(scores, n_gt)[:N_SAMPLE_POINTS]  # a 41-point curve
    else:
        thresholds = np.unique(scores)[::-1]
    tp, fp, fn, similarity = _counts(frames, min_overlap, thresholds)
    with np.errstate(divide="ignore", invalid="ignore"):
        precision = np.nan_to_num(tp / (tp + fp))
        recall = np.nan_to_num(tp / (tp + fn))
        # a NaN similarity (an unknown angle) stays NaN: no AOS
        orientation = np.where(tp + fp > 0, similarity / (tp + fp), 0.0)
    if sampling == "devkit":
        # the k-th threshold stands for recall k / 40; points never reached count 0
        sampled = np.zeros(N_SAMPLE_POINTS)
        sampled[: len(thresholds)] = precision
        curve_recall = np.zeros(N_SAMPLE_POINTS)
        curve_recall[: len(thresholds)] = recall
        interpolated = np.maximum.accumulate(sampled[::-1])[::-1]
        sampled_aos = np.zeros(N_SAMPLE_POINTS)
        sampled_aos[: len(thresholds)] = orientation
        interpolated_aos = np.maximum.accumulate(sampled_aos[::-1])[::-1]
    else:
        # best precision over the thresholds reaching at least each recall point (0 if none)
        reaches = recall[None, :] >= RECALL_GRID[:, None] - RECALL_ROUND_OFF  # (41, K)
        interpolated = np.where(reaches, precision[None, :], 0.0).max(axis=1, initial=0.0)
        # the devkit interpolates the orientation score as it does precision
        interpolated_aos = np.where(reaches, orientation[None, :], 0.0).max(axis=1, initial=0.0)
        curve_recall = RECALL_GRID.copy()
    if n_gt == 0:
        ap_r40 = ap_r11 = aos_r40 = float("nan")
    else:
        ap_r40 = float(interpolated[R40_POINTS].mean() * 100.0)
        ap_r11 = float(interpolated[R11_POINTS].mean() * 100.0)
        known = np.isfinite(similarity).all()
        aos_r40 = float(interpolated_aos[R40_POINTS].mean() * 100.0) if known else float("nan")
    return APCurve(cls=cls, difficulty=difficulty, metric=metric, min_overlap=float(min_overlap),
                   ap_r40=ap_r40, ap_r11=ap_r11, precision=interpolated, recall=curve_recall,
                   thresholds=thresholds, n_gt=n_gt, aos_r40=aos_r40)


def _counts(frames: list[FrameBoxes], min_overlap: float,
            thresholds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(K,) TP, FP, FN and orientation similarity summed over the frames at each score
    threshold."""
    totals = np.zeros((len(thresholds), 3), dtype=np.int64)
    similarity = np.zeros(len(thresholds))
    for f in frames:
        # a detection overlapping no ground-truth box never matches: when kept it is simply
        # a false positive (unless ignored or over a DontCare region), counted without
        # matching -- this leaves the matching to the few detections near objects
        matchable = (f.overlaps > min_overlap).any(axis=1)
        idle = ~matchable & (f.det_state == EVALUATED) & ~f.covers_dont_care
        totals[:, 1] += np.count_nonzero(f.det_scores[idle][None, :] >= thresholds[:, None],
                                         axis=1)
        f = f.detections(matchable)
        # the counts only change when the threshold passes one of the frame's scores:
        # match once per number of detections kept
        kept = np.count_nonzero(f.det_scores[None, :] >= thresholds[:, None], axis=1)
        for n_kept in np.unique(kept):
            at = kept == n_kept
            if n_kept == 0:
                totals[at, 2] += f.n_evaluated_gt  # nothing kept: every evaluated box missed
                continue
            c = frame_counts(f, min_overlap, score_threshold=thresholds[at][0])
            totals[at] += (c.tp, c.fp, c.fn)
            similarity[at] += c.similarity
    return totals[:, 0], totals[:, 1], totals[:, 2], similarity


def _by_frame(tables: Tables, name: str) -> dict[int, ObjectTable]:
    if isinstance(tables, ObjectTable):
        return {int(f): tables.in_frame(f) for f in tables.frames}
    if isinstance(tables, Mapping):
        out = {}
        for frame, table in tables.items():
            if not isinstance(table, ObjectTable):
                raise TypeError(f"{name}[{frame!r}] must be an ObjectTable, "
                                f"got {type(table).__name__}")
            out[int(frame)] = table
        return out
    raise TypeError(f"{name} must be an ObjectTable or a dict frame -> ObjectTable, "
                    f"got {type(tables).__name__}")


def _class_thresholds(cls: str, iou) -> tuple[float, ...]:
    if iou is None:
        return IOU_THRESHOLDS[_known(cls.lower(), IOU_THRESHOLDS, "class without default IoU")]
    if isinstance(iou, Mapping):
        lower = {k.lower(): v for k, v in iou.items()}
        values = lower[_known(cls.lower(), lower, "class missing from iou")]
    else:
        values = iou
    values = tuple(float(v) for v in np.atleast_1d(values))
    if not values or not all(0.0 < v <= 1.0 for v in values):
        raise ValueError(f"IoU thresholds of {cls} must lie in (0, 1], got {values}")
    return values


def _known(key: str, options, what: str) -> str:
    if key not in options:
        raise ValueError(f"{what}: {key!r}; known: {sorted(options)}")
    return key


def _cell(value: float) -> str:
    return "-" if np.isnan(value) else f"{value:.2f}"


def _json_float(value: float) -> float | None:
    return None if np.isnan(value) else float(value)
