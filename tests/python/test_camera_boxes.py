"""The box of a camera-only track (twistslam.objects.camera_boxes): its front where it drove,
or for a parked car by the traffic side's rule, and a car's length and width completed away
from the camera."""

import numpy as np
import pytest

from twistslam.objects.camera_boxes import (CameraBoxRules, complete_car_extent,
                                           road_side_turns_around, travel_heading)
from twistslam.objects.visual import box_from_points, cluster_box


def _driving_track(steps_o: np.ndarray, yaw0: float = 0.4) -> np.ndarray:
    """Poses of a track whose frame turns by 1 deg per frame while taking ``steps_o`` (N, 3),
    each in the object frame of its later row (y: down)."""
    T = [np.eye(4)]
    T[0][:3, :3] = _rot_y(yaw0)
    for k, d in enumerate(steps_o):
        nxt = np.eye(4)
        nxt[:3, :3] = _rot_y(yaw0 + np.radians(k + 1))
        nxt[:3, 3] = T[-1][:3, 3] + nxt[:3, :3] @ d
        T.append(nxt)
    return np.array(T)


def _rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def test_a_driving_track_s_box_points_where_it_went_even_when_only_its_rear_was_seen():
    rng = np.random.default_rng(1)
    heading = np.array([0.6, 0.0, 0.8])  # in the object frame (its first camera's axes)
    steps = np.tile(0.5 * heading, (20, 1)) + rng.normal(0, 0.03, (20, 3)) * [1, 0, 1]
    T = _driving_track(steps)
    got = travel_heading(T, np.arange(21))
    assert got is not None and np.degrees(np.arccos(got @ heading)) < 3  # with its sign
    # the rear face alone: 1.8 m across, 0.1 m deep, behind the origin; its principal axis
    # is the width, at 90 deg from the heading
    side = np.cross(heading, [0, 1, 0])
    rear = (rng.uniform(-0.9, 0.9, (300, 1)) * side + rng.uniform(0, 0.1, (300, 1)) * -heading
            + rng.uniform(-0.7, 0.7, (300, 1)) * [0, 1, 0])
    T_pca, _ = box_from_points(rear)
    T_box, size = box_from_points(rear, got)
    assert abs(T_pca[:3, 0] @ heading) < 0.1  # the wrong axis without the heading
    assert np.degrees(np.arccos(T_box[:3, 0] @ heading)) < 3  # x: the car's front
    assert size[1] == pytest.approx(1.8, abs=0.2)  # the width across the heading


def test_no_heading_for_jitter_a_short_drive_or_frame_gaps():
    rng = np.random.default_rng(2)
    # a parked car's stereo swings along the line of sight: 6 m of path, ~0 net
    swing = np.diff(1.5 * np.sin(np.linspace(0, 4 * np.pi, 41)))
    T = _driving_track(np.column_stack([np.full(40, 0.01), np.zeros(40), swing]), yaw0=0.0)
    assert travel_heading(T, np.arange(41)) is None
    short = _driving_track(np.tile([0.0, 0.0, 0.5], (5, 1)))  # 2.5 m < 3 m
    assert travel_heading(short, np.arange(6)) is None
    assert travel_heading(short, np.arange(6), min_travel_m=2.0) is not None
    # steps across a gap in the rows are not steps
    far = _driving_track(np.tile([0.0, 0.0, 0.5], (8, 1)))
    assert travel_heading(far, np.array([0, 10, 20, 30, 40, 50, 60, 70, 80])) is None
    assert travel_heading(far[:1], np.arange(1)) is None
    noisy = rng.normal(0, 1, (21, 4, 4))
    noisy[:, 3] = [0, 0, 0, 1]
    noisy[3, 0, 3] = np.nan  # a NaN row's steps are dropped, not propagated
    got = travel_heading(noisy, np.arange(21), min_travel_m=0.0, min_straightness=0.0)
    assert got is None or np.isfinite(got).all()


def _camera_poses(n: int) -> dict[int, np.ndarray]:
    """A camera driving 1 m per frame along the world z (its own forward axis)."""
    poses = {}
    for f in range(n):
        T = np.eye(4)
        T[2, 3] = float(f)
        poses[f] = T
    return poses


def _boxes(n: int, lateral_m: float, yaw: float, ahead_m: float = 10.0) -> np.ndarray:
    """A parked box ``lateral_m`` to the camera's right (x), its x axis at ``yaw`` about y
    (KITTI: yaw 0 points along the camera's x; -pi/2 along its z, forward)."""
    T = np.eye(4)
    T[:3, :3] = _rot_y(yaw)
    T[:3, 3] = [lateral_m, 1.0, ahead_m]
    return np.repeat(T[None], n, axis=0)


FORWARD, BACKWARD = -np.pi / 2, np.pi / 2  # box x along the camera's +z / -z


