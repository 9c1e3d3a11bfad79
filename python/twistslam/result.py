"""``Result``: everything a run produced, as numpy arrays, and its files."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .config import Config
from .datasets import write_poses
from .timings import Timings

if TYPE_CHECKING:
    from .objects.visual import VisualObjects

#: file names inside a results directory (camera_poses.txt is what ``twistslam eval`` reads)
FILES = {"camera_poses": "camera_poses.txt", "timings": "timings.json",
         "config": "config.yaml", "status": "status.txt"}


@dataclass
class Result:
    """Output of :func:`twistslam.run` on one sequence; row ``k`` is frame ``frames[k]``.

    Attributes
    ----------
    camera_poses : (N, 4, 4) float64 ``T_w_c``, world = camera at the first tracked frame;
        the final trajectory, refined through the keyframes after bundle adjustment. Lost
        frames hold the predicted pose.
    tracked_poses : (N, 4, 4) the poses as each ``track`` call returned them (online).
    status : (N,) str, ``"initialized"``, ``"ok"``, ``"lost"`` or ``"relocalized"``.
    frames : (N,) int, dataset frame index of each row.
    is_keyframe : (N,) bool.
    num_inliers : (N,) int, static points that supported the pose.
    timings : per-frame stage times (:class:`~twistslam.timings.Timings`).
    keyframes : ``frame_index`` (K,), ``T_w_c`` (K, 4, 4) after local BA.
    map_points : ``X_w`` (M, 3), ``cluster_id`` (M,), ``num_observations`` (M,).
    objects : the object clusters (list-like of
        :class:`~twistslam.objects.result.TrackedObject`, plus ``tracking``, the boxes in the
        KITTI tracking format); ``None`` or empty without segmentation.
    config : the resolved settings of the run.
    seq : sequence name, when known.
    """

    camera_poses: np.ndarray
    status: np.ndarray
    frames: np.ndarray
    is_keyframe: np.ndarray
    num_inliers: np.ndarray
    timings: Timings
    tracked_poses: np.ndarray | None = None  # (N, 4, 4) as each track() call returned them
    keyframes: dict[str, np.ndarray] = field(default_factory=dict)
    map_points: dict[str, np.ndarray] = field(default_factory=dict)
    config: Config = field(default_factory=Config)
    seq: str | None = None
    #: px the run added to every stereo disparity (config lidar.disparity_offset; "auto" is
    #: estimated from the first frame's scan) and where it came from
    disparity_offset: float | None = None
    disparity_offset_source: str = ""
    #: the object clusters tracked in the SLAM (:class:`~twistslam.objects.VisualObjects`;
    #: empty without a segmentation source) and the perception sources the run used
    objects: "VisualObjects | None" = None
    segmentation: str = "none"
    flow: str = "none"
    detector: str = "none"

    def __len__(self) -> int:
        return len(self.frames)

    @property
    def num_lost(self) -> int:
        return int(np.count_nonzero(self.status == "lost"))

    def __repr__(self) -> str:
        return (f"Result(seq={self.seq!r}, frames={len(self)}, lost={self.num_lost}, "
                f"keyframes={int(self.is_keyframe.sum())}, hz={self.timings.hz:.1f})")

    def save(self, out_dir: str | Path) -> dict[str, Path]:
        """Write the results directory; returns ``{what: path}``.

        - ``camera_poses.txt``: one row-major 3x4 ``T_w_c`` per line, line ``i`` = dataset
          frame ``i`` (NaN rows before the first tracked frame), as ``twistslam eval`` reads.
        - ``timings.json``: :meth:`Timings.summary`.
        - ``config.yaml``: the resolved config (``Config.from_yaml`` reads it back).
        - ``status.txt``: ``<frame index> <status>`` per tracked frame.
        """
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = {name: out / file for name, file in FILES.items()}
        rows = int(self.frames.max()) + 1 if len(self.frames) else 0
        poses = np.full((rows, 4, 4), np.nan)
        poses[self.frames] = self.camera_poses
        write_poses(paths["camera_poses"], poses)
        paths["timings"].write_text(json.dumps(self.timings.summary(), indent=2) + "\n",
                                    encoding="utf-8")
        self.config.to_yaml(paths["config"])
        paths["status"].write_text(
            "".join(f"{i} {s}\n" for i, s in zip(self.frames, self.status)), encoding="utf-8")
        if self.objects is not None and self.seq is not None:
            paths.update(self.objects.save(out, self.seq))
        return paths
