"""The perception stages of a run (:func:`twistslam.run`): which segmentation and flow source
a sequence gets, from a name or a user's callable.

``segmentation``: ``"auto"`` (the sequence's panoptic files when it has them, else masks from
its 3D detections and LiDAR scans when it has both, else none), ``"files"``, ``"boxes"``,
``"torch"`` (a Mask R-CNN and a semantic network; needs ``segmentation_weights``),
``"none"`` / ``None``, or any callable ``frame -> Panoptic | (class_id, instance_id)``.
``flow``: ``"auto"`` (files when present, else OpenCV DIS), ``"files"``, ``"dis"``, ``"raft"``
(needs ``flow_weights``), ``"none"`` / ``None``, or any callable ``(previous, current) ->
(H, W, 2)``. Flow only serves object tracking: without segmentation no flow is computed.
``detector``: the 3D detections of the LiDAR fusion (``config.lidar_objects``): ``"auto"`` (the
sequence's detection files, else the classical LiDAR detector when the sequence has scans,
else none), ``"files"``, ``"classical"``, ``"3dssd"`` (needs ``detector_weights``), ``"none"``
/ ``None``, or any callable ``frame -> Detections3D``. Like flow, it only serves object
tracking.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .detection import Detections3D
from .flow import FLOW_KINDS, flow_source
from .panoptic import Panoptic
from .panoptic_source import check_panoptic, panoptic_source
from .stage import check_flow

SEGMENTATION_KINDS = ("auto", "files", "boxes", "torch", "none")
DETECTOR_KINDS = ("auto", "files", "classical", "3dssd", "none")


def find_detections(sequence) -> Path | None:
    """``<root>/detections/<name>/<seq>.txt`` beside the sequence's split folder (what the
    simulator writes for its oracle and the shared real data for PointRCNN), the first
    ``<name>`` in sorted order, or ``None``."""
    base, seq = getattr(sequence, "base", None), getattr(sequence, "seq", None)
    if base is None or seq is None:
        return None
    folder = Path(base).parent / "detections"
    if not folder.is_dir():
        return None
    for source in sorted(p for p in folder.iterdir() if p.is_dir()):
        if (source / f"{seq}.txt").is_file():
            return source / f"{seq}.txt"
    return None


def _has_lidar(sequence) -> bool:
    base, seq = getattr(sequence, "base", None), getattr(sequence, "seq", None)
    return base is not None and (Path(base) / "velodyne" / str(seq)).is_dir()


@dataclass
class Perception:
    """The stages a run uses. ``segmentation`` / ``flow`` are ``None`` when off; ``needs_lidar``:
    the segmentation reads the frames' scans (masks from boxes)."""

    segmentation: Callable[..., Any] | None = None
    flow: Callable[..., np.ndarray] | None = None
    segmentation_name: str = "none"
    flow_name: str = "none"
    needs_lidar: bool = False
    detector: Callable[..., Detections3D] | None = None
    detector_name: str = "none"

    def panoptic(self, frame) -> Panoptic | None:
        """The frame's labels; ``None`` when off, or when a file source has no file for this
        frame (the frame is tracked without masks: clusters keep their tracks from their
        matched points, camera tracking uses every keypoint)."""
        if self.segmentation is None:
            return None
        shape = np.asarray(frame.image_left).shape[:2]
        try:
            result = self.segmentation(frame)
        except FileNotFoundError:
            if self.segmentation_name != "files":
                raise
            return None
        return check_panoptic(result, shape, self.segmentation_name)

    def detect(self, frame) -> Detections3D | None:
        """The frame's 3D detections, ``None`` when off."""
        if self.detector is None:
            return None
        result = self.detector(frame)
        if not isinstance(result, Detections3D):
            raise TypeError(f"detector '{self.detector_name}': expected Detections3D from frame "
                            f"{frame.index}, got {type(result).__name__}")
        return result

    def optical_flow(self, previous, current) -> np.ndarray | None:
        if self.flow is None or previous is None:
            return None
        shape = np.asarray(current.image_left).shape[:2]
        return np.ascontiguousarray(check_flow(self.flow(previous, current), shape, self.flow_name))


