"""Which boxes count: the evaluated class, its ignored neighbour and the KITTI difficulty."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..datasets.objects import DONT_CARE, ObjectTable


@dataclass(frozen=True)
class Difficulty:
    """KITTI difficulty level: a ground-truth box outside it is *ignored*, not missed.

    Attributes
    ----------
    min_height : minimum image-box height (px) of a ground-truth box.
    max_occlusion : maximum KITTI occlusion level (0 fully visible .. 2 largely occluded).
    max_truncation : maximum truncation. Tracking labels store integer levels 0/1/2, so the
        object benchmark's 0.15 / 0.30 / 0.50 thresholds all keep level 0 only, exactly as
        the tracking devkit (which casts truncation to int) does.
    """

    name: str
    min_height: float
    max_occlusion: int
    max_truncation: float

    def accepts(self, table: ObjectTable, *, check_height: bool = True) -> np.ndarray:
        """(N,) bool: the row is inside this difficulty level.

        ``check_height=False`` judges occlusion and truncation only: the KITTI tracking
        devkit applies the minimum height to tracker boxes, never to ground truth.
        """
        inside = (table.occlusion <= self.max_occlusion) & (
            table.truncation <= self.max_truncation
        )
        if check_height:
            inside &= table.box_2d[:, 3] - table.box_2d[:, 1] >= self.min_height
        return inside


#: the KITTI object benchmark's three levels
DIFFICULTIES: dict[str, Difficulty] = {
    "easy": Difficulty("easy", 40.0, 0, 0.15),
    "moderate": Difficulty("moderate", 25.0, 1, 0.30),
    "hard": Difficulty("hard", 25.0, 2, 0.50),
}

#: evaluated class -> similar class whose boxes are ignored (a Van is neither a missed Car
#: nor a false Car), as in the KITTI devkit
NEIGHBOURS: dict[str, str] = {"car": "van", "pedestrian": "person_sitting"}


def get_difficulty(name_or_level: str | Difficulty) -> Difficulty:
    if isinstance(name_or_level, Difficulty):
        return name_or_level
    try:
        return DIFFICULTIES[name_or_level.lower()]
    except KeyError:
        raise ValueError(
            f"unknown difficulty {name_or_level!r}; choose one of {sorted(DIFFICULTIES)}"
        ) from None


def class_masks(table: ObjectTable, cls: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Masks of rows of the evaluated class, of its neighbour class, and DontCare regions.

    Class names compare case-insensitively (KITTI files say ``Car``, users type ``car``).
    """
    lower = np.char.lower(table.cls.astype(str))
    cls = cls.lower()
    target = lower == cls
    neighbour = lower == NEIGHBOURS.get(cls, "\0")
    dont_care = lower == DONT_CARE.lower()
    return target, neighbour, dont_care
