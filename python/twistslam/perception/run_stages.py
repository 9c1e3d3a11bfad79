"""The perception stages of a run (:func:`twistslam.run`): which segmentation, flow and 3D
detection source a sequence gets, from a name or a user's callable.

``segmentation``: ``"auto"`` (the sequence's panoptic files when it has them, else masks from
3D boxes and the LiDAR scans when it has scans and boxes come from somewhere, else none),
``"files"``, ``"boxes"``, ``"torch"`` (a Mask R-CNN and a semantic network; needs
``segmentation_weights``), ``"none"`` / ``None``, or any callable ``frame -> Panoptic |
(class_id, instance_id)``. The boxes of ``"boxes"`` are the configured detector's of the same
frame (named ``"boxes:<detector>"``, e.g. ``"boxes:classical"``: the whole system from raw
stereo + LiDAR); with ``detector="none"`` the precomputed detection files
(``"boxes:files"``).
``flow``: ``"auto"`` (files when present, else OpenCV DIS), ``"files"``, ``"dis"``, ``"raft"``
(needs ``flow_weights``), ``"none"`` / ``None``, or any callable ``(previous, current) ->
(H, W, 2)``. Flow only serves object tracking: without segmentation no flow is computed.
``detector``: the 3D detections of the LiDAR fusion (``config.lidar_objects``) and of the
masks from boxes: ``"auto"`` (the sequence's detection files, else the classical LiDAR
detector when the sequence has scans, else none), ``"files"``, ``"classical"``, ``"3dssd"``
(needs ``detector_weights``), ``"none"`` / ``None``, or any callable ``frame ->
Detections3D``. Like flow, it only serves object tracking.
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
from .panoptic_from_boxes import DETECTOR_MASK_MIN_SCORE, BoxMaskConfig, PanopticFromDetections
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


#: Boxes of a PointRCNN comma-format file (the layout of the AB3DMOT / KITTI tracking
#: detections, whose scores are the network's logits) scored below this are not used by a run
#: (neither its masks nor the LiDAR fusion). Measured on the tuning split's labels (0000 0002
#: 0003 0004 0005 0007 0009 0011 0017 0020; not the shared 0001): the share of boxes lying on a
#: labelled car is 9 / 14 / 15 % for scores in [-1, 0) / [0, 0.5) / [0.5, 1), then 20 / 30 / 40 /
#: 59 % up to 4 and 99 % from 7 (validation split alike). Real 0001, whole system with the
#: files: 3D CLEAR MOTA 62.5 -> 91.7 %, FP 9 -> 2, TP, MOTP and ATE unchanged. Other file
#: layouts (KITTI object or tracking results: any writer's scale) keep every box; the
#: detections tracker (issue 9, ``track_detections``) keeps every box and thresholds tracks.
POINTRCNN_MIN_SCORE = 1.0


def _file_detections(source, sequence):
    """The precomputed detections ``source`` (file, folder or ObjectTable) of ``sequence``,
    checked; a PointRCNN comma file's boxes below ``POINTRCNN_MIN_SCORE`` left out."""
    from ..datasets.detections import is_pointrcnn_file
    from ..objects.detections_input import load_detections

    table = load_detections(source, str(getattr(sequence, "seq", "")), len(sequence))
    read_from = Path(table.source) if table.source else None  # the file the rows came from
    if read_from is not None and read_from.is_file() and is_pointrcnn_file(read_from):
        table = table.select(table.score >= POINTRCNN_MIN_SCORE)
    return table


def _has_lidar(sequence) -> bool:
    base, seq = getattr(sequence, "base", None), getattr(sequence, "seq", None)
    return base is not None and (Path(base) / "velodyne" / str(seq)).is_dir()


