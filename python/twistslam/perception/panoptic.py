"""The panoptic-segmentation result every panoptic source returns, and its class vocabulary.

A panoptic source is any callable ``source(frame) -> Panoptic`` (files, a user's network, or
masks from 3D boxes), so the SLAM sees one type whatever produced the labels.

Vocabulary: Cityscapes label ids (what :mod:`twistslam.sim` writes), with ``0`` ("unlabeled")
standing for *unknown*. As in the TwistSLAM paper, unknown pixels are treated as static: only
classes named a-priori dynamic (vehicles, people, ...) may become moving clusters.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Cityscapes label id -> name (``0`` = unknown / unlabeled, treated as static)
CITYSCAPES_CLASSES = {
    0: "unknown", 1: "ego vehicle", 2: "rectification border", 3: "out of roi", 4: "static",
    5: "dynamic", 6: "ground", 7: "road", 8: "sidewalk", 9: "parking", 10: "rail track",
    11: "building", 12: "wall", 13: "fence", 14: "guard rail", 15: "bridge", 16: "tunnel",
    17: "pole", 18: "polegroup", 19: "traffic light", 20: "traffic sign", 21: "vegetation",
    22: "terrain", 23: "sky", 24: "person", 25: "rider", 26: "car", 27: "truck", 28: "bus",
    29: "caravan", 30: "trailer", 31: "train", 32: "motorcycle", 33: "bicycle",
}
UNKNOWN = 0
ROAD = 7
PERSON = 24
CAR = 26
#: a-priori dynamic classes (Cityscapes "human" and "vehicle" categories): everything else,
#: unknown included, is static by default
DEFAULT_DYNAMIC_CLASSES = (24, 25, 26, 27, 28, 29, 30, 31, 32, 33)
#: Cityscapes ``instanceIds`` PNGs: thing pixels hold ``class id * 1000 + instance``
INSTANCE_DIVISOR = 1000


def _present_values(values: np.ndarray) -> np.ndarray:
    """The sorted distinct values of an integer array (``np.unique``; by counting when they are
    small non-negative ones, as class ids are: 0.7 ms per KITTI-size image against 5)."""
    if values.size and 0 <= values.min() and values.max() < 65536:
        return np.flatnonzero(np.bincount(values.ravel()))
    return np.unique(values)


@dataclass(eq=False)
class Panoptic:
    """Per-pixel labels of one left image.

    Attributes
    ----------
    class_id : (H, W) int32
        Cityscapes label id of each pixel (keys of :data:`CITYSCAPES_CLASSES`; 0 = unknown).
    instance_id : (H, W) int32
        Instance of each thing pixel, ``>= 1``, unique within the image; 0 on stuff and
        unknown pixels.
    source : str
        Where the labels came from (a file name, ``"boxes"``), for messages.
    """

    class_id: np.ndarray
    instance_id: np.ndarray
    source: str = ""

    def __post_init__(self) -> None:
        where = f"{self.source}: " if self.source else ""
        self.class_id = np.asarray(self.class_id)
        self.instance_id = np.asarray(self.instance_id)
        if self.class_id.ndim != 2 or self.class_id.shape != self.instance_id.shape:
            raise ValueError(f"{where}class_id {self.class_id.shape} and instance_id "
                             f"{self.instance_id.shape} must be (H, W) arrays of the same shape")
        for name in ("class_id", "instance_id"):
            values = getattr(self, name)
            if not np.issubdtype(values.dtype, np.integer):
                raise ValueError(f"{where}{name} must hold integers, got {values.dtype}")
            setattr(self, name, values.astype(np.int32, copy=False))
        unknown = np.setdiff1d(_present_values(self.class_id), list(CITYSCAPES_CLASSES))
        if len(unknown):
            raise ValueError(f"{where}class_id {unknown[:5].tolist()} not in the Cityscapes "
                             "vocabulary (ids 0-33, 0 = unknown)")
        if (self.instance_id < 0).any():
            raise ValueError(f"{where}instance_id must be >= 0 (0 = no instance)")

    @property
    def shape(self) -> tuple[int, int]:
        return self.class_id.shape

    def dynamic_mask(self, dynamic_classes=DEFAULT_DYNAMIC_CLASSES) -> np.ndarray:
        """(H, W) bool: pixels of a-priori dynamic classes (unknown is static)."""
        return np.isin(self.class_id, np.asarray(dynamic_classes, dtype=np.int32))

    def static_mask(self, dynamic_classes=DEFAULT_DYNAMIC_CLASSES) -> np.ndarray:
        """(H, W) bool: every pixel not of an a-priori dynamic class, unknown included."""
        return ~self.dynamic_mask(dynamic_classes)

    def instances(self) -> dict[int, int]:
        """Instance id -> its class id (the majority class of its pixels)."""
        out = {}
        for k in np.unique(self.instance_id[self.instance_id > 0]):
            classes = self.class_id[self.instance_id == k]
            out[int(k)] = int(np.bincount(classes).argmax())
        return out

    @classmethod
    def from_cityscapes_ids(cls, ids: np.ndarray, source: str = "") -> "Panoptic":
        """Decode Cityscapes ``instanceIds`` values: stuff = class id, things =
        ``class id * 1000 + instance``.

        A thing's instance id is its whole encoded value (``26005``): the instance part
        alone is unique within its class only, and the whole value stays the same from frame
        to frame (the simulator encodes its track id), which a tracker can use."""
        ids = np.asarray(ids)
        if ids.dtype.kind == "u" and ids.itemsize <= 2 and ids.size:
            # 16-bit PNG values: decoded through two tables of at most 65536 entries (2 ms
            # per KITTI-size image against 8 for the int64 arithmetic below); np.take, not
            # table[ids]: fancy indexing widens the uint16 ids to intp first (1.1 against 3.2 ms)
            codes = np.arange(int(ids.max()) + 1, dtype=np.int32)
            thing = codes >= INSTANCE_DIVISOR
            class_table = np.where(thing, codes // INSTANCE_DIVISOR, codes).astype(np.int32)
            instance_table = np.where(thing, codes, 0).astype(np.int32)
            return cls(np.take(class_table, ids), np.take(instance_table, ids), source)
        ids = ids.astype(np.int64)
        thing = ids >= INSTANCE_DIVISOR
        class_id = np.where(thing, ids // INSTANCE_DIVISOR, ids)
        instance = np.where(thing, ids, 0)
        return cls(class_id.astype(np.int32), instance.astype(np.int32), source)
