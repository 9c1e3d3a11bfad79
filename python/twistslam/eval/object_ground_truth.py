"""The simulator's object ground truth and which of its cars (and frames) are evaluated.

Ground truth (written by :mod:`twistslam.sim`, world = camera of frame 0):
``training/object_poses/SEQ.txt`` (every object in every frame: ``frame track_id class l w h``
and a row-major 3x4 ``T_w_o``, origin at the box centre, x along the length, y down, z across),
``poses/SEQ.txt`` (``T_w_c``), ``label_02/SEQ.txt`` (the objects seen in the image, with their
visible 2D box) and ``meshes/SEQ/shapes.json`` (per track ``moving``).

A car's evaluated frames are those where it is labelled, its centre is within
``MAX_RANGE_M``, its labelled 2D box is at least ``MIN_BOX_HEIGHT_PX`` tall and its
occlusion level at most ``MAX_OCCLUSION``: the simulator labels cars hidden behind others
down to a few pixels, which no camera can track. Height and occlusion are the KITTI object
benchmark's *moderate* level; a frame must also show at least half of the car's projected
box inside the image (truncation level <= ``MAX_TRUNCATION``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..datasets import read_labels, read_poses
from .difficulty import DIFFICULTIES
from .trajectory import invert

#: class of the evaluated ground-truth objects (KITTI type)
CAR_CLASS = "Car"
#: a car is evaluated when seen this often (frames labelled, in range and tall enough)
MIN_VISIBLE_FRAMES = 20
#: range (m, box centre from the camera) of the evaluated frames: the issue's "within 50 m"
MAX_RANGE_M = 50.0
#: frames whose labelled 2D box is lower than this (px, bottom - top) are not evaluated: a
#: box that small is a car seen through a gap or at the image border. 25 px is KITTI's
#: minimum ground-truth height of its moderate and hard levels (object devkit
#: ``evaluate_object.cpp``: ``MIN_HEIGHT[3] = {40, 25, 25}``, "minimum height for evaluated
#: groundtruth/detections"). The tracking devkit (``evaluate_tracking.py``) has the same
#: ``min_height = 25`` but applies it only to unmatched *tracker* boxes (ignored, not false
#: positives); its ground truth is ignored for occlusion, truncation and class, not height.
MIN_BOX_HEIGHT_PX = DIFFICULTIES["moderate"].min_height
#: frames whose KITTI occlusion level is above this are not evaluated. The simulator's level
#: is 2 when under half of the car's silhouette is visible; 1 is the object benchmark's
#: moderate level (``MAX_OCCLUSION[3] = {0, 1, 2}``). Measured on crowded seeds 0-2: of the
#: 628 evaluated frames with no track near the car, 607 were level 2, and 491 of those
#: showed the car on under 500 pixels (a 25 px slice of a car queued behind another).
#: The tracking devkit keeps level 2; ``max_occlusion=2`` restores it.
MAX_OCCLUSION = DIFFICULTIES["moderate"].max_occlusion
#: frames whose truncation level is above this are not evaluated. The simulator's level is 1
#: when the car touches the image border with at least half of its projected 3D box inside,
#: 2 when over half of it lies outside (a car beside the camera, seen as a sliver at the
#: border). KITTI is stricter (moderate keeps truncation <= 0.3, the tracking devkit level 0
#: only); we keep level 1 because a half-visible car at the border is trackable. Measured on
#: crowded seed 1: car 79, driving beside the camera, was level 2 in 93 of its 100 frames
#: (its visible part a strip under 40 px tall at the right border). 2 restores every frame.
MAX_TRUNCATION = 1


@dataclass
class GtTrack:
    """One ground-truth object; row ``k`` of the arrays is frame ``frames[k]``.

    Attributes
    ----------
    size : (3,) length, width, height (m).
    labelled : (K,) bool, the object is in the image (a ``label_02`` row).
    box_height_px : (K,) height of the labelled 2D box (px, bottom - top), NaN where the
        frame is not labelled.
    occlusion : (K,) KITTI occlusion level of the label (0 visible .. 2 largely hidden), -1
        where the frame is not labelled; None: level 0 everywhere.
    truncation : (K,) KITTI tracking truncation level of the label (0 inside the image, 1 at
        the border, 2 mostly outside), -1 where the frame is not labelled; None: level 0.
    """

    track_id: int
    cls: str
    moving: bool
    frames: np.ndarray
    T_w_o: np.ndarray
    size: np.ndarray
    labelled: np.ndarray
    box_height_px: np.ndarray
    occlusion: np.ndarray | None = None
    truncation: np.ndarray | None = None

    def half_extents(self) -> np.ndarray:
        """(3,) half sizes along the object axes x (length), y (height), z (width)."""
        length, width, height = self.size
        return 0.5 * np.array([length, height, width])


@dataclass
class SequenceGroundTruth:
    """Camera poses ``T_w_c`` (F, 4, 4) and every object's track, keyed by track id."""

    T_w_c: np.ndarray
    tracks: dict[int, GtTrack] = field(default_factory=dict)


