"""The view's LiDAR returns (figure 1 (d)): road returns are those projecting onto road pixels,
the rest are shown apart; bad rows, far returns and the thinning; the world transform; bad
arguments name themselves."""

from __future__ import annotations

import numpy as np
import pytest

from twistslam.viz import lidar_view

HEIGHT, WIDTH = 100, 200
K = np.array([[100.0, 0.0, 100.0], [0.0, 100.0, 50.0], [0.0, 0.0, 1.0]])
ROAD, SKY, CAR = 7, 23, 26


def classes() -> np.ndarray:
    """Sky above row 50, road below, a car on the road at columns 120-160."""
    image = np.full((HEIGHT, WIDTH), SKY, np.int32)
    image[50:] = ROAD
    image[50:, 120:160] = CAR
    return image


def through_pixel(u: float, v: float, depth: float) -> np.ndarray:
    """The camera-frame point at ``depth`` seen at pixel (u, v)."""
    return np.array([(u - K[0, 2]) / K[0, 0] * depth, (v - K[1, 2]) / K[1, 1] * depth, depth])


def test_road_returns_are_those_on_road_pixels():
    on_road = [through_pixel(30.5, 80.5, 8.0), through_pixel(100.5, 95.5, 3.0)]
    off_road = [through_pixel(30.5, 20.5, 20.0),   # sky
                through_pixel(140.5, 80.5, 9.0),   # the car
                through_pixel(160.5, 20.5, 8.0) * [1, 1, -1],  # behind: would project on the road
                np.array([40.0, 1.6, 5.0])]        # beside the camera, outside the image
    points = np.array(on_road + off_road)
    view = lidar_view(points, np.eye(4), K, classes(), ROAD)
    np.testing.assert_allclose(view.road_w, on_road)
    np.testing.assert_allclose(view.scan_w, off_road)


def test_without_a_segmentation_nothing_is_road():
    points = np.array([through_pixel(30.5, 80.5, 8.0)])
    view = lidar_view(points, np.eye(4), K, None, ROAD)
    assert view.road_w.shape == (0, 3) and len(view.scan_w) == 1


def test_returns_go_to_the_world_with_the_camera_pose():
    yaw = np.radians(30.0)
    T_w_c = np.eye(4)
    T_w_c[:3, :3] = [[np.cos(yaw), 0, np.sin(yaw)], [0, 1, 0], [-np.sin(yaw), 0, np.cos(yaw)]]
    T_w_c[:3, 3] = [5.0, -0.2, 40.0]
    road_c = through_pixel(60.5, 90.5, 6.0)
    view = lidar_view(np.array([road_c]), T_w_c, K, classes(), ROAD)
    np.testing.assert_allclose(view.road_w, [T_w_c[:3, :3] @ road_c + T_w_c[:3, 3]])


def test_bad_rows_and_far_returns_are_left_out_and_the_scan_is_thinned():
    rng = np.random.default_rng(0)
    points = np.column_stack([rng.uniform(-30, 30, (5000, 3)), rng.uniform(0, 1, 5000)])
    points[:10, 0] = np.nan
    points[10:20, 2] = np.inf
    points[20:30, :3] = [70.0, 0.0, 10.0]  # beyond the 60 m shown
    view = lidar_view(points, np.eye(4), K, classes(), ROAD, max_range_m=60.0, max_points=1000)
    shown = np.vstack([view.scan_w, view.road_w])
    assert np.isfinite(shown).all()
    assert np.hypot(shown[:, 0], shown[:, 2]).max() <= 60.0
    assert 900 <= len(shown) <= 1000
    everything = lidar_view(points, np.eye(4), K, classes(), ROAD, max_points=10 ** 6)
    assert len(everything.scan_w) + len(everything.road_w) == 5000 - 30


@pytest.mark.parametrize("argument, kwargs", [
    ("points_c", dict(points_c=np.zeros((5, 2)))),
    ("T_w_c", dict(T_w_c=np.eye(3))),
    ("K", dict(K=np.eye(4))),
    ("class_ids", dict(class_ids=np.zeros((HEIGHT, WIDTH), np.float32))),
    ("max_points", dict(max_points=0)),
])
def test_bad_arguments_name_themselves(argument, kwargs):
    args = dict(points_c=np.zeros((5, 3)), T_w_c=np.eye(4), K=K, class_ids=classes(),
                road_class_id=ROAD)
    with pytest.raises(ValueError, match=argument):
        lidar_view(**{**args, **kwargs})