def test_a_parked_car_faces_the_traffic_of_its_side_of_the_road():
    rules = CameraBoxRules()
    frames = np.arange(5)
    cams = _camera_poses(5)
    assert np.allclose(_boxes(1, 4.0, FORWARD)[0][:3, 0], [0, 0, 1], atol=1e-9)
    # right-hand traffic: on the right a car faces the camera's way, on the left the other
    assert road_side_turns_around(_boxes(5, 4.0, BACKWARD), frames, cams, rules)
    assert not road_side_turns_around(_boxes(5, 4.0, FORWARD), frames, cams, rules)
    assert road_side_turns_around(_boxes(5, -4.0, FORWARD), frames, cams, rules)
    assert not road_side_turns_around(_boxes(5, -4.0, BACKWARD), frames, cams, rules)
    left_hand = CameraBoxRules(road_side=-1)
    assert road_side_turns_around(_boxes(5, 4.0, FORWARD), frames, cams, left_hand)
    assert not road_side_turns_around(_boxes(5, 4.0, BACKWARD), frames, cams,
                                      CameraBoxRules(road_side=0))


def test_no_vote_in_the_camera_s_lane_off_its_road_across_it_or_without_a_camera():
    rules = CameraBoxRules()
    frames = np.arange(5)
    cams = _camera_poses(5)
    assert not road_side_turns_around(_boxes(5, 1.0, BACKWARD), frames, cams, rules)  # its lane
    assert not road_side_turns_around(_boxes(5, 12.0, BACKWARD), frames, cams, rules)  # off road
    across = _boxes(5, 4.0, BACKWARD + np.radians(50))
    assert not road_side_turns_around(across, frames, cams, rules)
    slanted = _boxes(5, 4.0, BACKWARD + np.radians(20))  # within 30 deg: still votes
    assert road_side_turns_around(slanted, frames, cams, rules)
    assert not road_side_turns_around(_boxes(5, 4.0, BACKWARD), frames + 100, cams, rules)
    # the majority of the rows decides: 3 rows against, 2 for (a box that moved across lanes)
    mixed = np.concatenate([_boxes(3, 4.0, BACKWARD), _boxes(2, -4.0, BACKWARD)])
    assert road_side_turns_around(mixed, frames, cams, rules)
    nan = _boxes(5, 4.0, BACKWARD)
    nan[:, 0, 3] = np.nan  # no finite pose, no vote
    assert not road_side_turns_around(nan, frames, cams, rules)


def _box(yaw: float, centre, size) -> tuple[np.ndarray, np.ndarray]:
    T = np.eye(4)
    T[:3, :3] = _rot_y(yaw)
    T[:3, 3] = centre
    return T, np.asarray(size, dtype=float)


def test_a_car_seen_from_behind_grows_its_hidden_length_away_from_the_camera():
    rules = CameraBoxRules()  # 4.0 m x 1.65 m
    # a car ahead (its x axis along the camera's z), its rear 1.2 m of points seen from 15 m
    T, size = _box(-np.pi / 2, [0.0, 0.0, 15.6], [1.2, 1.7, 1.4])
    camera = np.zeros(3)
    T2, size2 = complete_car_extent(T, size, camera, rules)
    assert size2 == pytest.approx([4.0, 1.7, 1.4])  # the width was seen whole: kept
    assert T2[:3, 3] == pytest.approx([0.0, 0.0, 15.6 + 1.4])  # its seen face stays at 15 m
    assert np.allclose(T2[:3, :3], T[:3, :3])
    # the same car turned around (its front towards the camera): still grows away from it
    T3, _ = complete_car_extent(_box(np.pi / 2, [0.0, 0.0, 15.6], size)[0], size, camera, rules)
    assert T3[:3, 3] == pytest.approx([0.0, 0.0, 17.0])
    # 4 m to the right, seen side-on: only the width is short, it grows further right
    T4, size4 = complete_car_extent(*_box(-np.pi / 2, [4.0, 0.0, 15.0], [4.3, 0.8, 1.4]),
                                    np.zeros(3), rules)
    assert size4 == pytest.approx([4.3, 1.65, 1.4])
    assert T4[:3, 3] == pytest.approx([4.0 + 0.425, 0.0, 15.0])