@dataclass
class Perception:
    """The stages a run uses. ``segmentation`` / ``flow`` / ``detector`` are ``None`` when off.
    ``needs_lidar``: a stage reads the frames' scans (masks from boxes, a LiDAR detector).
    ``masks_from_detections``: the segmentation is ``(frame, detections) -> Panoptic``, fed
    the detector's boxes of the same frame (:meth:`detect` runs first, once per frame).
    ``fuse_detections``: the detections also go to the LiDAR fusion (``False``: they only
    make the masks, ``config.lidar_objects.use_detections`` off)."""

    segmentation: Callable[..., Any] | None = None
    flow: Callable[..., np.ndarray] | None = None
    segmentation_name: str = "none"
    flow_name: str = "none"
    needs_lidar: bool = False
    detector: Callable[..., Detections3D] | None = None
    detector_name: str = "none"
    masks_from_detections: bool = False
    fuse_detections: bool = True

    def panoptic(self, frame, detections: Detections3D | None = None) -> Panoptic | None:
        """The frame's labels; ``None`` when off, or when a file source has no file for this
        frame (the frame is tracked without masks: clusters keep their tracks from their
        matched points, camera tracking uses every keypoint). ``detections``: this frame's
        :meth:`detect`, required when the masks come from the detector."""
        if self.segmentation is None:
            return None
        shape = np.asarray(frame.image_left).shape[:2]
        if self.masks_from_detections:
            if detections is None:
                raise ValueError(f"segmentation '{self.segmentation_name}': frame {frame.index} "
                                 "needs its detections (Perception.detect) for its masks")
            return check_panoptic(self.segmentation(frame, detections), shape,
                                  self.segmentation_name)
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

    def optical_flow(self, previous, current, instances=None) -> np.ndarray | None:
        """The flow from ``previous`` to ``current``; ``None`` when off or at the first frame.
        ``instances``: both frames' instance images, given to the sources that take them
        (``accepts_instances``: DIS, which then computes only around them; the flow serves
        the object search alone)."""
        if self.flow is None or previous is None:
            return None
        shape = np.asarray(current.image_left).shape[:2]
        if instances is not None and getattr(self.flow, "accepts_instances", False):
            flow = self.flow(previous, current, instances=instances)
        else:
            flow = self.flow(previous, current)
        return np.ascontiguousarray(check_flow(flow, shape, self.flow_name))


def _segmentation_kind(kind, sequence) -> Any:
    """``kind`` checked, ``"auto"`` resolved: ``"files"`` when the sequence has panoptic
    files, else ``"boxes"`` when it has scans (the boxes' source is chosen with the detector,
    :func:`_box_masks`), else ``"none"``; ``None`` is ``"none"``."""
    if kind is None or callable(kind):
        return "none" if kind is None else kind
    if kind not in SEGMENTATION_KINDS:
        raise ValueError(f"segmentation '{kind}': expected one of {', '.join(SEGMENTATION_KINDS)} "
                         "or a callable frame -> Panoptic")
    if kind != "auto":
        return kind
    try:
        panoptic_source("files", sequence)
        return "files"
    except FileNotFoundError:
        return "boxes" if _has_lidar(sequence) else "none"


def _box_masks(sequence, detections, detect, detect_name: str, auto: bool
               ) -> tuple[Callable | None, str, bool]:
    """The masks-from-boxes stage, its name ``"boxes:<source>"`` and whether it takes the
    frame's detections: the run's detector when there is one, else the precomputed
    ``detections`` (or the sequence's own files); ``(None, "none", False)`` for ``"auto"``
    without either."""
    if detect is not None:
        config = BoxMaskConfig(min_score=DETECTOR_MASK_MIN_SCORE.get(detect_name))
        return PanopticFromDetections(config), f"boxes:{detect_name}", True
    if detections is None:
        detections = find_detections(sequence)
    if detections is None:
        if auto:
            return None, "none", False
        raise FileNotFoundError(
            f"segmentation 'boxes' needs 3D boxes: no detector is configured (detector 'none') "
            f"and {sequence} has no detections/<name>/{getattr(sequence, 'seq', '')}.txt; pass "
            "detector='classical' (the LiDAR detector, no weights) or detections=FILE")
    table = _file_detections(detections, sequence)
    return panoptic_source("boxes", sequence, boxes=table), "boxes:files", False


class TableDetections:
    """Detection stage over precomputed boxes of a whole sequence (an ObjectTable): a frame
    without rows has no detections."""

    def __init__(self, table) -> None:
        self.table = table

    def __call__(self, frame) -> Detections3D:
        return Detections3D.from_table(self.table.in_frame(int(frame.index)))


