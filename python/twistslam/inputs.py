"""What the sequence loop feeds the core: checked stereo frames and panoptic class-id images.

Errors name the frame and, for sequences on disk (anything with ``base`` and ``seq``, such as
:class:`~twistslam.datasets.KittiTracking`), the file: a run over hundreds of frames must
say which file to look at.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .datasets import Frame, MissingDataWarning, Sequence, read_image

#: camera folder -> what the user calls it
CAMERAS = {"image_02": "left", "image_03": "right"}
#: Cityscapes ``instanceIds`` encoding of the simulator's panoptic PNGs (docs/sim.md):
#: stuff pixels hold the class id, thing pixels ``class id * 1000 + instance``
INSTANCE_DIVISOR = 1000


def _frame_file(sequence: Sequence, folder: str, index: int, ext: str = ".png") -> Path | None:
    base, seq = getattr(sequence, "base", None), getattr(sequence, "seq", None)
    if base is None or seq is None:
        return None
    return Path(base) / folder / str(seq) / f"{index:06d}{ext}"


def check_stereo(sequence: Sequence) -> None:
    """Refuse, before any frame is tracked, a sequence that lacks a whole camera.

    Raises
    ------
    FileNotFoundError
        The left (``image_02``) or right (``image_03``) image folder does not exist.
    ValueError
        The sequence has no frames.
    """
    if len(sequence) == 0:
        raise ValueError(f"{sequence}: the sequence has no frames")
    for folder, side in CAMERAS.items():
        path = _frame_file(sequence, folder, 0)
        if path is not None and not path.parent.is_dir():
            raise FileNotFoundError(
                f"{path.parent} not found: the sequence has no {side} images, and stereo SLAM "
                "needs both the left (image_02) and the right (image_03) camera"
            )


def load_frame(sequence: Sequence, index: int, *, lidar: bool = False) -> Frame:
    """Frame ``index`` with both images present and readable; its LiDAR scan too when
    ``lidar`` (``None`` where the frame has none: tracking then uses stereo depth alone).

    Raises
    ------
    FileNotFoundError
        An image of this frame is missing (named).
    ValueError
        A file of this frame cannot be read (named when the sequence is on disk).
    """
    try:
        with warnings.catch_warnings():
            # a missing image is raised below with the frame's name; missing LiDAR is
            # already reported once when the sequence is opened
            warnings.simplefilter("ignore", MissingDataWarning)
            # the scan is read only when used; sequences without frame() load everything
            read = getattr(sequence, "frame", None)
            frame = read(index, lidar=lidar) if callable(read) else sequence[index]
    except (OSError, ValueError) as exc:
        raise ValueError(f"frame {index}: {_unreadable(sequence, index) or exc}") from exc
    for folder, side in CAMERAS.items():
        image = frame.image_left if side == "left" else frame.image_right
        if image is None:
            path = _frame_file(sequence, folder, index)
            where = f" ({path} not found)" if path is not None else ""
            raise FileNotFoundError(
                f"frame {index}: no {side} image{where}; stereo SLAM needs both images")
    return frame


def _unreadable(sequence: Sequence, index: int) -> str | None:
    """Which image of the frame fails to read, and why (``None``: not an image file)."""
    for folder in CAMERAS:
        path = _frame_file(sequence, folder, index)
        if path is None or not path.is_file():
            continue
        try:
            read_image(path)
        except (OSError, ValueError) as exc:
            return f"cannot read {path}: {exc}"
    return None


class PanopticLabels:
    """Per-frame class-id images from ``<base>/<labels_dir>/<seq>/NNNNNN.png``.

    The PNGs are 16-bit panoptic ids in the Cityscapes ``instanceIds`` encoding (what
    :mod:`twistslam.sim` writes); :meth:`read` turns them into ``(H, W)`` int32 class ids.
    """

    def __init__(self, sequence: Sequence, labels_dir: str) -> None:
        self.sequence = sequence
        self.labels_dir = labels_dir

    @classmethod
    def find(cls, sequence: Sequence, labels_dir: str) -> "PanopticLabels | None":
        """The reader when the sequence has a ``labels_dir`` folder, else ``None``."""
        path = _frame_file(sequence, labels_dir, 0)
        if path is None or not path.parent.is_dir():
            return None
        return cls(sequence, labels_dir)

    def path(self, index: int) -> Path:
        return _frame_file(self.sequence, self.labels_dir, index)

    def read(self, index: int) -> np.ndarray | None:
        """``(H, W)`` int32 class ids of frame ``index``; ``None`` when its file is missing."""
        path = self.path(index)
        if not path.is_file():
            return None
        from .datasets.sensors import read_bounded_image

        try:
            ids = read_bounded_image(path, lambda image, _: np.array(image))
        except OSError as exc:
            raise ValueError(f"frame {index}: cannot read panoptic labels {path}: {exc}") from exc
        if ids.ndim != 2:
            raise ValueError(f"frame {index}: {path} is not a single-channel panoptic id image "
                             f"(shape {ids.shape})")
        return class_ids(ids)


def class_ids(panoptic: np.ndarray) -> np.ndarray:
    """Class ids ``(H, W)`` int32 of Cityscapes-encoded panoptic ids (stuff: the id itself,
    things: ``id // 1000``)."""
    ids = np.asarray(panoptic).astype(np.int32)
    return np.where(ids >= INSTANCE_DIVISOR, ids // INSTANCE_DIVISOR, ids).astype(np.int32)
