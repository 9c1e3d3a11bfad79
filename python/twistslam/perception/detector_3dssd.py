"""3DSSD (Yang et al., CVPR 2020) as a detection stage: ``Detector3DSSD(weights)(frame)``
-> :class:`~twistslam.perception.detection.Detections3D`.

The network is :class:`twistslam.perception.torch_models.ssd3d_model.SSD3D` (plain torch); its
weights come from a checkpoint file the user names (format in
:mod:`twistslam.perception.torch_models.ssd3d_checkpoint`; ``twistslam train-detector``
writes one). Nothing is downloaded. torch is an optional extra, imported when a detector is
built.

As KITTI labels only objects in the left image, the detector looks only at the LiDAR points
that project into it (the frame's image size, else KITTI's 1242 x 375).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .detection import Detections3D

#: default confidence below which a candidate is dropped (sigmoid of a centre-ness-trained
#: logit: true centres score near 1, object borders lower)
DEFAULT_SCORE_THRESHOLD = 0.3
#: bird's-eye-view IoU above which a lower-scored box is suppressed (objects do not overlap
#: on the ground, so a small value removes the duplicates the many candidates produce)
DEFAULT_NMS_IOU = 0.1
#: at most this many boxes per frame (KITTI frames hold a few tens of objects)
MAX_DETECTIONS = 100
#: seed of the input resampling: the same scan always gives the same detections
INPUT_SEED = 0


def _import_torch():
    try:
        import torch
    except ImportError as e:  # pragma: no cover - torch is installed where tests run
        raise ImportError("3DSSD needs torch: pip install 'twistslam[models]'") from e
    return torch


class Detector3DSSD:
    """3DSSD on a frame's LiDAR scan.

    Parameters
    ----------
    weights_path : a 3DSSD checkpoint file (``twistslam train-detector --out``).
    device : torch device name.
    score_threshold : boxes scoring lower are dropped.
    nms_iou : bird's-eye-view IoU of the per-class non-maximum suppression.

    Raises
    ------
    FileNotFoundError for a missing file, ValueError for a file that is not a 3DSSD checkpoint
    of a supported version, ImportError without torch.
    """

    def __init__(self, weights_path: str | Path, device: str = "cpu",
                 score_threshold: float = DEFAULT_SCORE_THRESHOLD, nms_iou: float = DEFAULT_NMS_IOU) -> None:
        self.torch = _import_torch()
        from .torch_models.ssd3d_checkpoint import load_checkpoint

        self.model, self.training_info = load_checkpoint(weights_path)
        self.model.to(device)
        self.device = device
        self.score_threshold = float(score_threshold)
        self.nms_iou = float(nms_iou)

    @property
    def config(self):
        return self.model.config

    def __repr__(self) -> str:
        return f"Detector3DSSD(classes={list(self.config.classes)}, points={self.config.num_points})"

    def __call__(self, frame) -> Detections3D:
        """Boxes of ``frame.points_c`` (N, 4) float32 in the rectified camera frame."""
        from .torch_models.ssd3d_input import frame_points, image_shape_of, resample

        if frame.points_c is None:
            raise ValueError(f"3DSSD: frame {frame.index} has no LiDAR scan")
        P2 = frame.calib.P2 if getattr(frame, "calib", None) is not None else None
        points = frame_points(frame.points_c, P2, image_shape_of(frame), self.config.point_range)
        if len(points) == 0:
            return Detections3D()
        points = resample(points, self.config.num_points, np.random.default_rng(INPUT_SEED))
        return self.detect_points(points)

    def detect_points(self, points_l: np.ndarray) -> Detections3D:
        """Boxes of an already prepared input (num_points, 4) in frame l."""
        from .torch_models.ssd3d_boxes import lidar_to_camera_boxes, rotated_nms_bev

        torch = self.torch
        with torch.no_grad():
            output = self.model(torch.from_numpy(np.ascontiguousarray(points_l, np.float32))[None].to(self.device))
            boxes, scores, labels = (t.cpu().numpy() for t in self.model.decode(output))
        keep = (scores >= self.score_threshold) & np.isfinite(boxes).all(axis=1)
        boxes_c = lidar_to_camera_boxes(boxes[keep])
        scores, labels = scores[keep].astype(np.float64), labels[keep]
        chosen = []
        for label in np.unique(labels):
            members = np.flatnonzero(labels == label)
            chosen.extend(members[rotated_nms_bev(boxes_c[members], scores[members], self.nms_iou)])
        chosen = np.asarray(chosen, dtype=np.int64)
        chosen = chosen[np.argsort(-scores[chosen], kind="stable")][:MAX_DETECTIONS]
        names = np.asarray(self.config.classes, dtype=object)
        return Detections3D(boxes=boxes_c[chosen], scores=scores[chosen], classes=names[labels[chosen]])
