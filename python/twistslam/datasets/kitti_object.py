"""The KITTI 3D object benchmark: independent frames with a scan, an image, labels, calibration.

Layout (the KITTI object download)::

    <root>/<split>/calib/NNNNNN.txt      required; one file per frame (object key spelling:
                                         P0..P3, R0_rect, Tr_velo_to_cam, Tr_imu_to_velo)
    <root>/<split>/label_2/NNNNNN.txt    ground-truth objects (not in the testing split)
    <root>/<split>/velodyne/NNNNNN.bin   LiDAR scans
    <root>/<split>/image_2/NNNNNN.png    left colour images

The frames of the object benchmark are unrelated snapshots, each with its own calibration, so
:class:`KittiObject` is not a :class:`~twistslam.datasets.Sequence` (no poses, no time). Frames
are addressed by their KITTI number (the file name): ``ds[8]`` is ``.../000008.*``.

A folder other than ``calib`` that is missing altogether (the testing split has no labels, a
partial download has no scans) gives ``None`` in every frame with one
:class:`MissingDataWarning`; a single file missing from a folder that exists is an error
naming that file (the download is broken).
"""

from __future__ import annotations

import errno
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ._parsing import PathLike, iter_lines, parse_error, to_floats, to_int
from .calibration import read_calibration
from .frame import Frame
from .labels import label_table
from .objects import ObjectTable
from .sensors import MissingDataWarning, read_image, read_velodyne, scan_in_camera

#: folder -> file suffix of the per-frame files
_FOLDERS = {"label_2": ".txt", "velodyne": ".bin", "image_2": ".png"}


def read_object_labels(path: PathLike, frame: int = 0) -> ObjectTable:
    """Read a KITTI object label file (``label_2/NNNNNN.txt``) into an :class:`ObjectTable`.

    One object per line: ``type truncated occluded alpha x1 y1 x2 y2 h w l x y z rotation_y
    [score]`` -- the tracking label columns without ``frame`` and ``track_id``. Every row gets
    ``frame`` and track id -1; rows without a score get 1. Boxes follow the tracking reader:
    geometric centre (``cy = y - h / 2``), DontCare placeholders kept as written.

    Raises
    ------
    ValueError
        ``"<file>:<line>: expected 15 or 16 columns, got n"`` or a bad number.
    """
    cls, trunc, occ, numbers = [], [], [], []
    for line_no, tokens in iter_lines(path):
        if len(tokens) not in (15, 16):
            raise parse_error(path, line_no, f"expected 15 or 16 columns, got {len(tokens)}")
        cls.append(tokens[0])
        trunc.append(to_floats(tokens[1:2], path, line_no, "truncated")[0])
        occ.append(to_int(tokens[2], path, line_no, "occluded"))
        values = to_floats(tokens[3:], path, line_no, "box")
        numbers.append(values if len(values) == 13 else np.append(values, 1.0))
    n = len(cls)
    return label_table(np.full(n, int(frame)), np.full(n, -1), cls, trunc, occ, numbers, path)


class KittiObject:
    """The frames of the KITTI object benchmark under ``root/<split>``.

    ``len`` is the number of frames (one per calibration file); ``ids`` their KITTI numbers in
    order; ``ds[i]`` / ``ds.frame(i)`` reads frame number ``i`` from disk as a
    :class:`~twistslam.datasets.Frame`: ``calib`` of that frame, ``objects_gt`` its labels,
    ``points_velo`` the raw scan, ``points_c`` the scan in the rectified camera frame
    (``X_c = R0_rect Tr_velo_to_cam X_velo``, intensity carried along), ``image_left`` the
    image; ``image_right`` and ``T_w_c_gt`` are ``None`` and ``timestamp`` is NaN.
    """

    def __init__(self, root: PathLike, split: str = "training") -> None:
        self.root = Path(root)
        self.split = split
        self.base = self.root / split
        calib_dir = self.base / "calib"
        if not calib_dir.is_dir():
            raise FileNotFoundError(
                errno.ENOENT, f"KITTI object calibration folder not found: {calib_dir}",
                str(calib_dir),
            )
        self.ids = sorted(int(p.stem) for p in calib_dir.glob("*.txt") if p.stem.isdigit())
        self._id_set = set(self.ids)
        self._warned: set[str] = set()
        for name in _FOLDERS:
            if not (self.base / name).is_dir():
                self._warn(name, f"{self.base / name} not found: frames of {self} will have "
                                 f"no {name}")

    def __repr__(self) -> str:
        return f"KittiObject({str(self.root)!r}, split={self.split!r})"

    def __len__(self) -> int:
        return len(self.ids)

    def _warn(self, key: str, message: str) -> None:
        if key not in self._warned:
            self._warned.add(key)
            warnings.warn(message, MissingDataWarning, stacklevel=3)

    def path(self, folder: str, index: int) -> Path:
        """File of frame ``index`` in ``folder`` (``calib``, ``label_2``, ``velodyne``,
        ``image_2``), whether or not it exists."""
        suffix = ".txt" if folder == "calib" else _FOLDERS[folder]
        return self.base / folder / f"{int(index):06d}{suffix}"

    def _file(self, folder: str, index: int) -> Path | None:
        if not (self.base / folder).is_dir():
            return None  # the whole folder is missing: warned once in __init__
        path = self.path(folder, index)
        if not path.is_file():
            raise FileNotFoundError(
                errno.ENOENT, f"{self}: frame {index:06d} has a calibration but no {folder} file",
                str(path),
            )
        return path

    def labels(self, index: int) -> ObjectTable | None:
        """Ground-truth objects of frame ``index`` (``None`` without a ``label_2`` folder)."""
        self._check(index)
        path = self._file("label_2", index)
        return read_object_labels(path, frame=index) if path is not None else None

    def _check(self, index: int) -> None:
        if not isinstance(index, (int, np.integer)) or isinstance(index, bool):
            raise TypeError(f"frame number must be an integer, got {type(index).__name__}")
        if int(index) not in self._id_set:
            have = (f"{len(self.ids)} frames, {self.ids[0]:06d}..{self.ids[-1]:06d}"
                    if self.ids else "no frames")
            raise IndexError(
                f"frame {int(index):06d} not in {self} ({have}): "
                f"{self.path('calib', index)} not found"
            )

    def __getitem__(self, index: int) -> Frame:
        return self.frame(index)

    def frame(self, index: int, *, lidar: bool = True, image: bool = True) -> Frame:
        """Frame number ``index``; ``lidar=False`` / ``image=False`` skip reading the scan /
        the image (those fields are then ``None``)."""
        self._check(index)
        i = int(index)
        calib = read_calibration(self.path("calib", i))
        points_velo = points_c = None
        velo = self._file("velodyne", i) if lidar else None
        if velo is not None:
            points_velo, points_c = scan_in_camera(read_velodyne(velo), calib.T_c_velo)
        image_path = self._file("image_2", i) if image else None
        return Frame(
            index=i,
            timestamp=float("nan"),
            image_left=read_image(image_path) if image_path is not None else None,
            image_right=None,
            points_c=points_c,
            points_velo=points_velo,
            calib=calib,
            T_w_c_gt=None,
            objects_gt=self.labels(i),
        )

    def __iter__(self) -> Iterator[Frame]:
        for i in self.ids:
            yield self.frame(i)
