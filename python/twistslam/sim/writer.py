"""Files of a simulated sequence, in the KITTI tracking layout plus the documented extras.

Per-frame files go to ``OUT/training/<folder>/SEQ/NNNNNN.<ext>``, per-sequence files to
``OUT/training/<folder>/SEQ.txt``; oracle detections mirror the real data's detections/ layout at
``OUT/detections/oracle/SEQ.txt``. The reuse of :mod:`twistslam.datasets` writers keeps
calibration, poses, oxts, labels and scans byte-compatible with the reader.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import asdict
from pathlib import Path

import numpy as np

from twistslam.datasets import write_calibration, write_labels, write_oxts, write_poses, write_velodyne
from twistslam.datasets.objects import ObjectTable

from .mesh import write_ply
from twistslam.datasets.png16 import write_png, write_png16

FRAME_FOLDERS = {"image_02": ".png", "image_03": ".png", "velodyne": ".bin", "velodyne_labels": ".label",
                 "panoptic": ".png", "flow_occ": ".png", "flow_noc": ".png", "disparity": ".png"}
SEQUENCE_FILES = ("calib", "oxts", "poses", "label_02", "object_poses", "sim")


class SequenceWriter:
    def __init__(self, out: str | Path, seq: str, overwrite: bool, compression: int) -> None:
        self.root = Path(out)
        self.base = self.root / "training"
        self.seq = seq
        self.level = compression
        if self.root.exists() and any(self.root.iterdir()):
            if not overwrite:
                raise FileExistsError(f"{self.root} is not empty; pass overwrite=True (--overwrite) to replace "
                                      f"sequence {seq} in it")
            self._remove_sequence()
        self.base.mkdir(parents=True, exist_ok=True)

    def _remove_sequence(self) -> None:
        """Delete this sequence's files only (other sequences in OUT stay)."""
        for folder in (*FRAME_FOLDERS, "meshes"):
            shutil.rmtree(self.base / folder / self.seq, ignore_errors=True)
        for folder in SEQUENCE_FILES:
            for ext in (".txt", ".json"):
                (self.base / folder / f"{self.seq}{ext}").unlink(missing_ok=True)
        (self.root / "detections" / "oracle" / f"{self.seq}.txt").unlink(missing_ok=True)

    def frame_path(self, folder: str, n: int) -> Path:
        path = self.base / folder / self.seq / f"{n:06d}{FRAME_FOLDERS[folder]}"
        path.parent.mkdir(parents=True, exist_ok=True)
        return path

    def seq_path(self, folder: str, ext: str = ".txt") -> Path:
        path = self.base / folder / f"{self.seq}{ext}"
        path.parent.mkdir(parents=True, exist_ok=True)
        return path

    # ------------------------------------------------------------------------ per frame
    def image(self, folder: str, n: int, rgb: np.ndarray) -> None:
        write_png(self.frame_path(folder, n), rgb, self.level)

    def png16(self, folder: str, n: int, values: np.ndarray) -> None:
        write_png16(self.frame_path(folder, n), values, self.level)

    def scan(self, n: int, points: np.ndarray, labels: np.ndarray | None) -> None:
        write_velodyne(self.frame_path("velodyne", n), points)
        if labels is not None:
            labels.astype("<u4").tofile(self.frame_path("velodyne_labels", n))

    # --------------------------------------------------------------------- per sequence
    def sequence(self, calib, T_w_c: np.ndarray, labels: ObjectTable, object_poses: list[str], config) -> None:
        write_calibration(self.seq_path("calib"), calib)
        write_poses(self.seq_path("poses"), T_w_c)
        write_oxts(self.seq_path("oxts"), T_w_c, calib)
        write_labels(self.seq_path("label_02"), labels)
        self.seq_path("object_poses").write_text("".join(line + "\n" for line in object_poses), encoding="utf-8")
        text = json.dumps(asdict(config), indent=1, sort_keys=True, default=list)
        self.seq_path("sim", ".json").write_text(text + "\n", encoding="utf-8")

    def detections(self, lines: list[str]) -> None:
        path = self.root / "detections" / "oracle" / f"{self.seq}.txt"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("".join(line + "\n" for line in lines), encoding="utf-8")

    def meshes(self, entries: list[tuple[int, str, object, dict]]) -> None:
        """``(track_id, class, mesh, shape parameters)`` -> ``meshes/SEQ/TTTTTT.ply`` + shapes.json."""
        folder = self.base / "meshes" / self.seq
        shapes = {}
        for track, cls, mesh, params in entries:
            write_ply(folder / f"{track:06d}.ply", mesh)
            shapes[f"{track:06d}"] = {"class": cls, **params}
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "shapes.json").write_text(json.dumps(shapes, indent=1, sort_keys=True) + "\n", encoding="utf-8")
