"""3D object detection: the protocol every detection source follows and its result type.

A detection stage is any callable ``detect(frame) -> Detections3D`` from a
:class:`~twistslam.datasets.Frame` (its LiDAR scan ``points_c``, in the rectified camera
frame) to boxes in that same camera frame. Built-in sources (:func:`detection_source`):
precomputed files (:class:`~twistslam.perception.detection_files.FileDetections`), the
classical LiDAR detector of the C++ core, the default without weights
(:class:`~twistslam.perception.detection_classical.ClassicalDetector`) and 3DSSD in torch
(``Detector3DSSD``, imported only when asked for). See ``docs/detection.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:  # datasets imports nothing from perception: no cycle at run time either
    from twistslam.datasets import Calibration, ObjectTable

#: the names :func:`detection_source` accepts
DETECTION_KINDS = ("auto", "files", "classical", "3dssd")


def _flags(name: str, value, default: np.ndarray) -> np.ndarray:
    """``value`` as an (N,) bool array like ``default`` (``default`` itself when None)."""
    if value is None:
        return default
    flags = np.asarray(value).reshape(-1)
    if len(flags) != len(default) or flags.dtype.kind not in "bui":
        raise ValueError(f"Detections3D: {name} must hold {len(default)} booleans, got {flags.tolist()}")
    return flags.astype(bool)


@dataclass
class Detections3D:
    """The 3D boxes one frame's detector found.

    Attributes
    ----------
    boxes : (N, 7) float64 ``[x, y, z, l, w, h, yaw]`` in the rectified camera frame c
        (x right, y down, z forward): ``x y z`` the box's geometric centre (not KITTI's bottom
        centre), ``l w h`` in metres along the box's x (heading), z and y axes, ``yaw`` the
        KITTI ``rotation_y`` in radians (about the camera's y axis; 0 faces the camera's x).
    scores : (N,) float64 confidences, larger is surer (not necessarily probabilities).
    classes : (N,) str, KITTI type names (``Car``, ``Pedestrian``, ``Cyclist``, ...).
    open_end : (N,) int8, optional. 0: the box's length was measured (or the source does not
        say: files, 3DSSD). +1 / -1: a partly seen car whose length is the detector's prior,
        laid from its seen face towards the box's +x / -x end (x along ``yaw``'s heading);
        the LiDAR fusion moves such a box's centre that way once other frames measured the
        car's length (the classical detector sets it).
    point_extent : (N,) bool, optional. True: the box is the tight extent of its LiDAR points
        (the classical detector), so a measured length is a lower bound (the far end of a
        car's side returns few points) and the box's end nearer the sensor is the seen one;
        the LiDAR fusion then takes a car's length from an upper quantile of its boxes and
        lays each box from its near end (``lidar_objects.point_extent_length_quantile``).
        False (default; files, 3DSSD): the length is the detector's estimate.
    heading_known : (N,) bool, optional. True: ``yaw``'s heading points to the object's front.
        Default: where ``point_extent`` is False (files and 3DSSD know front from back; a box
        around LiDAR points knows its heading mod pi). The classical detector sets it for the
        cars whose front it told from their height profile; the LiDAR fusion lets only such
        boxes vote for a parked car's heading with their own.
    """

    boxes: np.ndarray = field(default_factory=lambda: np.zeros((0, 7)))
    scores: np.ndarray = field(default_factory=lambda: np.zeros(0))
    classes: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))
    open_end: np.ndarray | None = None
    point_extent: np.ndarray | None = None
    heading_known: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.boxes = np.asarray(self.boxes, dtype=np.float64).reshape(-1, 7)
        self.scores = np.asarray(self.scores, dtype=np.float64).reshape(-1)
        self.classes = np.asarray(self.classes, dtype=object).reshape(-1)
        n = len(self.boxes)
        if len(self.scores) != n or len(self.classes) != n:
            raise ValueError(f"Detections3D: {n} boxes but {len(self.scores)} scores and "
                             f"{len(self.classes)} classes")
        if not np.isfinite(self.boxes).all() or not np.isfinite(self.scores).all():
            raise ValueError("Detections3D: boxes and scores must be finite")
        if self.open_end is None:
            self.open_end = np.zeros(n, dtype=np.int8)
        open_end = np.asarray(self.open_end).reshape(-1)
        if len(open_end) != n or not np.isin(open_end, (-1, 0, 1)).all():
            raise ValueError(f"Detections3D: open_end must hold {n} values in {{-1, 0, 1}}, "
                             f"got {open_end.tolist()}")
        self.open_end = open_end.astype(np.int8)
        self.point_extent = _flags("point_extent", self.point_extent, np.zeros(n, dtype=bool))
        self.heading_known = _flags("heading_known", self.heading_known, ~self.point_extent)

    def __len__(self) -> int:
        return len(self.boxes)

    def select(self, mask_or_index) -> "Detections3D":
        """The detections picked by a boolean mask or an index array."""
        return Detections3D(self.boxes[mask_or_index], self.scores[mask_or_index],
                            self.classes[mask_or_index], self.open_end[mask_or_index],
                            self.point_extent[mask_or_index], self.heading_known[mask_or_index])

    @classmethod
    def from_table(cls, table: "ObjectTable") -> "Detections3D":
        """The boxes of an :class:`~twistslam.datasets.ObjectTable` (one frame's rows; the
        table's ``box_3d`` already has the geometric centre). DontCare rows are left out."""
        keep = table.cls != "DontCare"
        return cls(table.box_3d[keep], table.score[keep], table.cls[keep].astype(object))

    def to_table(self, frame: int, calib: "Calibration | None" = None,
                 image_size: tuple[int, int] | None = None) -> "ObjectTable":
        """These detections as an :class:`~twistslam.datasets.ObjectTable` of ``frame``.

        ``alpha`` (the observation angle) is ``yaw - atan2(x, z)``; with ``calib`` the image
        boxes are the boxes projected by ``P2`` (clipped to ``image_size = (width, height)``
        when given), else -1. Boxes wholly behind the camera get image box -1 too.
        """
        from twistslam.datasets import ObjectTable
        from twistslam.geometry import project_boxes

        n = len(self)
        x, z, yaw = self.boxes[:, 0], self.boxes[:, 2], self.boxes[:, 6]
        alpha = np.angle(np.exp(1j * (yaw - np.arctan2(x, z))))  # wrapped to (-pi, pi]
        box_2d = np.full((n, 4), -1.0)
        if calib is not None and n:
            width, height = image_size if image_size is not None else (0, 0)
            projected = project_boxes(self.boxes, calib.P2, int(width), int(height))
            seen = np.isfinite(projected).all(axis=1)
            box_2d[seen] = projected[seen]
        return ObjectTable(frame=np.full(n, int(frame)), track_id=np.full(n, -1),
                           cls=self.classes.astype(str), truncation=np.full(n, -1.0),
                           occlusion=np.full(n, -1), alpha=alpha, box_2d=box_2d,
                           box_3d=self.boxes, score=self.scores)


@runtime_checkable
class DetectionStage(Protocol):
    """3D detection of one frame: ``detect(frame) -> Detections3D`` (boxes in frame c)."""

    def __call__(self, frame) -> Detections3D: ...


def detection_source(kind: str = "auto", *, path: str | Path | None = None,
                     weights: str | Path | None = None, options: dict[str, Any] | None = None,
                     missing_frames: str = "error") -> DetectionStage:
    """The detection stage of ``kind``.

    Parameters
    ----------
    kind : "auto", "files", "classical" or "3dssd"
        "auto": files when ``path`` is given, else 3DSSD when ``weights`` is given, else the
        classical detector.
    path : a detection file or folder for "files": a PointRCNN comma file, a KITTI tracking
        result file (one file, every frame) or a KITTI object result folder (NNNNNN.txt per
        frame).
    weights : the 3DSSD checkpoint ("3dssd" requires it).
    options : options of the classical detector (``twistslam._core.detection.default_options``).
    missing_frames : "error" (default) or "empty": what a KITTI object result folder without
        the frame's file gives. A frame absent from a one-file source has no detections.

    Raises
    ------
    ValueError
        An unknown ``kind``, "files" without ``path``, "3dssd" without ``weights``, or bad
        classical options.
    """
    if kind not in DETECTION_KINDS:
        raise ValueError(f"detection source '{kind}': expected one of {', '.join(DETECTION_KINDS)}")
    if kind == "auto":
        kind = "files" if path is not None else "3dssd" if weights is not None else "classical"
    if kind == "files":
        if path is None:
            raise ValueError("detection source 'files': needs path (a detection file or folder)")
        from .detection_files import FileDetections

        return FileDetections(path, missing_frames=missing_frames)
    if kind == "3dssd":
        if weights is None:
            raise ValueError("detection source '3dssd': needs weights (a 3DSSD checkpoint file)")
        from .detector_3dssd import Detector3DSSD  # torch: imported only when asked for

        return Detector3DSSD(weights)
    from .detection_classical import ClassicalDetector

    return ClassicalDetector(options)
