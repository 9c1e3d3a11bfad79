"""The object clusters a SLAM run tracked (issue 10), as :class:`TrackedObject` rows and
KITTI tracking boxes.

A cluster's object frame is the one the core gave it at birth: world axes (identity rotation)
at the centroid of its first points, so ``T_w_o`` is not a canonical box pose, until a 3D
detection is associated with it (LiDAR fusion, ``config.lidar_objects``): then the frame is
that box's (canonical pose) and its size the boxes' median. Without one, its box is fitted to
its points in that frame: yaw about the frame's y axis (the first camera's "down") from the
direction the track drove in (:func:`travel_heading`: its front is where it went), or, for a
track that did not drive, from the principal axis of the points' x-z coordinates (modulo pi;
a rear face seen alone gives its width's axis; a parked car's front by the traffic side's
rule), extents between the 5th and 95th percentile along each box axis (robust to the few
background points a mask lets in), a car's length and width at least the car-size prior, grown
away from the camera (:mod:`.camera_boxes`). Reported frames are those with a valid twist
(eq. 4).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..datasets import ObjectTable, write_tracking_results
from .camera_boxes import (CameraBoxRules, complete_car_extent, road_side_turns_around,
                           travel_heading)
from .result import TrackedObject
from .tracking import _image_size, _speed_kmh, in_image

#: Cityscapes class id -> KITTI type written to the tracking results
KITTI_TYPES = {24: "Pedestrian", 25: "Cyclist", 26: "Car", 27: "Truck", 28: "Misc", 29: "Van",
               30: "Misc", 31: "Tram", 32: "Cyclist", 33: "Cyclist"}
#: percentiles of the points along each box axis taken as the box's faces: 5 / 95 keeps a
#: stray background point (a mask's edge) from stretching the box
EXTENT_PERCENTILES = (5.0, 95.0)
#: a box turned by pi about its y axis (its front and back swapped)
TURN_AROUND = np.diag([-1.0, 1.0, -1.0, 1.0])


def box_from_points(points_o: np.ndarray,
                    heading_o: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(T_o_box, size)`` of a cluster's points (M, 3) in its object frame: the box frame is
    KITTI's (x = length, y = down, z = width), rotated about y; size = (l, w, h) in metres.
    The box's x axis is ``heading_o`` (a direction in the x-z plane, e.g. from
    :func:`travel_heading`) when given, else the points' principal horizontal axis.
    Fewer than 3 points give an identity pose and a zero size."""
    T = np.eye(4)
    if len(points_o) < 3:
        return T, np.zeros(3)
    if heading_o is not None:
        dx, dz = heading_o[0], heading_o[2]
    else:
        xz = points_o[:, [0, 2]] - np.median(points_o[:, [0, 2]], axis=0)
        _, vectors = np.linalg.eigh(xz.T @ xz)
        dx, dz = vectors[:, -1]  # principal horizontal axis: the car's length
    yaw = np.arctan2(-dz, dx)
    c, s = np.cos(yaw), np.sin(yaw)
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])  # R_y(yaw), as a KITTI box
    local = points_o @ R  # coordinates along the box axes
    lo, hi = np.percentile(local, EXTENT_PERCENTILES, axis=0)
    T[:3, :3] = R
    T[:3, 3] = R @ ((lo + hi) / 2)
    extent = hi - lo
    return T, np.array([extent[0], extent[2], extent[1]])


