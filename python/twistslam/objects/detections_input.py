"""Precomputed 3D detections of a sequence, checked before they reach the tracker.

A detections *source* is one of

- a folder holding ``SEQ.txt`` in the PointRCNN comma format (what AB3DMOT ships), or in the
  KITTI tracking result format (space separated, 17-18 columns; track ids are ignored), or a
  sub-folder ``SEQ/`` of KITTI object result files ``NNNNNN.txt`` (one per frame, 15-16
  columns, no frame column);
- one such file;
- an :class:`~twistslam.datasets.ObjectTable` already in memory.

Checks (errors name the file and line): a non-finite number is an error; a box with a
non-positive size is skipped with one warning naming the file, the lines and the count; a
frame outside the sequence is an error; frames out of order are sorted with one warning; a
missing file is an error; an empty file gives no detections and one warning.
"""

from __future__ import annotations

import errno
import warnings
from pathlib import Path

import numpy as np

from ..datasets import ObjectTable, read_detection_file
from ..datasets._parsing import iter_lines, parse_error
from ..datasets.kitti_object import read_object_labels

DetectionSource = str | Path | ObjectTable


class DetectionWarning(UserWarning):
    """A detection file has rows that were skipped or reordered."""


def _read_object_results(folder: Path) -> tuple[ObjectTable, list[tuple[Path, int]]]:
    """KITTI object result files ``NNNNNN.txt`` of one sequence, frame = file number."""
    tables, where = [], []
    for path in sorted(folder.glob("*.txt")):
        if path.stem.isdigit():
            tables.append(read_object_labels(path, frame=int(path.stem)))
            where += _line_numbers(path)
    return ObjectTable.concat(tables), where


def _line_numbers(path: Path) -> list[tuple[Path, int]]:
    return [(path, line_no) for line_no, _ in iter_lines(path)]


def _read_file(path: Path) -> tuple[ObjectTable, list[tuple[Path, int]]]:
    return read_detection_file(path), _line_numbers(path)


def _locate(source: Path, seq: str) -> Path:
    if source.is_file():
        return source
    for candidate in (source / f"{seq}.txt", source / seq):
        if candidate.exists():
            return candidate
    raise FileNotFoundError(errno.ENOENT, f"no detections for sequence {seq} in {source} "
                            f"(expected {seq}.txt or a folder {seq}/ of NNNNNN.txt)", str(source))


def load_detections(source: DetectionSource, seq: str, num_frames: int | None = None,
                    classes: list[str] | None = None) -> ObjectTable:
    """Detections of sequence ``seq`` from ``source``, checked, sorted by frame.

    Parameters
    ----------
    source : folder, file or ObjectTable (see the module docstring).
    seq : sequence name, e.g. ``"0001"`` (picks ``SEQ.txt`` / ``SEQ/`` in a folder).
    num_frames : frames of the sequence; a detection at a frame >= this is an error.
    classes : keep only these classes (KITTI names); None keeps all.
    """
    if isinstance(source, ObjectTable):
        table, where = source, [(Path(source.source or "<table>"), i + 1) for i in range(len(source))]
    else:
        path = _locate(Path(source), seq)
        table, where = _read_object_results(path) if path.is_dir() else _read_file(path)
        if len(table) == 0:
            warnings.warn(f"{path}: no detections", DetectionWarning, stacklevel=2)
    values = np.column_stack([table.box_3d, table.score])
    bad = ~np.isfinite(values).all(axis=1)
    if bad.any():
        file, line = where[int(np.flatnonzero(bad)[0])]
        raise parse_error(file, line, "a box value or the score is not finite (NaN or Inf)")
    frame_limit = num_frames if num_frames is not None else np.inf
    outside = (table.frame < 0) | (table.frame >= frame_limit)
    if outside.any():
        k = int(np.flatnonzero(outside)[0])
        file, line = where[k]
        raise parse_error(file, line, f"frame {table.frame[k]} is outside the sequence "
                          f"(frames 0-{num_frames - 1})")
    degenerate = (table.box_3d[:, 3:6] <= 0).any(axis=1)
    if degenerate.any():
        lines = [where[k] for k in np.flatnonzero(degenerate)]
        shown = ", ".join(str(line) for _, line in lines[:5]) + (" ..." if len(lines) > 5 else "")
        warnings.warn(f"{lines[0][0]}: skipped {len(lines)} detection(s) with a non-positive "
                      f"size (lines {shown})", DetectionWarning, stacklevel=2)
        table = table.select(~degenerate)
    if np.any(np.diff(table.frame) < 0):
        warnings.warn(f"{table.source or source}: frames are not in order; sorted",
                      DetectionWarning, stacklevel=2)
    table = table.select(np.argsort(table.frame, kind="stable"))
    if classes is not None:
        table = table.select(np.isin(table.cls, classes))
    return table
