"""3D multi-object tracking from detections: the C++ tracker (cpp/objects) driven over a
sequence, its tracks turned into numpy arrays and KITTI tracking results.

>>> result = twistslam.track_detections(("data/kitti", "0001"), "detections/")  # doctest: +SKIP
>>> result.objects[0].T_w_o.shape, result.frame                                # doctest: +SKIP
((54, 4, 4), 'world')
>>> result.save("results")      # results/tracking/0001.txt, as `twistslam eval` reads it
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from .. import _core
from ..config import Config
from ..datasets import ObjectTable, Sequence, open_sequence
from ..timings import Timings
from .detections_input import DetectionSource, load_detections
from .result import ObjectsResult, TrackedObject

_o = _core.objects
SequenceLike = Sequence | str | Path | tuple[Any, Any]
FRAME_PERIOD = 0.1  # s, KITTI's 10 Hz when the sequence gives no timestamps


class ObjectTracker:
    """Frame-by-frame face of the C++ tracker for a user's own loop.

    >>> tracker = ObjectTracker(Config().objects)                        # doctest: +SKIP
    >>> tracker.step(0, np.eye(4), detections_of_frame_0)                 # doctest: +SKIP
    """

    def __init__(self, config=None) -> None:
        self.config = config if config is not None else Config().objects
        self.class_ids = {name: k for k, name in enumerate(self.config.classes)}
        self._tracker = _o.Tracker(self.config.tracker_options())

    def step(self, frame: int, T_w_c: np.ndarray, detections: ObjectTable) -> float:
        """Track one frame's detections (camera frame boxes); returns the C++ time in ms.
        Classes not in ``config.classes`` are ignored."""
        keep = np.isin(detections.cls, list(self.class_ids))
        det = detections.select(keep)
        ids = np.array([self.class_ids[c] for c in det.cls], dtype=np.int64)
        planar = np.isin(det.cls, self.config.planar_classes)
        start = time.perf_counter()
        self._tracker.step(int(frame), T_w_c, det.box_3d, det.score, ids, planar)
        return (time.perf_counter() - start) * 1e3

    def tracks(self) -> list[dict]:
        """Every track of the C++ tracker as a dict of arrays (see ``_core.objects.Tracker``)."""
        return self._tracker.tracks()


def _open(seq_or_path: SequenceLike) -> Sequence:
    if isinstance(seq_or_path, tuple):
        return open_sequence(*seq_or_path)
    if isinstance(seq_or_path, (str, Path)):
        return open_sequence(seq_or_path)
    return seq_or_path


def _image_size(seq: Sequence) -> tuple[int, int]:
    """(width, height) of the left images when the sequence has them, else (0, 0): 2D boxes
    are then not clipped to the image."""
    base, name = getattr(seq, "base", None), getattr(seq, "seq", None)
    if base is None:
        return 0, 0
    files = sorted((Path(base) / "image_02" / str(name)).glob("*.png"))[:1]
    if not files:
        return 0, 0
    from PIL import Image

    with Image.open(files[0]) as image:
        return image.size


def _camera_poses(seq: Sequence, config, num_frames: int, camera_poses) -> tuple[np.ndarray, str]:
    frame = config.frame
    if frame not in ("auto", "world", "camera"):
        raise ValueError(f"objects.frame = {frame!r}: choose auto, world or camera")
    poses = camera_poses if camera_poses is not None else getattr(seq, "gt_poses", None)
    if frame == "camera" or (frame == "auto" and poses is None):
        return np.tile(np.eye(4), (num_frames, 1, 1)), "camera"
    if poses is None:
        raise ValueError(f"{seq}: objects.frame = 'world' needs camera poses (oxts/ or poses/ "
                         "in the sequence, or the camera_poses argument)")
    poses = np.asarray(poses, dtype=np.float64)
    if poses.ndim != 3 or poses.shape[1:] != (4, 4) or len(poses) < num_frames:
        raise ValueError(f"camera poses: expected ({num_frames}, 4, 4), got {poses.shape}")
    if not np.isfinite(poses[:num_frames]).all():
        raise ValueError("camera poses: non-finite values; use objects.frame = 'camera'")
    return poses[:num_frames], "world"


def _camera_frame_boxes(T_c_w: np.ndarray, T_w_o: np.ndarray, size: np.ndarray) -> np.ndarray:
    """(K, 7) boxes [cx, cy, cz, l, w, h, ry] of poses T_w_o seen from cameras T_c_w."""
    T_c_o = T_c_w @ T_w_o
    R = T_c_o[:, :3, :3]
    ry = np.arctan2(R[:, 0, 2], R[:, 0, 0])
    return np.column_stack([T_c_o[:, :3, 3], np.tile(size, (len(T_c_o), 1)), ry])


def in_image(box_2d: np.ndarray) -> np.ndarray:
    """(N,) bool: rows of projected boxes ``[x1, y1, x2, y2]`` (clipped to the image when its
    size is known) that are finite and keep an area. NaN: every corner behind the camera; no
    area: the box lies wholly beside the image. Either way the object is not in the left image,
    which is all that KITTI labels: such a row is a false positive (or a poor match of a car at
    the image's edge), and is not written
    (validation split, detections tracker at track score >= 4: FP 285 -> 273, FN unchanged;
    docs/objects.md)."""
    box_2d = np.asarray(box_2d, dtype=np.float64).reshape(-1, 4)
    return (np.isfinite(box_2d).all(axis=1) & (box_2d[:, 2] > box_2d[:, 0])
            & (box_2d[:, 3] > box_2d[:, 1]))


def _speed_kmh(T_w_o: np.ndarray, period: float) -> np.ndarray:
    if len(T_w_o) < 2:
        return np.zeros(len(T_w_o))
    velocity = np.gradient(T_w_o[:, :3, 3], period, axis=0)
    return np.linalg.norm(velocity, axis=1) * 3.6


def _results(tracks: list[dict], names: list[str], T_w_c: np.ndarray, calib, image_size,
             period: float) -> tuple[list[TrackedObject], ObjectTable]:
    from .. import geometry

    objects, tables = [], []
    T_c_w = np.linalg.inv(T_w_c)
    for t in tracks:
        if t["confirmed_frame"] < 0:
            continue
        cls = names[t["class_id"]]
        reported = t["reported"].copy()
        rows = np.flatnonzero(reported)
        frames = t["frames"][rows]
        box_3d = _camera_frame_boxes(T_c_w[frames], t["T_w_o"][rows], t["size"])
        if calib is not None:
            box_2d = geometry.project_boxes(box_3d, calib.P2, *image_size)
            visible = in_image(box_2d)
        else:  # no calibration: the devkit's "no 2D box" placeholder
            box_2d = np.full((len(rows), 4), -1.0)
            visible = box_3d[:, 2] > 0
        # A predicted box behind the camera (a wild extrapolation) or beside the image is no
        # observation: the output policy drops it rather than write an unreadable line.
        reported[rows[~visible]] = False
        rows, frames, box_3d, box_2d = rows[visible], frames[visible], box_3d[visible], box_2d[visible]
        objects.append(TrackedObject(
            track_id=t["id"], cls=cls, state=t["state"], link=t["link"], frames=t["frames"],
            T_w_o=t["T_w_o"], size=t["size"], velocity_kmh=_speed_kmh(t["T_w_o"], period),
            detected=t["detected"], reported=reported, score=t["score"],
            mean_score=t["mean_score"], confidence=t["confidence"], range=t["range"],
            backcast=t["backcast"]))
        if not len(rows):
            continue
        alpha = box_3d[:, 6] - np.arctan2(box_3d[:, 0], box_3d[:, 2])
        n = len(rows)
        tables.append(ObjectTable(
            frame=frames, track_id=np.full(n, t["id"]), cls=np.full(n, cls),
            truncation=np.full(n, -1.0), occlusion=np.full(n, -1),
            alpha=np.arctan2(np.sin(alpha), np.cos(alpha)), box_2d=box_2d, box_3d=box_3d,
            score=np.full(n, t["confidence"])))
    table = ObjectTable.concat(tables).sorted() if tables else ObjectTable.empty()
    return objects, table


def track_detections(seq: SequenceLike, detections: DetectionSource, config: Config | None = None,
                     camera_poses: np.ndarray | None = None) -> ObjectsResult:
    """Track the objects of one sequence from its 3D detections (no images needed).

    Parameters
    ----------
    seq : a :class:`~twistslam.datasets.KittiTracking`, ``(root, seq)`` or a path into one.
    detections : folder with ``SEQ.txt`` (PointRCNN comma format or KITTI tracking results)
        or ``SEQ/NNNNNN.txt`` (KITTI object results), one file, or an ObjectTable.
    config : its ``objects`` section is used (``Config()`` when None).
    camera_poses : (N, 4, 4) ``T_w_c`` to track in the world frame (e.g. a SLAM run); by
        default the sequence's oxts / poses when ``objects.frame`` is ``auto`` or ``world``.

    Returns
    -------
    ObjectsResult
        Tracks as numpy arrays, reported boxes as an ObjectTable, timings; ``.save(out)``
        writes ``out/tracking/SEQ.txt`` for ``twistslam eval``.
    """
    config = config if config is not None else Config()
    cfg = config.objects
    sequence = _open(seq)
    name = str(getattr(sequence, "seq", "0000"))
    length = len(sequence) or None
    table = load_detections(detections, name, num_frames=length, classes=cfg.classes)
    num_frames = length or (int(table.frame.max()) + 1 if len(table) else 0)
    T_w_c, frame_kind = _camera_poses(sequence, cfg, num_frames, camera_poses)
    tracker = ObjectTracker(cfg)
    bounds = np.searchsorted(table.frame, np.arange(num_frames + 1))
    step_ms = []
    for f in range(num_frames):
        step_ms.append(tracker.step(f, T_w_c[f], table.select(slice(bounds[f], bounds[f + 1]))))
    timestamps = getattr(sequence, "timestamps", None)
    period = float(np.median(np.diff(timestamps))) if timestamps is not None and len(timestamps) > 1 else FRAME_PERIOD
    objects, boxes = _results(tracker.tracks(), list(cfg.classes), T_w_c,
                              getattr(sequence, "calib", None), _image_size(sequence), period)
    timings = Timings.from_frames([{"track": ms} for ms in step_ms], step_ms)
    return ObjectsResult(objects=objects, tracking=boxes, frame=frame_kind, seq=name,
                         num_frames=num_frames, timings=timings,
                         min_track_score=cfg.min_track_score, config=config)
