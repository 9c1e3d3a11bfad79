"""Columnar table of 3D object boxes: ground-truth labels, detections and tracking results.

One row per (frame, object). Every reader in :mod:`twistslam.datasets` returns this type and
every writer takes it, so labels, detector output and our own tracking results are compared
by the evaluator without conversion.

Box convention (docs/design.md): ``box_3d`` rows are ``[cx, cy, cz, l, w, h, ry]`` in the
rectified reference camera frame ``c`` (x right, y down, z forward). ``(cx, cy, cz)`` is the
*geometric centre* of the box, not KITTI's bottom centre: ``cy = y_kitti - h / 2``. ``ry`` is
KITTI's ``rotation_y`` (radians, about the camera y axis); the object x axis (length) points
along camera x when ``ry = 0``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

#: classes that KITTI treats as "regions to ignore" rather than objects
DONT_CARE = "DontCare"


@dataclass(eq=False)
class ObjectTable:
    """Objects of one sequence, one row per (frame, object); all arrays have length N."""

    frame: np.ndarray  # (N,) int64 frame index
    track_id: np.ndarray  # (N,) int64, -1 for untracked detections and DontCare regions
    cls: np.ndarray  # (N,) str (numpy unicode), KITTI type: Car, Van, Pedestrian, DontCare...
    truncation: np.ndarray  # (N,) float64 in [0, 1]; -1 where unknown
    occlusion: np.ndarray  # (N,) int64 KITTI level 0..3; -1 where unknown
    alpha: np.ndarray  # (N,) float64 observation angle (rad); -10 where unknown
    box_2d: np.ndarray  # (N, 4) float64 image box x1 y1 x2 y2 in image 2 (px)
    box_3d: np.ndarray  # (N, 7) float64 [cx, cy, cz, l, w, h, ry] camera frame, geometric centre
    score: np.ndarray  # (N,) float64 detector / tracker confidence; 1 for ground truth
    source: str = field(default="", compare=False)  # file the rows came from, for messages

    def __post_init__(self) -> None:
        self.frame = np.asarray(self.frame, dtype=np.int64).reshape(-1)
        n = len(self.frame)
        self.track_id = np.asarray(self.track_id, dtype=np.int64).reshape(n)
        self.cls = np.asarray(self.cls, dtype=str).reshape(n)
        self.truncation = np.asarray(self.truncation, dtype=np.float64).reshape(n)
        self.occlusion = np.asarray(self.occlusion, dtype=np.int64).reshape(n)
        self.alpha = np.asarray(self.alpha, dtype=np.float64).reshape(n)
        self.box_2d = np.asarray(self.box_2d, dtype=np.float64).reshape(n, 4)
        self.box_3d = np.asarray(self.box_3d, dtype=np.float64).reshape(n, 7)
        self.score = np.asarray(self.score, dtype=np.float64).reshape(n)

    @classmethod
    def empty(cls, source: str = "") -> "ObjectTable":
        return cls(
            frame=np.zeros(0), track_id=np.zeros(0), cls=np.zeros(0, dtype=str),
            truncation=np.zeros(0), occlusion=np.zeros(0), alpha=np.zeros(0),
            box_2d=np.zeros((0, 4)), box_3d=np.zeros((0, 7)), score=np.zeros(0),
            source=source,
        )

    def __len__(self) -> int:
        return len(self.frame)

    def select(self, mask_or_index) -> "ObjectTable":
        """Rows picked by a boolean mask or an index array, as a new table."""
        columns = {
            f.name: getattr(self, f.name)[mask_or_index]
            for f in fields(self)
            if f.name != "source"
        }
        return ObjectTable(**columns, source=self.source)

    def in_frame(self, frame: int) -> "ObjectTable":
        return self.select(self.frame == frame)

    def of_class(self, *names: str) -> "ObjectTable":
        return self.select(np.isin(self.cls, names))

    @property
    def frames(self) -> np.ndarray:
        """Sorted distinct frame indices present in the table."""
        return np.unique(self.frame)

    @property
    def track_ids(self) -> np.ndarray:
        """Sorted distinct track ids (excluding -1)."""
        ids = np.unique(self.track_id)
        return ids[ids >= 0]

    @staticmethod
    def concat(tables: list["ObjectTable"]) -> "ObjectTable":
        if not tables:
            return ObjectTable.empty()
        columns = {
            f.name: np.concatenate([getattr(t, f.name) for t in tables])
            for f in fields(ObjectTable)
            if f.name != "source"
        }
        return ObjectTable(**columns, source=tables[0].source)

    def equals(self, other: "ObjectTable", atol: float = 0.0) -> bool:
        """True when both tables hold the same rows in the same order (floats within atol)."""
        if len(self) != len(other):
            return False
        for f in fields(self):
            if f.name == "source":
                continue
            a, b = getattr(self, f.name), getattr(other, f.name)
            if a.dtype.kind == "f":
                if not np.allclose(a, b, rtol=0.0, atol=atol, equal_nan=True):
                    return False
            elif not np.array_equal(a, b):
                return False
        return True

    def sorted(self) -> "ObjectTable":
        """Rows ordered by (frame, track_id), the order KITTI files use."""
        return self.select(np.lexsort((self.track_id, self.frame)))
