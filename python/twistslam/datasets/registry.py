"""Name -> dataset class registry, so that ``twistslam.run`` takes any supported sequence."""

from __future__ import annotations

from ._parsing import PathLike
from .frame import Sequence
from .kitti_tracking import KittiTracking

#: dataset name -> class; a class is built as ``cls(root, seq, split=...)`` and, for a single
#: path, as ``cls.from_path(path)``
DATASETS: dict[str, type] = {"kitti_tracking": KittiTracking}


def register_dataset(name: str, cls: type) -> None:
    """Make ``cls`` available to :func:`open_sequence` as ``dataset=name``."""
    DATASETS[name] = cls


def open_sequence(
    path_or_root: PathLike | Sequence,
    seq: int | str | None = None,
    *,
    dataset: str = "kitti_tracking",
    split: str = "training",
) -> Sequence:
    """Open a sequence.

    Parameters
    ----------
    path_or_root
        The dataset root (with ``seq``), a path inside one sequence (without ``seq``, e.g.
        ``.../training/image_02/0001`` or ``.../training/0001``), or an already opened
        sequence, which is returned unchanged.
    seq
        Sequence number (``1`` or ``"0001"``).
    dataset
        Key of :data:`DATASETS`.
    split
        ``"training"`` or ``"testing"`` (used with ``seq``).
    """
    if isinstance(path_or_root, Sequence):
        return path_or_root
    if dataset not in DATASETS:
        raise ValueError(f"unknown dataset {dataset!r}; known: {', '.join(sorted(DATASETS))}")
    cls = DATASETS[dataset]
    if seq is None:
        return cls.from_path(path_or_root)
    return cls(path_or_root, seq, split=split)
