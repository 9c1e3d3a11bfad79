"""Precomputed 3D detections read from files, one :class:`Detections3D` per frame.

Three layouts, told apart by what ``path`` is:

* a folder: KITTI object results, ``NNNNNN.txt`` per frame in the object label format with a
  score (what ``twistslam detect`` writes);
* a file whose first line has commas: PointRCNN / AB3DMOT detections
  (:func:`twistslam.datasets.read_detections`);
* any other file: KITTI tracking results, every frame in one file
  (:func:`twistslam.datasets.read_labels`).

A frame absent from a one-file source has no detections (detectors write nothing for a frame
where they found nothing). A frame whose file is missing from a folder is an error naming the
file (a run that stopped half-way should not read as empty frames), unless
``missing_frames="empty"``.
"""

from __future__ import annotations

import errno
from pathlib import Path

from twistslam.datasets import ObjectTable, read_detection_file, read_object_labels

from .detection import Detections3D

MISSING_FRAME_RULES = ("error", "empty")


class FileDetections:
    """Detections of each frame from precomputed files (see the module docstring).

    Parameters
    ----------
    path : a detection file or a KITTI object result folder.
    missing_frames : "error" (default): a frame without its ``NNNNNN.txt`` in a folder raises
        ``FileNotFoundError`` naming the file; "empty": it has no detections.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        An unknown ``missing_frames``; a malformed file (message ``"<file>:<line>: ..."``).
    """

    def __init__(self, path: str | Path, *, missing_frames: str = "error") -> None:
        if missing_frames not in MISSING_FRAME_RULES:
            raise ValueError(f"missing_frames '{missing_frames}': expected one of "
                             f"{', '.join(MISSING_FRAME_RULES)}")
        self.path = Path(path)
        self.missing_frames = missing_frames
        if not self.path.exists():
            raise FileNotFoundError(errno.ENOENT, f"detection source not found: {self.path}",
                                    str(self.path))
        self.table: ObjectTable | None = None if self.path.is_dir() else read_detection_file(self.path)

    def __repr__(self) -> str:
        return f"FileDetections({str(self.path)!r})"

    def frame_file(self, index: int) -> Path:
        """The file of frame ``index`` in a result folder."""
        return self.path / f"{int(index):06d}.txt"

    def detections(self, index: int) -> Detections3D:
        """The detections of frame number ``index``."""
        if self.table is not None:
            return Detections3D.from_table(self.table.in_frame(int(index)))
        file = self.frame_file(index)
        if not file.is_file():
            if self.missing_frames == "empty":
                return Detections3D()
            raise FileNotFoundError(
                errno.ENOENT, f"{self}: no detection file for frame {int(index):06d} "
                              "(pass missing_frames='empty' to read it as no detections)", str(file))
        return Detections3D.from_table(read_object_labels(file, frame=int(index)))

    def __call__(self, frame) -> Detections3D:
        return self.detections(frame.index)