def _detector(kind, sequence, detections, weights=None,
              options: dict | None = None) -> tuple[Callable | None, str]:
    """The detection stage and its name; ``options``: the classical detector's."""
    if kind is None or kind == "none":
        return None, "none"
    if callable(kind):
        from .detection_classical import ClassicalDetector

        # the classical detector with the user's options is still the classical detector:
        # its name picks its masks' score floor (DETECTOR_MASK_MIN_SCORE)
        if isinstance(kind, ClassicalDetector):
            return kind, "classical"
        return kind, getattr(kind, "__name__", type(kind).__name__)
    if kind not in DETECTOR_KINDS:
        raise ValueError(f"detector '{kind}': expected one of {', '.join(DETECTOR_KINDS)} or a "
                         "callable frame -> Detections3D")
    from .detection import detection_source

    if kind in ("classical", "3dssd"):
        return detection_source(kind, weights=weights, options=options), kind
    if detections is None:
        detections = find_detections(sequence)
    if detections is None:
        if kind == "auto":
            if not _has_lidar(sequence):
                return None, "none"
            return detection_source("classical", options=options), "classical"
        raise FileNotFoundError(f"detector 'files': {sequence} has no detections/<name>/"
                                f"{getattr(sequence, 'seq', '')}.txt; pass detections=")
    return TableDetections(_file_detections(detections, sequence)), "files"


def perception_stages(sequence, segmentation: Any = "auto", flow: Any = "auto", *,
                      detections: Any = None, flow_weights: str | Path | None = None,
                      segmentation_weights: dict | None = None,
                      detector: Any = "none", detector_weights: str | Path | None = None,
                      fuse_detections: bool = True,
                      detector_options: dict | None = None) -> Perception:
    """The segmentation, flow and detection stages for ``sequence`` (see the module
    docstring). ``segmentation_weights``: the files of ``segmentation="torch"``, ``{"maskrcnn":
    FILE, "semantic": FILE}`` (see :func:`~.panoptic_source.panoptic_source`).
    ``fuse_detections``: the detections serve the LiDAR fusion; when ``False`` the detector
    only runs when the masks come from it. ``detector_options``: the classical detector's
    options (``Config.detection``; ``None``: its defaults).

    Masks from boxes (``"boxes"``, or ``"auto"`` without panoptic files) come from the
    configured detector's boxes of each frame (the detector runs once per frame, for the
    masks and the fusion); with ``detector="none"`` from the precomputed ``detections``.

    Raises
    ------
    ValueError
        An unknown source name; "torch" without its weights or with a file that is not that
        network's state dict.
    FileNotFoundError
        "files" without files, "boxes" with neither a detector nor detections, a weight file
        of "raft" or "torch" that does not exist.
    """
    seg_kind = _segmentation_kind(segmentation, sequence)
    detect, detect_name = None, "none"
    if seg_kind != "none" and (fuse_detections or seg_kind == "boxes"):
        detect, detect_name = _detector(detector, sequence, detections, detector_weights,
                                        detector_options)
    from_detections = False
    if callable(seg_kind):
        seg, seg_name = seg_kind, getattr(seg_kind, "__name__", type(seg_kind).__name__)
    elif seg_kind == "boxes":
        seg, seg_name, from_detections = _box_masks(sequence, detections, detect, detect_name,
                                                    auto=segmentation == "auto")
    elif seg_kind in ("files", "torch"):
        seg, seg_name = panoptic_source(seg_kind, sequence, weights=segmentation_weights), seg_kind
    else:
        seg, seg_name = None, "none"
    if seg is None or not (fuse_detections or from_detections):
        detect, detect_name = None, "none"  # the detections only serve object tracking
    # the classical detector, 3DSSD and a user's callable read the scans; files do not
    needs_lidar = seg_name.startswith("boxes:") or (detect is not None and detect_name != "files")
    stages = dict(segmentation_name=seg_name, needs_lidar=needs_lidar, detector=detect,
                  detector_name=detect_name, masks_from_detections=from_detections,
                  fuse_detections=fuse_detections and detect is not None)
    if seg is None or flow is None or flow == "none":
        return Perception(seg, None, flow_name="none", **stages)
    if callable(flow):
        return Perception(seg, flow, flow_name=getattr(flow, "__name__", type(flow).__name__),
                          **stages)
    if flow not in FLOW_KINDS:
        raise ValueError(f"flow '{flow}': expected one of {', '.join(FLOW_KINDS)}, 'none' "
                         "or a callable (previous, current) -> (H, W, 2)")
    stage = flow_source(flow, sequence, weights=flow_weights)
    name = type(stage).__name__.replace("Flow", "").lower() or flow
    return Perception(seg, stage, flow_name=name or flow, **stages)
