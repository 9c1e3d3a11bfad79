"""The per-frame record every dataset yields, and the protocol every sequence follows.

Conventions (docs/design.md): ``points_c`` are in the rectified reference camera frame ``c``
(x right, y down, z forward), ``T_w_c_gt`` maps camera points into the world (= camera frame
of frame 0), boxes in ``objects_gt`` follow :mod:`twistslam.datasets.objects`.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from .calibration import Calibration
from .objects import ObjectTable


@dataclass
class Frame:
    """One time step of a sequence; a modality that the dataset lacks is ``None``."""

    index: int  # frame index within the sequence (KITTI numbering)
    timestamp: float  # seconds since the start of the sequence
    image_left: np.ndarray | None  # (H, W, 3) uint8 RGB, camera 2
    image_right: np.ndarray | None  # (H, W, 3) uint8 RGB, camera 3
    points_c: np.ndarray | None  # (N, 4) float32: x y z in frame c, intensity
    points_velo: np.ndarray | None  # (N, 4) float32: raw LiDAR x y z intensity
    calib: Calibration
    T_w_c_gt: np.ndarray | None = None  # (4, 4) float64 ground-truth camera pose
    objects_gt: ObjectTable | None = None  # ground-truth objects of this frame


@runtime_checkable
class Sequence(Protocol):
    """What the pipeline needs from a dataset sequence (KITTI tracking, simulator, ...).

    Optional: ``frame(index, lidar=False)``, a frame without its LiDAR scan (used by the
    stereo pipeline's loader when present; otherwise it indexes the sequence)."""

    calib: Calibration

    def __len__(self) -> int: ...

    def __getitem__(self, index: int) -> Frame: ...

    def __iter__(self) -> Iterator[Frame]: ...

    @property
    def timestamps(self) -> np.ndarray: ...

    @property
    def gt_poses(self) -> np.ndarray | None: ...

    @property
    def gt_objects(self) -> ObjectTable | None: ...
