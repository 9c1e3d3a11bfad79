"""Average precision of a 3DSSD checkpoint on labelled frames (KITTI tracking or object
layout), with the project's KITTI-rules evaluator (:mod:`twistslam.eval.detection_ap`).

The evaluator needs each detection's image box (its minimum-height rule): the 3D boxes are
projected with the frame's ``P2`` and clipped to the image.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from twistslam.datasets import KittiObject, KittiTracking
from twistslam.datasets.objects import ObjectTable

from .ssd3d_input import image_shape_of

#: evaluation keeps low-scored boxes too: AP sweeps the score threshold itself
EVALUATION_SCORE_THRESHOLD = 0.05
#: frame keys of the n-th evaluated sequence start at n * this (unique keys across sequences)
SEQUENCE_KEY_STRIDE = 100_000


def detections_table(detections, frame, key: int) -> ObjectTable:
    """A :class:`Detections3D` of ``frame`` as an ObjectTable (image boxes projected)."""
    from twistslam._core.geometry import project_boxes

    n = len(detections)
    rows, cols = image_shape_of(frame)
    box_2d = (np.asarray(project_boxes(detections.boxes, frame.calib.P2, cols, rows)) if n
              else np.zeros((0, 4)))
    box_2d = np.nan_to_num(box_2d, nan=0.0)
    return ObjectTable(frame=np.full(n, key), track_id=np.full(n, -1), cls=detections.classes.astype(str),
                       truncation=np.full(n, -1.0), occlusion=np.full(n, -1), alpha=np.full(n, -10.0),
                       box_2d=box_2d, box_3d=detections.boxes, score=detections.scores)


def _relabel(table: ObjectTable, key: int) -> ObjectTable:
    return ObjectTable(frame=np.full(len(table), key), track_id=table.track_id, cls=table.cls,
                       truncation=table.truncation, occlusion=table.occlusion, alpha=table.alpha,
                       box_2d=table.box_2d, box_3d=table.box_3d, score=table.score)


def labelled_frames(root: str | Path, seqs=()):
    """``(key, frame)`` of every labelled frame: tracking sequences ``seqs`` under ``root``,
    or, without ``seqs``, the KITTI object frames of ``root``."""
    if not seqs:
        dataset = KittiObject(root)
        for index in dataset.ids:
            yield int(index), dataset.frame(index)
        return
    for n, seq in enumerate(seqs):
        sequence = KittiTracking(root, seq)
        labelled = sorted(set(sequence.gt_objects.frame.tolist())) if sequence.gt_objects is not None else []
        for index in labelled:
            yield n * SEQUENCE_KEY_STRIDE + index, sequence.frame(index)


def evaluate_detector(detector, root: str | Path, seqs=(), classes=("Car",), iou=(0.5, 0.7)):
    """AP (``DetectionAPResult``, bird's-eye view and 3D, easy / moderate / hard) of
    ``detector`` (``frame -> Detections3D``) on the labelled frames of ``root``."""
    from twistslam.eval.detection_ap import evaluate_detections

    gt, dets = {}, {}
    for key, frame in labelled_frames(root, seqs):
        gt[key] = _relabel(frame.objects_gt, key) if frame.objects_gt is not None else ObjectTable.empty()
        dets[key] = detections_table(detector(frame), frame, key)
    return evaluate_detections(gt, dets, classes=classes, metrics=("bev", "3d"), iou=list(iou))


def evaluate_checkpoint(weights: str | Path, root: str | Path, seqs=(), **kwargs):
    """:func:`evaluate_detector` of the 3DSSD checkpoint ``weights`` at a low score threshold."""
    from ..detector_3dssd import Detector3DSSD

    detector = Detector3DSSD(weights, score_threshold=EVALUATION_SCORE_THRESHOLD)
    return evaluate_detector(detector, root, seqs, **kwargs)
