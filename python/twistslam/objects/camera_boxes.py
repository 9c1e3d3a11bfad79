"""The box of a camera-only track (issue 10: a cluster's object frame has no canonical pose or
size until a 3D detection gives them): where its front is, and how long and wide a car is
whose points show only part of it.

* A track that drove: its front is where it went (:func:`travel_heading`).
* A track that did not (parked, or too little travel to tell from jitter): its points give an
  axis modulo pi only, and the traffic side's rule (the one ``lidar_objects.road_side_heading``
  applies to the classical detector's boxes) picks the end: a car parked along the camera's
  road on its right faces the camera's travel, on its left the other way (right-hand traffic).
  Each row votes; the box turns around when more rows vote against it than for it
  (:func:`road_side_turns_around`).
* A car's points cover the faces the camera saw: a car seen from behind spans its width but a
  fraction of its length, so its box centre sat metres towards the camera. A length or width
  short of the classical detector's car-size prior (``detection.car_length_m``,
  ``car_width_m``) grows to it, away from the camera (:func:`complete_car_extent`), as that
  detector lays a partly seen car's hidden end.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CameraBoxRules:
    """The thresholds and priors (their configuration keys in brackets)."""

    min_travel_m: float = 3.0  # net displacement of a driving track (visual_objects.travel_min_path_m)
    min_straightness: float = 0.5  # ... over its path (visual_objects.travel_min_straightness)
    road_side: int = 1  # 1 right-hand traffic, -1 left-hand, 0 no rule (lidar_objects.road_side_heading)
    road_side_min_lateral_m: float = 2.0  # (lidar_objects.road_side_min_lateral_m)
    road_side_max_lateral_m: float = 8.0  # (lidar_objects.road_side_max_lateral_m)
    road_side_max_angle_deg: float = 30.0  # (lidar_objects.road_side_max_angle_deg)
    car_length_m: float = 4.0  # a car's length at least (detection.car_length_m; 0: none)
    car_width_m: float = 1.65  # ... and width (detection.car_width_m)

    @classmethod
    def from_config(cls, config) -> "CameraBoxRules":
        vo, lo, det = config.visual_objects, config.lidar_objects, config.detection
        return cls(vo.travel_min_path_m, vo.travel_min_straightness, lo.road_side_heading,
                   lo.road_side_min_lateral_m, lo.road_side_max_lateral_m,
                   lo.road_side_max_angle_deg, det.car_length_m, det.car_width_m)


def travel_heading(T_w_o: np.ndarray, frames: np.ndarray, min_travel_m: float = 3.0,
                   min_straightness: float = 0.5) -> np.ndarray | None:
    """The unit direction (object frame, its x-z plane) a track drove in, or None.

    Parameters
    ----------
    T_w_o : (N, 4, 4) poses of the track's rows; frames : (N,) their frame indices (steps are
        taken between consecutive frames only).
    min_travel_m : the net displacement (m) the track must have made.
    min_straightness : ... as a fraction of its path: steps that cancel out are a parked or
        crawling car's stereo jitter, along the line of sight (as ``visual_objects.
        travel_min_straightness`` gates the core's travel axis).

    Each step is taken in the object frame of its later row, ``R_w_o^T (t_i - t_{i-1})``, so a
    car that turns keeps adding along its own heading.
    """
    T_w_o = np.asarray(T_w_o, dtype=np.float64).reshape(-1, 4, 4)
    frames = np.asarray(frames)
    if len(T_w_o) < 2:
        return None
    steps = np.einsum("nji,nj->ni", T_w_o[1:, :3, :3], T_w_o[1:, :3, 3] - T_w_o[:-1, :3, 3])
    steps = steps[(np.diff(frames) == 1) & np.isfinite(steps).all(axis=1)][:, [0, 2]]
    net = steps.sum(axis=0)
    path = np.linalg.norm(steps, axis=1).sum()
    distance = np.linalg.norm(net)
    if not (distance >= min_travel_m and distance >= min_straightness * path):
        return None
    return np.array([net[0], 0.0, net[1]]) / distance


def road_side_turns_around(T_w_box: np.ndarray, frames: np.ndarray,
                           camera_poses: dict[int, np.ndarray], rules: CameraBoxRules) -> bool:
    """Whether the traffic side's rule says the box (its x axis: the front) faces backwards.

    Parameters
    ----------
    T_w_box : (N, 4, 4) the box's pose in each of the track's rows; frames : (N,) their frames.
    camera_poses : frame -> T_w_c (x right, z forward); rows without one do not vote.
    rules : the lateral band and the angle within which a row votes.

    A row votes when the box centre lies ``road_side_min_lateral_m``-``road_side_max_lateral_m``
    to the side of its camera (not in the camera's lane, not off its road) and the box's axis
    is within ``road_side_max_angle_deg`` of the camera's forward axis (not parked across or
    turning). Ties and no votes keep the box as it is.
    """
    if rules.road_side == 0:
        return False
    T_w_box = np.asarray(T_w_box, dtype=np.float64).reshape(-1, 4, 4)
    min_along = np.cos(np.radians(rules.road_side_max_angle_deg))
    votes = 0
    for T, f in zip(T_w_box, np.asarray(frames).tolist()):
        T_w_c = camera_poses.get(int(f))
        if T_w_c is None or not np.isfinite(T).all():
            continue
        lateral = (T[:3, 3] - T_w_c[:3, 3]) @ T_w_c[:3, 0]
        along = T[:3, 0] @ T_w_c[:3, 2]
        if not (rules.road_side_min_lateral_m <= abs(lateral) <= rules.road_side_max_lateral_m
                and abs(along) >= min_along):
            continue
        facing = np.sign(lateral) * rules.road_side  # +1: the camera's way
        votes += 1 if along * facing > 0 else -1
    return votes < 0


def complete_car_extent(T_o_box: np.ndarray, size: np.ndarray, camera_o: np.ndarray,
                        rules: CameraBoxRules) -> tuple[np.ndarray, np.ndarray]:
    """``(T_o_box, size)`` with a length or width short of the car-size prior grown to it.

    Parameters
    ----------
    T_o_box : (4, 4) the box in its object frame (x = length, y = down, z = width).
    size : (3,) its (l, w, h) in metres.
    camera_o : (3,) where the camera saw it from, in the object frame (e.g. the mean of its
        rows' camera centres).
    rules : ``car_length_m`` and ``car_width_m``; 0 leaves that extent as measured.

    The face nearer the camera is the seen one and stays; the box grows away from it. A camera
    exactly in line with the box's centre along an axis grows that extent on both sides.
    """
    T, size = np.array(T_o_box, dtype=np.float64), np.array(size, dtype=np.float64)
    if not (np.isfinite(T).all() and np.isfinite(size).all() and np.isfinite(camera_o).all()):
        return T, size
    camera_box = T[:3, :3].T @ (np.asarray(camera_o, dtype=np.float64) - T[:3, 3])
    for axis, extent, prior in ((0, 0, rules.car_length_m), (2, 1, rules.car_width_m)):
        grow = prior - size[extent]
        if not (prior > 0 and grow > 0):
            continue
        # the centre moves half the growth away from the camera, along the box's axis
        T[:3, 3] -= np.sign(camera_box[axis]) * 0.5 * grow * T[:3, axis]
        size[extent] = prior
    return T, size
