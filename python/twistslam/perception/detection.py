"""3D object detection: the protocol every detection source follows and its result type.

A detection stage is any callable ``detect(frame) -> Detections3D`` from a
:class:`~twistslam.datasets.Frame` (its LiDAR scan ``points_c``, in the rectified camera
frame) to boxes in that same camera frame. Built-in sources: precomputed files, the classical
LiDAR detector of the C++ core (the default without weights) and 3DSSD in torch.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np


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
    """

    boxes: np.ndarray = field(default_factory=lambda: np.zeros((0, 7)))
    scores: np.ndarray = field(default_factory=lambda: np.zeros(0))
    classes: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))

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

    def __len__(self) -> int:
        return len(self.boxes)


@runtime_checkable
class DetectionStage(Protocol):
    """3D detection of one frame: ``detect(frame) -> Detections3D`` (boxes in frame c)."""

    def __call__(self, frame) -> Detections3D: ...