def _segmentation(kind, sequence, detections, weights=None) -> tuple[Callable | None, str, bool]:
    if kind is None or kind == "none":
        return None, "none", False
    if callable(kind):
        return kind, getattr(kind, "__name__", type(kind).__name__), False
    if kind not in SEGMENTATION_KINDS:
        raise ValueError(f"segmentation '{kind}': expected one of {', '.join(SEGMENTATION_KINDS)} "
                         "or a callable frame -> Panoptic")
    if kind == "auto":
        try:
            return panoptic_source("files", sequence), "files", False
        except FileNotFoundError:
            pass
        if detections is None:
            detections = find_detections(sequence)
        if detections is None or not _has_lidar(sequence):
            return None, "none", False
        kind = "boxes"
    if kind == "files":
        return panoptic_source("files", sequence), "files", False
    if kind == "torch":
        return panoptic_source("torch", sequence, weights=weights), "torch", False
    from ..objects.detections_input import load_detections

    if detections is None:
        detections = find_detections(sequence)
    if detections is None:
        raise FileNotFoundError(f"segmentation 'boxes': {sequence} has no detections/<name>/"
                                f"{getattr(sequence, 'seq', '')}.txt; pass detections=")
    table = load_detections(detections, str(getattr(sequence, "seq", "")), len(sequence))
    return panoptic_source("boxes", sequence, boxes=table), "boxes", True


class TableDetections:
    """Detection stage over precomputed boxes of a whole sequence (an ObjectTable): a frame
    without rows has no detections."""

    def __init__(self, table) -> None:
        self.table = table

    def __call__(self, frame) -> Detections3D:
        return Detections3D.from_table(self.table.in_frame(int(frame.index)))


def _detector(kind, sequence, detections, segmentation_name: str,
              weights=None) -> tuple[Callable | None, str]:
    if kind is None or kind == "none" or segmentation_name == "none":
        return None, "none"
    if callable(kind):
        return kind, getattr(kind, "__name__", type(kind).__name__)
    if kind not in DETECTOR_KINDS:
        raise ValueError(f"detector '{kind}': expected one of {', '.join(DETECTOR_KINDS)} or a "
                         "callable frame -> Detections3D")
    from ..objects.detections_input import load_detections
    from .detection import detection_source

    if kind in ("classical", "3dssd"):
        return detection_source(kind, weights=weights), kind
    if detections is None:
        detections = find_detections(sequence)
    if detections is None:
        if kind == "auto":
            return (detection_source("classical"), "classical") if _has_lidar(sequence) else (None, "none")
        raise FileNotFoundError(f"detector 'files': {sequence} has no detections/<name>/"
                                f"{getattr(sequence, 'seq', '')}.txt; pass detections=")
    table = load_detections(detections, str(getattr(sequence, "seq", "")), len(sequence))
    return TableDetections(table), "files"


def perception_stages(sequence, segmentation: Any = "auto", flow: Any = "auto", *,
                      detections: Any = None, flow_weights: str | Path | None = None,
                      segmentation_weights: dict | None = None,
                      detector: Any = "none", detector_weights: str | Path | None = None) -> Perception:
    """The segmentation and flow stages for ``sequence`` (see the module docstring).
    ``segmentation_weights``: the files of ``segmentation="torch"``, ``{"maskrcnn": FILE,
    "semantic": FILE}`` (see :func:`~.panoptic_source.panoptic_source`).

    Raises
    ------
    ValueError
        An unknown source name; "torch" without its weights or with a file that is not that
        network's state dict.
    FileNotFoundError
        "files" without files, "boxes" without detections, a weight file of "raft" or
        "torch" that does not exist.
    """
    seg, seg_name, needs_lidar = _segmentation(segmentation, sequence, detections,
                                               segmentation_weights)
    detect, detect_name = _detector(detector, sequence, detections, seg_name, detector_weights)
    if seg is None or flow is None or flow == "none":
        return Perception(seg, None, seg_name, "none", needs_lidar, detect, detect_name)
    if callable(flow):
        return Perception(seg, flow, seg_name, getattr(flow, "__name__", type(flow).__name__),
                          needs_lidar, detect, detect_name)
    if flow not in FLOW_KINDS:
        raise ValueError(f"flow '{flow}': expected one of {', '.join(FLOW_KINDS)}, 'none' "
                         "or a callable (previous, current) -> (H, W, 2)")
    stage = flow_source(flow, sequence, weights=flow_weights)
    name = type(stage).__name__.replace("Flow", "").lower() or flow
    return Perception(seg, stage, seg_name, name, needs_lidar, detect, detect_name)
