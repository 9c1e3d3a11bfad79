"""A KITTI tracking sequence, read lazily frame by frame.

Layout (the KITTI tracking download, plus two optional extras)::

    <root>/<split>/calib/XXXX.txt            required
    <root>/<split>/image_02/XXXX/NNNNNN.png  left colour images
    <root>/<split>/image_03/XXXX/NNNNNN.png  right colour images
    <root>/<split>/velodyne/XXXX/NNNNNN.bin  LiDAR scans
    <root>/<split>/label_02/XXXX.txt         ground-truth objects
    <root>/<split>/oxts/XXXX.txt             GPS/IMU -> ground-truth camera poses
    <root>/<split>/poses/XXXX.txt            ground-truth camera poses (preferred over oxts)
    <root>/<split>/timestamps/XXXX.txt       seconds, one per line (default: 0.1 s per frame)

Any part but the calibration may be missing (the testing split has no labels, partial
downloads lack LiDAR): the frame field is then ``None`` and a :class:`MissingDataWarning`
names the missing path once per modality.
"""

from __future__ import annotations

import errno
import math
import logging
import os
import warnings
from collections.abc import Iterator
from functools import cached_property
from pathlib import Path

import numpy as np

from ._parsing import PathLike
from .calibration import read_calibration
from .frame import Frame
from .labels import read_labels
from .objects import ObjectTable
from .oxts import read_oxts_poses
from .poses import read_poses
from .tracks import ObjectTrack, object_tracks
from .sensors import MissingDataWarning, read_image, read_timestamps, read_velodyne, scan_in_camera

log = logging.getLogger(__name__)

FRAME_PERIOD = 0.1  # s, KITTI records at 10 Hz
#: deg, upward: the HDL-64 elevation error of KITTI scans (cpp/lidar/kitti_scan_correction.hpp);
#: with it, stereo-vs-LiDAR disparities on the road agree with those above it (measured on
#: 0001: -0.63 px on both, against -0.1..-0.5 px varying with range on the road without it)
KITTI_VERTICAL_OFFSET_DEG = 0.205
_SENSORS = {"image_02": ".png", "image_03": ".png", "velodyne": ".bin"}


