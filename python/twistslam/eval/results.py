"""Reading a results directory: ``camera_poses.txt`` and/or ``tracking/XXXX.txt``."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..datasets import ObjectTable, read_poses, read_tracking_results

CAMERA_POSES = "camera_poses.txt"
TRACKING_DIR = "tracking"


class ResultsNotFoundError(FileNotFoundError):
    """A results directory holds nothing the evaluator can use."""


def seq_name(seq: int | str) -> str:
    """KITTI's four-digit sequence name: ``1``, ``"1"`` and ``"0001"`` all give ``"0001"``."""
    try:
        return f"{int(seq):04d}"
    except ValueError:
        raise ValueError(f"sequence must be a number such as 0001, got {seq!r}") from None


@dataclass
class SequenceResults:
    """What a system wrote for one sequence; either part may be absent (None)."""

    camera_poses: np.ndarray | None  # (N, 4, 4) T_w_c, NaN rows for frames without output
    tracking: ObjectTable | None
    camera_path: Path | None
    tracking_path: Path | None


def check_unique_ids(table: ObjectTable) -> None:
    """A track id may appear once per frame (as the devkit requires): two boxes claiming
    to be the same object in one frame make ID switches meaningless."""
    tracked = table.track_id >= 0
    keys = np.stack([table.frame[tracked], table.track_id[tracked]], axis=1)
    uniq, counts = np.unique(keys, axis=0, return_counts=True)
    if len(uniq) and counts.max() > 1:
        frame, tid = uniq[np.argmax(counts)]
        raise ValueError(f"{table.source}: track id {tid} appears {counts.max()} times in "
                         f"frame {frame}; a track id must be unique within a frame")


def load_results(results_dir: str | Path, seq: int | str) -> SequenceResults:
    """Read ``results_dir/camera_poses.txt`` and ``results_dir/tracking/<seq>.txt``.

    Raises
    ------
    ResultsNotFoundError
        When the directory does not exist or holds neither file.
    ValueError
        ``"<file>:<line>: ..."`` for a malformed line (from the dataset readers), or a
        track id repeated within one frame.
    """
    root = Path(results_dir)
    if not root.is_dir():
        raise ResultsNotFoundError(f"results directory not found: {root}")
    camera_path = root / CAMERA_POSES
    tracking_path = root / TRACKING_DIR / f"{seq_name(seq)}.txt"
    has_camera, has_tracking = camera_path.is_file(), tracking_path.is_file()
    if not (has_camera or has_tracking):
        raise ResultsNotFoundError(
            f"{root} holds no results for sequence {seq_name(seq)}: expected "
            f"{camera_path} (camera poses, one row-major 3x4 T_w_c per line) and/or "
            f"{tracking_path} (objects, KITTI tracking format)"
        )
    tracking = read_tracking_results(tracking_path) if has_tracking else None
    if tracking is not None:
        check_unique_ids(tracking)
    return SequenceResults(
        camera_poses=read_poses(camera_path) if has_camera else None,
        tracking=tracking,
        camera_path=camera_path if has_camera else None,
        tracking_path=tracking_path if has_tracking else None,
    )