def test_a_whole_car_or_no_prior_or_a_bad_camera_keeps_the_box():
    T, size = _box(0.3, [2.0, 0.5, 20.0], [4.4, 1.8, 1.5])
    T2, size2 = complete_car_extent(T, size, np.zeros(3), CameraBoxRules())
    assert np.array_equal(T2, T) and np.array_equal(size2, size)
    short = np.array([2.0, 1.0, 1.5])
    T3, size3 = complete_car_extent(T, short, np.zeros(3),
                                    CameraBoxRules(car_length_m=0.0, car_width_m=0.0))
    assert np.array_equal(T3, T) and np.array_equal(size3, short)
    T4, size4 = complete_car_extent(T, short, np.full(3, np.nan), CameraBoxRules())
    assert np.array_equal(T4, T) and np.array_equal(size4, short)
    # a camera in line with the centre along the length: it grows on both sides
    T5, size5 = complete_car_extent(*_box(0.0, [0.0, 0.0, 10.0], [2.0, 1.7, 1.5]),
                                    np.array([0.0, 0.0, 0.0]), CameraBoxRules())
    assert size5[0] == pytest.approx(4.0) and T5[:3, 3] == pytest.approx([0.0, 0.0, 10.0])



def test_the_output_and_the_live_view_box_of_a_cluster():
    """``cluster_box`` (what the output and the ``--viz`` view draw): a canonical track is its
    own box, whatever its points; any other car is fitted to its points and completed."""
    rng = np.random.default_rng(1)
    # a car 15 m ahead, its length along the camera's z: its rear face (1.7 m wide) and the
    # first 3 m of its left side seen
    u = rng.uniform(-0.5, 0.5, (2, 300))
    rear = np.column_stack([1.7 * u[0], 1.4 * u[1], np.full(300, -1.5)])
    side = np.column_stack([np.full(300, -0.85), 1.4 * u[1], -1.5 + 3.0 * (u[0] + 0.5)])
    rear = np.vstack([rear, side])
    frames = np.arange(3)
    T_w_o = np.repeat(np.eye(4)[None], 3, axis=0)
    T_w_o[:, :3, 3] = [0.0, 0.0, 15.6]
    cameras = {int(f): np.eye(4) for f in frames}
    cluster = {"frames": frames, "T_w_o": T_w_o, "points_o": rear, "class_id": 26,
               "canonical": True, "size": np.array([4.4, 1.8, 1.5])}
    T_o_box, size, canonical = cluster_box(cluster, cameras)
    assert canonical and np.array_equal(T_o_box, np.eye(4))
    assert size == pytest.approx([4.4, 1.8, 1.5])
    # without a canonical frame (or without sizes): the points' box, grown to a car's length
    for fitted in ({**cluster, "canonical": False}, {**cluster, "size": np.zeros(3)}):
        T_o_box, size, canonical = cluster_box(fitted, cameras)
        assert not canonical
        assert size[0] == pytest.approx(4.0) and size[1] == pytest.approx(1.7, abs=0.1)
        assert abs(T_o_box[0, 2]) > 0.99  # its length along the object's z
        # the seen rear face stays 1.5 m before the origin; the box grows away from the camera
        assert T_o_box[:3, 3] == pytest.approx([0.0, 0.0, -1.5 + 2.0], abs=0.1)


def test_a_camera_only_box_counts_the_points_its_track_culled():
    """The points a track culled while tracked (``retired_points_o``) hold the faces its earlier
    views showed: the box is fitted to them with the live ones. Here the live points at the
    track's end are a few on the rear face plus a clump 3.5 m before it (towards the camera);
    the retired ones cover the rear and the side."""
    rng = np.random.default_rng(4)
    u = rng.uniform(-0.5, 0.5, (2, 200))
    rear = np.column_stack([1.7 * u[0], 1.4 * u[1], np.full(200, -2.0)])
    side = np.column_stack([np.full(200, -0.85), 1.4 * u[1], -2.0 + 4.2 * (u[0] + 0.5)])
    live = np.vstack([rear[:8], rear[8:18] + [0.0, 0.0, -3.5]])
    frames = np.arange(3)
    T_w_o = np.repeat(np.eye(4)[None], 3, axis=0)
    T_w_o[:, :3, 3] = [0.0, 0.0, 16.0]
    cameras = {int(f): np.eye(4) for f in frames}
    cluster = {"frames": frames, "T_w_o": T_w_o, "points_o": live, "class_id": 26,
               "canonical": False, "size": np.zeros(3)}
    T_live, size_live, _ = cluster_box(cluster, cameras)
    T_all, size_all, _ = cluster_box({**cluster, "retired_points_o": np.vstack([rear, side])},
                                     cameras)
    # the car spans z in [-2.0, 2.2] of its object frame, its centre at z = 0.1
    assert abs(T_live[2, 3] - 0.1) > 1.5  # the live clump drags the box off the car
    # on the car (the 5-95 % extents trim its faces' outer points a little)
    assert np.linalg.norm(T_all[[0, 2], 3] - [0.0, 0.1]) < 0.3
    assert size_all[0] == pytest.approx(4.2, abs=0.5) and size_all[1] == pytest.approx(1.7, abs=0.2)
    # no retired points (a run without the final smoothing): the live points alone, as before
    T_empty, _, _ = cluster_box({**cluster, "retired_points_o": np.zeros((0, 3))}, cameras)
    assert np.allclose(T_empty, T_live)