def load_ground_truth(root: str | Path, seq: str) -> SequenceGroundTruth:
    """Read a simulated sequence (``root`` holds ``training/``)."""
    base = Path(root) / "training"
    rows: dict[int, list] = {}
    classes, sizes = {}, {}
    for line in (base / "object_poses" / f"{seq}.txt").read_text(encoding="utf-8").splitlines():
        tok = line.split()
        if not tok:
            continue
        frame, tid = int(tok[0]), int(tok[1])
        classes[tid], sizes[tid] = tok[2], np.array(tok[3:6], dtype=np.float64)
        T = np.eye(4)
        T[:3, :] = np.array(tok[6:18], dtype=np.float64).reshape(3, 4)
        rows.setdefault(tid, []).append((frame, T))
    labels = read_labels(base / "label_02" / f"{seq}.txt")
    heights = labels.box_2d[:, 3] - labels.box_2d[:, 1]  # image y grows down: bottom - top
    height_of = {(int(t), int(f)): float(h)
                 for t, f, h in zip(labels.track_id.tolist(), labels.frame.tolist(), heights)}
    key = list(zip(labels.track_id.tolist(), labels.frame.tolist()))
    occlusion_of = {(int(t), int(f)): int(o) for (t, f), o in zip(key, labels.occlusion.tolist())}
    truncation_of = {(int(t), int(f)): int(round(v)) for (t, f), v in zip(key, labels.truncation.tolist())}
    shapes = json.loads((base / "meshes" / seq / "shapes.json").read_text(encoding="utf-8"))
    tracks = {}
    for tid, items in rows.items():
        items.sort(key=lambda item: item[0])
        frames = np.array([f for f, _ in items], dtype=np.int64)
        box_height = np.array([height_of.get((tid, int(f)), np.nan) for f in frames])
        tracks[tid] = GtTrack(
            track_id=tid, cls=classes[tid], moving=bool(shapes.get(f"{tid:06d}", {}).get("moving")),
            frames=frames, T_w_o=np.stack([T for _, T in items]), size=sizes[tid],
            labelled=np.array([(tid, int(f)) in height_of for f in frames], dtype=bool),
            box_height_px=box_height,
            occlusion=np.array([occlusion_of.get((tid, int(f)), -1) for f in frames], dtype=np.int64),
            truncation=np.array([truncation_of.get((tid, int(f)), -1) for f in frames], dtype=np.int64))
    return SequenceGroundTruth(T_w_c=read_poses(base / "poses" / f"{seq}.txt"), tracks=tracks)


def selected_frames(track: GtTrack, T_w_c: np.ndarray, max_range_m: float = MAX_RANGE_M,
                    min_box_height_px: float = MIN_BOX_HEIGHT_PX,
                    max_occlusion: int = MAX_OCCLUSION,
                    max_truncation: int = MAX_TRUNCATION) -> np.ndarray:
    """Frames where the object is labelled, its centre within ``max_range_m`` of the camera,
    its labelled box at least ``min_box_height_px`` tall (0: no height rule), its
    occlusion level at most ``max_occlusion`` (2: no occlusion rule) and its truncation level
    at most ``max_truncation`` (2: no truncation rule)."""
    T_c_o = invert(T_w_c[track.frames]) @ track.T_w_o
    near = np.linalg.norm(T_c_o[:, :3, 3], axis=1) <= max_range_m
    if min_box_height_px > 0:
        tall = np.asarray(track.box_height_px) >= min_box_height_px  # NaN (unlabelled): False
    else:
        tall = np.ones(len(track.frames), dtype=bool)
    seen = _level(track.occlusion, len(track.frames)) <= max_occlusion
    inside = _level(track.truncation, len(track.frames)) <= max_truncation
    return track.frames[track.labelled & near & tall & seen & inside]


def _level(levels: np.ndarray | None, n: int) -> np.ndarray:
    """(n,) per-frame label levels, 0 where the track does not give them."""
    return np.zeros(n, dtype=np.int64) if levels is None else np.asarray(levels)


def evaluated_cars(gt: SequenceGroundTruth, min_frames: int = MIN_VISIBLE_FRAMES,
                   max_range_m: float = MAX_RANGE_M,
                   min_box_height_px: float = MIN_BOX_HEIGHT_PX,
                   max_occlusion: int = MAX_OCCLUSION,
                   max_truncation: int = MAX_TRUNCATION) -> dict[int, np.ndarray]:
    """``{track id: selected frames}`` of the moving cars with ``min_frames`` or more
    selected frames (see :func:`selected_frames`)."""
    cars = {}
    for tid, track in sorted(gt.tracks.items()):
        if track.cls == CAR_CLASS and track.moving:
            frames = selected_frames(track, gt.T_w_c, max_range_m, min_box_height_px, max_occlusion,
                                     max_truncation)
            if len(frames) >= min_frames:
                cars[tid] = frames
    return cars