@dataclass
class VisualObjects:
    """The object clusters of a run: ``objects`` (one :class:`TrackedObject` per cluster, its
    ``T_w_o`` the cluster frame in the SLAM world), ``points_o`` (track id -> (M, 3) points in
    that frame), ``T_o_box`` (track id -> the box fitted to them) and ``tracking`` (the
    reported boxes in each frame's camera frame, KITTI tracking format rows)."""

    objects: list[TrackedObject] = field(default_factory=list)
    points_o: dict[int, np.ndarray] = field(default_factory=dict)
    T_o_box: dict[int, np.ndarray] = field(default_factory=dict)
    tracking: ObjectTable = field(default_factory=ObjectTable.empty)

    def __len__(self) -> int:
        return len(self.objects)

    def __iter__(self):
        return iter(self.objects)

    def __getitem__(self, k: int) -> TrackedObject:
        return self.objects[k]

    def reported(self) -> list[TrackedObject]:
        """Each cluster restricted to its reported rows: what the evaluator compares. A row is
        reported when its twist was valid, or when the twist failed while the cluster's
        instance was seen and its stereo points re-seeded the cluster (``detected`` False).
        Rows predicted through misses are left out."""
        return [_rows(o, o.reported) for o in self.objects if o.reported.any()]

    def __repr__(self) -> str:
        return f"VisualObjects({len(self)} clusters, {len(self.tracking)} boxes)"

    def save(self, out_dir: str | Path, seq: str) -> dict[str, Path]:
        """``tracking/SEQ.txt`` (KITTI tracking results) and ``object_points.npz`` (per track:
        ``frames``, ``T_w_o``, ``points_o``, ``T_o_box``, ``size``)."""
        out = Path(out_dir)
        paths = {"tracking": out / "tracking" / f"{seq}.txt", "object_points": out / "object_points.npz"}
        write_tracking_results(paths["tracking"], self.tracking)
        arrays = {}
        for o in self.objects:
            arrays.update({f"{o.track_id}/frames": o.frames, f"{o.track_id}/T_w_o": o.T_w_o,
                           f"{o.track_id}/size": o.size,
                           f"{o.track_id}/points_o": self.points_o[o.track_id],
                           f"{o.track_id}/T_o_box": self.T_o_box[o.track_id]})
        np.savez_compressed(paths["object_points"], **arrays)
        return paths


#: TrackedObject's per-row arrays (row k = frame frames[k]; None where a track has none)
_ROW_FIELDS = ("frames", "T_w_o", "velocity_kmh", "detected", "reported", "score", "range",
               "has_box", "T_w_o_online")


def _camera_in_object(T_w_o: np.ndarray, frames: np.ndarray,
                      camera_poses: dict[int, np.ndarray]) -> np.ndarray:
    """The mean of the rows' camera centres in the object frame (NaN without any)."""
    centres = [np.linalg.solve(T, np.append(camera_poses[int(f)][:3, 3], 1.0))[:3]
               for T, f in zip(T_w_o, frames) if int(f) in camera_poses]
    return np.mean(centres, axis=0) if centres else np.full(3, np.nan)


def _rows(obj: TrackedObject, keep: np.ndarray) -> TrackedObject:
    """The track restricted to the rows ``keep`` (bool mask or indices), every per-row array."""
    return dataclasses.replace(obj, **{name: getattr(obj, name)[keep] for name in _ROW_FIELDS
                                       if getattr(obj, name) is not None})


def cluster_box(cluster: dict, camera_poses: dict[int, np.ndarray],
                box_rules: CameraBoxRules = CameraBoxRules()) -> tuple[np.ndarray, np.ndarray, bool]:
    """``(T_o_box, size, canonical)`` of one of the core's clusters (``Slam.objects()``), with
    the camera poses (frame -> T_w_c) of its rows so far: a track with a canonical frame (a
    3D box's) and sizes is its own box; any other gets a box fitted to its points (``points_o``
    and, when given, ``retired_points_o``: the ones it culled while tracked), its front
    where it drove or by the road side's rule, a car its full extent (:mod:`.camera_boxes`).
    What the run's output and the live view both draw."""
    frames = np.asarray(cluster["frames"])
    T_w_o = np.asarray(cluster["T_w_o"]).reshape(-1, 4, 4)
    if bool(cluster.get("canonical")) and bool((np.asarray(cluster["size"]) > 0).all()):
        # the object frame is its first detection's box frame; size: the boxes' median
        return np.eye(4), np.asarray(cluster["size"], dtype=np.float64), True
    # the box is fitted to every point the track confirmed, as its re-centring's median: the
    # ones it culled too (``retired_points_o``), which hold the faces earlier views showed. The
    # live points alone can be a handful at the track's end (crowded s1's car 17: 19 points,
    # more than half 3-4 m off its rear face, a 6.1 m box centred 2 m before the car). 10
    # simulated sequences, camera rows: 3D TP 80.9 -> 83.8 %, MOTP 57.2 -> 57.7 %; real 0001
    # camera alone: 3D MOTA 95.8 -> 100 %, 3D MOTP 55.3 -> 55.9 %
    points = np.asarray(cluster["points_o"]).reshape(-1, 3)
    retired = np.asarray(cluster.get("retired_points_o", np.zeros((0, 3)))).reshape(-1, 3)
    points = np.vstack([points, retired])
    heading = travel_heading(T_w_o, frames, box_rules.min_travel_m, box_rules.min_straightness)
    T_o_box, size = box_from_points(points, heading)
    if heading is None and road_side_turns_around(T_w_o @ T_o_box, frames, camera_poses,
                                                  box_rules):
        T_o_box = T_o_box @ TURN_AROUND
    if KITTI_TYPES.get(int(cluster["class_id"])) == "Car" and (size > 0).all():
        T_o_box, size = complete_car_extent(T_o_box, size,
                                            _camera_in_object(T_w_o, frames, camera_poses),
                                            box_rules)
    return T_o_box, size, False