class KittiTracking:
    """Sequence ``seq`` of the KITTI tracking benchmark under ``root/<split>``.

    Frames are read from disk on each ``seq[i]``; only the calibration, the file listings and
    (on first use) the small ground-truth text files are read up front. ``len`` is the
    largest frame index found in any source (images, LiDAR, labels, poses/oxts) plus one.

    ``lidar_vertical_offset_deg``: every LiDAR return is rotated up by this angle about the
    horizontal axis ``p x z`` when read (KITTI's HDL-64 beams point ~0.205 deg lower than its
    calibration says; KISS-ICP's KITTI reader applies the same correction). ``None`` (default)
    = 0.205 deg for real KITTI, 0 for the simulator's exact scans (``<split>/sim/<seq>.json``).
    """

    def __init__(self, root: PathLike, seq: int | str, split: str = "training", *,
                 lidar_vertical_offset_deg: float | None = None) -> None:
        self.root = Path(root)
        self.split = split
        self.seq = f"{int(seq):04d}"
        self.base = self.root / split
        if lidar_vertical_offset_deg is None:
            lidar_vertical_offset_deg = 0.0 if self.is_simulated else KITTI_VERTICAL_OFFSET_DEG
        if not math.isfinite(lidar_vertical_offset_deg) or abs(lidar_vertical_offset_deg) > 5:
            raise ValueError(f"lidar_vertical_offset_deg = {lidar_vertical_offset_deg}: must be "
                             "finite and within +-5 deg")
        self.lidar_vertical_offset_deg = float(lidar_vertical_offset_deg)
        calib_path = self.base / "calib" / f"{self.seq}.txt"
        if not calib_path.is_file():
            raise FileNotFoundError(
                errno.ENOENT, f"KITTI calibration file not found: {calib_path}", str(calib_path)
            )
        self.calib = read_calibration(calib_path)
        self._warned: set[str] = set()
        # frame index -> file, per sensor; None when the whole folder is missing
        self._files: dict[str, dict[int, Path] | None] = {}
        for name, ext in _SENSORS.items():
            self._files[name] = self._scan(name, ext)

    @property
    def is_simulated(self) -> bool:
        """The simulator writes ``<split>/sim/<seq>.json`` beside its sequences."""
        return (self.base / "sim" / f"{self.seq}.json").is_file()

    @classmethod
    def from_path(cls, path: PathLike) -> "KittiTracking":
        """Open the sequence that ``path`` points into: ``<root>/<split>/<seq>``, a sensor
        folder ``<root>/<split>/image_02/<seq>`` or a file ``<root>/<split>/calib/<seq>.txt``."""
        path = Path(path)
        if not path.stem.isdigit():
            raise ValueError(f"{path}: cannot tell the sequence number (expected e.g. .../0001)")
        for split_dir in (path.parent, path.parent.parent):
            if (split_dir / "calib").is_dir():
                return cls(split_dir.parent, path.stem, split=split_dir.name)
        raise ValueError(f"{path}: no calib/ folder beside it or its parent; not a KITTI sequence")

    def _path(self, name: str) -> Path:
        return self.base / name / f"{self.seq}.txt"

    def _warn_once(self, key: str, message: str) -> None:
        if key not in self._warned:
            self._warned.add(key)
            # stacklevel: point at the user's line (user -> method -> helper -> here)
            warnings.warn(message, MissingDataWarning, stacklevel=4)

    def _scan(self, name: str, ext: str) -> dict[int, Path] | None:
        folder = self.base / name / self.seq
        if not folder.is_dir():
            self._warn_once(name, f"{folder} not found: frames of {self} will have no {name}")
            return None
        files = {}
        for entry in os.scandir(folder):
            stem, suffix = os.path.splitext(entry.name)
            if suffix == ext and stem.isdigit():
                files[int(stem)] = Path(entry.path)
        return files

    def __repr__(self) -> str:
        return f"KittiTracking({str(self.root)!r}, {self.seq!r}, split={self.split!r})"

    # ------------------------------------------------------------------ sequence-level data
    @cached_property
    def gt_objects(self) -> ObjectTable | None:
        """All ground-truth objects of the sequence (``label_02``), or None without labels."""
        path = self._path("label_02")
        if not path.is_file():
            log.info("%s: no labels at %s", self, path)
            return None
        return read_labels(path)

    @cached_property
    def gt_poses(self) -> np.ndarray | None:
        """Ground-truth ``T_w_c`` (N, 4, 4): ``poses/`` if present, else from ``oxts/``."""
        if self._path("poses").is_file():
            return read_poses(self._path("poses"))
        if self._path("oxts").is_file():
            return read_oxts_poses(self._path("oxts"), self.calib)
        log.info("%s: no ground-truth poses (neither poses/ nor oxts/)", self)
        return None

    @cached_property
    def gt_tracks(self) -> dict[int, ObjectTrack] | None:
        """Ground-truth object tracks keyed by track id: world-frame poses ``T_w_o``, sizes,
        class, truncation and occlusion per frame (in each frame's camera frame when the
        sequence has no ground-truth camera poses)."""
        if self.gt_objects is None:
            return None
        return object_tracks(self.gt_objects, self.gt_poses)

    @cached_property
    def _length(self) -> int:
        # Largest frame index any source knows of, + 1. The sources agree on a full download;
        # on a partial one (a few images, labels for all frames) the union keeps every frame.
        counts = [max(files) + 1 for files in self._files.values() if files]
        if self.gt_objects is not None and len(self.gt_objects):
            counts.append(int(self.gt_objects.frame.max()) + 1)
        if self.gt_poses is not None:
            counts.append(len(self.gt_poses))
        return max(counts, default=0)

    def __len__(self) -> int:
        return self._length

    @cached_property
    def timestamps(self) -> np.ndarray:
        """Seconds per frame: ``timestamps/XXXX.txt`` if present, else ``0.1 * index``."""
        path = self._path("timestamps")
        if not path.is_file():
            return np.arange(len(self), dtype=np.float64) * FRAME_PERIOD
        times = read_timestamps(path)
        if len(times) < len(self):
            raise ValueError(f"{path}: {len(times)} timestamps for {len(self)} frames")
        return times

    # ------------------------------------------------------------------------- frame access
    def _sensor_file(self, name: str, index: int) -> Path | None:
        files = self._files[name]
        if files is None:
            return None  # whole folder missing, reported in __init__
        path = files.get(index)
        if path is None:
            expected = self.base / name / self.seq / f"{index:06d}{_SENSORS[name]}"
            self._warn_once(
                name + "/file",
                f"{expected} not found: that frame has no {name} "
                f"(further missing {name} files of {self} are not reported)",
            )
        return path

    def __getitem__(self, index: int) -> Frame:
        return self.frame(index)

    def frame(self, index: int, *, lidar: bool = True) -> Frame:
        """Frame ``index``; ``lidar=False`` leaves ``points_c``/``points_velo`` as ``None``
        without reading the scan (the stereo pipeline's loader: a KITTI scan costs about as
        much to read and transform as one image to decode)."""
        n = len(self)
        if not isinstance(index, (int, np.integer)):
            raise TypeError(f"frame index must be an integer, got {type(index).__name__}")
        if not -n <= index < n:
            raise IndexError(f"frame {index} out of range for {self} with {n} frames")
        i = int(index) % n

        left = self._sensor_file("image_02", i)
        right = self._sensor_file("image_03", i)
        velo = self._sensor_file("velodyne", i) if lidar else None
        points_velo = points_c = None
        if velo is not None:
            # X_c = R_rect Tr_velo_cam X_velo (docs/design.md); intensity carried along
            points_velo, points_c = scan_in_camera(read_velodyne(velo), self.calib.T_c_velo,
                                                   self.lidar_vertical_offset_deg)
        poses, objects = self.gt_poses, self.gt_objects
        return Frame(
            index=i,
            timestamp=float(self.timestamps[i]),
            image_left=read_image(left) if left is not None else None,
            image_right=read_image(right) if right is not None else None,
            points_c=points_c,
            points_velo=points_velo,
            calib=self.calib,
            T_w_c_gt=poses[i].copy() if poses is not None and i < len(poses) else None,
            objects_gt=objects.in_frame(i) if objects is not None else None,
        )

    def __iter__(self) -> Iterator[Frame]:
        for i in range(len(self)):
            yield self[i]
