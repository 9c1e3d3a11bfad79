"""``ObjectsResult``: the tracks of a run as numpy arrays, and their files."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..datasets import ObjectTable, write_tracking_results
from ..timings import Timings


@dataclass
class TrackedObject:
    """One track; row ``k`` of every per-frame array is dataset frame ``frames[k]``.

    Attributes
    ----------
    track_id : id written to the results (unique in the sequence).
    cls : class name (KITTI type).
    state : ``"confirmed"``, ``"lost"``, ``"tentative"`` or ``"dead"`` at the end of the run.
    link : ``"planar"`` (3 DoF on the ground plane) or ``"free"``.
    frames : (K,) consecutive frames from birth to the last frame kept alive, preceded by the
        ``backcast`` frames the output policy predicted before the first detection.
    T_w_o : (K, 4, 4) pose in the tracking frame (:attr:`ObjectsResult.frame`), after the
        sliding-window optimisation; object frame = box frame (x along the length, y down).
    size : (3,) length, width, height (m): per-dimension median of the detections.
    velocity_kmh : (K,) speed of the box centre in the tracking frame, km/h (in the camera
        frame this is the speed relative to the moving camera).
    detected : (K,) bool, a detection was associated in that frame (visual object tracking:
        the cluster was tracked in it, by its keypoints).
    reported : (K,) bool, the row is written to the results (output policy, docs/objects.md).
    score : (K,) score of the associated detection (0 where none); ``mean_score`` their mean.
    confidence : the track's confidence, the mean range-corrected score of its detections
        (``objects.range_score_*``): the score of its result rows, what ``min_track_score``
        compares.
    range : (K,) distance of the associated detection from the camera, m (0 where none).
    backcast : number of leading rows before the track's first frame: the detections
        tracker's predictions before its first detection; for visual object tracking, the
        frames before its cluster started where unused boxes followed it back
        (``lidar_objects.backfill_frames``), placed along its first motion.
    canonical : the object frame is a 3D box's frame (origin at the box centre, x along the
        length): always for the detections tracker; for visual object tracking once a 3D
        detection was associated (before that the box is fitted to the cluster's points).
    has_box : (K,) bool, a 3D detection was associated in that frame (None: same as
        ``detected``, the detections tracker).
    T_w_o_online : (K, 4, 4) the poses as the online tracking left them, before the final
        smoothing of visual object tracking (``visual_objects.final_smoothing``) replaced
        ``T_w_o``; None where there was no smoothing (then ``T_w_o`` is online).
    """

    track_id: int
    cls: str
    state: str
    link: str
    frames: np.ndarray
    T_w_o: np.ndarray
    size: np.ndarray
    velocity_kmh: np.ndarray
    detected: np.ndarray
    reported: np.ndarray
    score: np.ndarray
    mean_score: float
    confidence: float = 0.0
    range: np.ndarray | None = None
    backcast: int = 0
    canonical: bool = True
    has_box: np.ndarray | None = None
    T_w_o_online: np.ndarray | None = None

    def __repr__(self) -> str:
        return (f"TrackedObject(id={self.track_id}, {self.cls}, {self.state}, frames "
                f"{self.frames[0]}-{self.frames[-1]}, {int(self.detected.sum())} detected)")


@dataclass
class ObjectsResult:
    """Output of :func:`twistslam.track_detections` on one sequence.

    Attributes
    ----------
    objects : every track ever confirmed (never-confirmed tentative tracks are left out).
    tracking : the reported boxes as an ObjectTable in each frame's camera frame, one row per
        (frame, track), score = the track's confidence: what ``tracking/SEQ.txt`` holds before
        ``min_track_score`` is applied.
    frame : ``"world"`` (camera poses known: world = camera of the first frame) or
        ``"camera"`` (each frame's camera frame, as AB3DMOT).
    min_track_score : the threshold applied when writing ``tracking/SEQ.txt``.
    timings : per-frame tracker time (``track`` stage: the C++ step, ms).
    """

    objects: list[TrackedObject]
    tracking: ObjectTable
    frame: str
    seq: str
    num_frames: int
    timings: Timings = field(default_factory=Timings)
    min_track_score: float = -np.inf
    config: object = None

    def __len__(self) -> int:
        return len(self.objects)

    def __repr__(self) -> str:
        return (f"ObjectsResult(seq={self.seq!r}, frame={self.frame!r}, tracks={len(self)}, "
                f"boxes={len(self.tracking)}, {self.frames_per_second:.0f} frames/s)")

    @property
    def frames_per_second(self) -> float:
        """Frames per second of the tracker alone (sum of the per-frame step times)."""
        total = float(np.nansum(self.timings.frame_ms))
        return len(self.timings.frame_ms) / (total / 1e3) if total > 0 else float("nan")

    def thresholded(self) -> ObjectTable:
        """The rows of tracks whose confidence is at least ``min_track_score``."""
        return self.tracking.select(self.tracking.score >= self.min_track_score)

    def save(self, out_dir: str | Path) -> dict[str, Path]:
        """Write ``tracking/SEQ.txt`` (thresholded at ``min_track_score``),
        ``tracking_all/SEQ.txt`` (every reported box, for sAMOTA), ``objects.npz`` (the
        per-track arrays), ``timings.json`` and ``config.yaml``; returns ``{what: path}``."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = {"tracking": out / "tracking" / f"{self.seq}.txt",
                 "tracking_all": out / "tracking_all" / f"{self.seq}.txt",
                 "objects": out / "objects.npz", "timings": out / "timings.json"}
        write_tracking_results(paths["tracking"], self.thresholded())
        write_tracking_results(paths["tracking_all"], self.tracking)
        arrays = {}
        for o in self.objects:
            for name in ("frames", "T_w_o", "size", "velocity_kmh", "detected", "reported", "score"):
                arrays[f"{o.track_id}/{name}"] = getattr(o, name)
        np.savez_compressed(paths["objects"], frame=np.array(self.frame), **arrays)
        summary = self.timings.summary()
        summary["frames_per_second"] = round(self.frames_per_second, 1)
        summary["tracking_frame"] = self.frame
        paths["timings"].write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
        if self.config is not None:
            paths["config"] = out / "config.yaml"
            self.config.to_yaml(paths["config"])
        return paths