def visual_objects(clusters: list[dict], sequence, camera_poses: dict[int, np.ndarray],
                   period: float = 0.1,
                   box_rules: CameraBoxRules = CameraBoxRules()) -> VisualObjects:
    """Convert the core's clusters (``Slam.objects()``) with the run's camera poses
    (frame -> T_w_c) into :class:`VisualObjects`. ``box_rules``: how a track without a
    canonical frame gets its box's front and a car its size (:mod:`.camera_boxes`)."""
    from .. import geometry

    calib = getattr(sequence, "calib", None)
    width, height = _image_size(sequence)
    result = VisualObjects()
    tables = []
    for c in clusters:
        frames = np.asarray(c["frames"])
        T_w_o = np.asarray(c["T_w_o"]).reshape(-1, 4, 4)
        points = np.asarray(c["points_o"]).reshape(-1, 3)
        T_o_box, size, canonical = cluster_box(c, camera_poses, box_rules)
        cls = KITTI_TYPES.get(int(c["class_id"]), "Misc")
        T_w_box = T_w_o @ T_o_box
        # the core's flag: a valid twist or a re-seed from the instance seen this frame
        reported = np.asarray(c["reported"], dtype=bool) & np.isin(frames, list(camera_poses))
        track_id = int(c["id"])
        result.points_o[track_id] = points
        result.T_o_box[track_id] = T_o_box
        result.objects.append(TrackedObject(
            track_id=track_id, cls=cls, state=str(c["state"]), link=str(c["link"]), frames=frames,
            T_w_o=T_w_o, size=size, velocity_kmh=_speed_kmh(T_w_box, period),
            detected=np.asarray(c["detected"], dtype=bool), reported=reported,
            score=np.zeros(len(frames)), mean_score=0.0, confidence=float(c["hits"]),
            range=np.linalg.norm(T_w_box[:, :3, 3], axis=1), canonical=canonical,
            has_box=np.asarray(c.get("detection_index", np.full(len(frames), -1))) >= 0,
            T_w_o_online=(np.asarray(c["T_w_o_online"]).reshape(-1, 4, 4) if c.get("smoothed")
                          else None)))
        rows = np.flatnonzero(reported)
        # a cluster whose points were all culled (or a flat one) has no box to write
        if not len(rows) or calib is None or not (size > 0).all():
            continue
        T_c_box = np.stack([np.linalg.inv(camera_poses[int(f)]) for f in frames[rows]]) @ T_w_box[rows]
        R = T_c_box[:, :3, :3]
        ry = np.arctan2(R[:, 0, 2], R[:, 0, 0])
        box_3d = np.column_stack([T_c_box[:, :3, 3], np.tile(size, (len(rows), 1)), ry])
        box_2d = geometry.project_boxes(box_3d, calib.P2, width, height)
        visible = in_image(box_2d) & (box_3d[:, 2] > 0)
        # a row not written is not reported either (TrackedObject.reported: "written")
        result.objects[-1].reported[rows[~visible]] = False
        n = int(visible.sum())
        if not n:
            continue
        alpha = ry[visible] - np.arctan2(box_3d[visible, 0], box_3d[visible, 2])
        tables.append(ObjectTable(
            frame=frames[rows][visible], track_id=np.full(n, track_id), cls=np.full(n, cls),
            truncation=np.full(n, -1.0), occlusion=np.full(n, -1),
            alpha=np.arctan2(np.sin(alpha), np.cos(alpha)), box_2d=box_2d[visible],
            box_3d=box_3d[visible], score=np.full(n, float(c["hits"]))))
    if tables:
        result.tracking = ObjectTable.concat(tables).sorted()
    return result
