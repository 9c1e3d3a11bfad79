"""twistslam.lidar: the binding's checks, synthetic depth edges, the KITTI scan correction,
and on real KITTI 0001 (frames 0-26) the LiDAR depth of stereo-matched static keypoints
against stereo depth once the disparity offset is estimated (docs/lidar.md).

The real frames are read from their files (raw scans, corrected here) so that the test does
not depend on the dataset reader's own correction policy.
"""

import numpy as np
import pytest

from conftest import require_real_data
from twistslam import features, lidar
from twistslam.datasets import read_calibration, read_image, read_labels, read_velodyne
from twistslam.geometry import StereoCamera

P2 = np.array([[721.5377, 0, 609.5593, 44.85728], [0, 721.5377, 172.854, 0.2163791],
               [0, 0, 1, 0.002745884]])
P3 = np.array([[721.5377, 0, 609.5593, -339.5242], [0, 721.5377, 172.854, 2.199936],
               [0, 0, 1, 0.002729905]])
W, H = 1242, 375
STATUS = {name: code for code, name in lidar.STATUS_NAMES.items()}


@pytest.fixture(scope="module")
def camera():
    return StereoCamera.from_kitti(P2, P3, W, H)


def scan_lines(cam, u0, u1, v0, v1, depth, line_step=5.0, point_step=2.2):
    """Points of frame c on scan lines over a pixel rectangle, at constant depth."""
    u, v = np.meshgrid(np.arange(u0, u1 + 1e-9, point_step), np.arange(v0, v1 + 1e-9, line_step))
    u, v = u.ravel(), v.ravel()
    x_left = np.c_[(u - cam.cx) * depth / cam.fx, (v - cam.cy) * depth / cam.fy,
                   np.full(u.size, depth)]
    return x_left - np.asarray(cam.t_left)


def test_box_in_front_of_wall_keeps_layers_apart(camera):
    wall = scan_lines(camera, 300, 900, 100, 300, 30.0)  # also behind the box (parallax)
    box = scan_lines(camera, 550, 650, 150, 250, 10.0)
    scan = lidar.project_scan(np.vstack([wall, box]), camera)
    assert scan.num_returns == len(wall) + len(box)
    u = np.arange(530.0, 571.0, 0.5)
    out = lidar.lidar_depth_at(np.c_[u, np.full(u.size, 202.5)], scan)
    on_box = u >= 550
    truth = np.where(on_box, 10.0, 30.0)
    valid = out["valid"]
    np.testing.assert_allclose(out["depth"][valid], truth[valid], rtol=1e-4)
    assert valid[on_box].any() and valid[~on_box].any() and not valid.all()
    assert np.isnan(out["depth"][~valid]).all()
    assert set(out["status"][valid]) <= {STATUS["plane"], STATUS["foreground"]}
    assert out["num_returns"].dtype == np.int32 and out["status"].dtype == np.uint8


def test_mask_drops_dynamic_returns(camera):
    wall = scan_lines(camera, 300, 900, 100, 300, 30.0)
    car = scan_lines(camera, 550, 650, 150, 250, 10.0)
    mask = np.ones((H, W), bool)
    mask[150:251, 550:651] = False
    scan = lidar.project_scan(np.vstack([wall, car]), camera, mask=mask)
    assert scan.num_masked > 0
    assert mask[scan.uv[:, 1].astype(int), scan.uv[:, 0].astype(int)].all()
    out = lidar.lidar_depth_at(np.array([[600.0, 202.5], [547.0, 202.5]]), scan)
    assert out["num_returns"][0] == 0 and not out["valid"][0]
    assert out["status"][1] == STATUS["plane"]
    assert out["depth"][1] == pytest.approx(30.0, rel=1e-4)


def test_nan_points_dropped_and_empty_scan(camera):
    wall = scan_lines(camera, 300, 900, 100, 300, 30.0)
    wall[::50, 1] = np.nan
    scan = lidar.project_scan(np.c_[wall, np.ones(len(wall))].astype(np.float32), camera)
    assert scan.num_non_finite == len(wall[::50])
    assert scan.num_returns == len(wall) - scan.num_non_finite
    assert lidar.lidar_depth_at(np.array([[600.0, 202.5]]), scan)["valid"][0]
    empty = lidar.project_scan(np.zeros((0, 3)), camera)
    out = lidar.lidar_depth_at(np.array([[600.0, 202.5]]), empty)
    assert not out["valid"][0] and out["status"][0] == STATUS["too_few_returns"]
    assert lidar.lidar_depth_at(np.zeros((0, 2)), empty)["depth"].shape == (0,)


def test_bad_input_is_refused_clearly(camera):
    scan = lidar.project_scan(np.zeros((0, 3)), camera)
    with pytest.raises(ValueError, match="points_c"):
        lidar.project_scan(np.zeros((5, 2)), camera)
    with pytest.raises(TypeError, match="points_c"):
        lidar.project_scan(np.array([["a", "b", "c"]]), camera)
    with pytest.raises(ValueError, match="mask"):
        lidar.project_scan(np.zeros((1, 3)), camera, mask=np.ones((10, 10), np.uint8))
    with pytest.raises(ValueError, match="mask"):
        lidar.project_scan(np.zeros((1, 3)), camera, mask=np.ones((H, W), np.float32))
    with pytest.raises(ValueError, match="keypoints"):
        lidar.lidar_depth_at(np.zeros((3, 3)), scan)
    with pytest.raises(ValueError, match="search_radius_typo"):
        lidar.project_scan(np.zeros((1, 3)), camera, search_radius_typo=3)
    with pytest.raises(ValueError, match="search_radius_px"):
        lidar.lidar_depth_at(np.zeros((1, 2)), scan, search_radius_px=float("inf"))
    with pytest.raises(ValueError, match="image size"):
        lidar.project_scan(np.zeros((1, 3)), StereoCamera.from_kitti(P2, P3, 0, 0))
    assert set(lidar.default_options()) >= {"search_radius_px", "max_fit_residual", "layer_gap"}


def test_correct_kitti_scan_matches_a_hand_computed_rotation():
    a = np.radians(0.205)
    pts = np.array([[10.0, 0, 0, 0.7], [0, 5, -1, 0.2], [0, 0, 7, 0.1]], np.float32)
    out = lidar.correct_kitti_scan(pts)
    assert out.shape == (3, 4) and out.dtype == np.float64
    np.testing.assert_allclose(out[0, :3], [10 * np.cos(a), 0, 10 * np.sin(a)], atol=1e-6)
    # axis p x z = (5, 0, 0): q = p cos a + (x_hat x p) sin a, x_hat x p = (0, 1, 5)
    np.testing.assert_allclose(out[1, :3], [0, 5 * np.cos(a) + np.sin(a), -np.cos(a) + 5 * np.sin(a)],
                               atol=1e-6)
    np.testing.assert_allclose(out[2], pts[2], atol=1e-7)  # on the z axis: unchanged
    np.testing.assert_allclose(out[:, 3], pts[:, 3], atol=1e-7)  # intensity kept
    with pytest.raises(ValueError, match="points_velo"):
        lidar.correct_kitti_scan(np.zeros((4, 2)))


def test_scan_in_camera_is_the_correction_then_the_calibration_transform():
    from twistslam.datasets.sensors import scan_in_camera
    from twistslam.geometry import so3_exp

    rng = np.random.default_rng(3)
    scan = np.hstack([rng.uniform(-60, 60, (500, 3)), rng.uniform(0, 1, (500, 1))]).astype(np.float32)
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = so3_exp(np.array([1.2, -1.1, 1.3])), [0.1, -0.2, 0.3]
    for angle in (0.0, 0.205):
        velo, cam = scan_in_camera(scan, T, angle)
        assert velo.dtype == cam.dtype == np.float32 and velo.shape == cam.shape == (500, 4)
        expected = lidar.correct_kitti_scan(scan, angle)
        np.testing.assert_allclose(velo, expected, atol=2e-5)
        np.testing.assert_allclose(cam[:, :3], expected[:, :3] @ T[:3, :3].T + T[:3, 3], atol=2e-5)
        np.testing.assert_array_equal(cam[:, 3], scan[:, 3])
    with pytest.raises(ValueError, match="points_velo"):
        scan_in_camera(np.zeros((4, 2), np.float32), T)
    with pytest.raises(ValueError, match="T_c_velo"):
        scan_in_camera(scan, np.full((4, 4), np.nan))
    with pytest.raises(ValueError, match="angle_deg"):
        scan_in_camera(scan, T, float("nan"))
    empty_velo, empty_cam = scan_in_camera(np.zeros((0, 4), np.float32), T)
    assert empty_velo.shape == empty_cam.shape == (0, 4)


def test_disparity_offset_estimate():
    rng = np.random.default_rng(0)
    z = rng.uniform(5, 60, 500)
    d = 389.0 / z - 0.6 + rng.normal(0, 0.2, z.size)
    z[:20] = np.nan  # keypoints without LiDAR depth
    off = lidar.estimate_disparity_offset(d, z, 389.0)
    assert off["valid"] and off["num_samples"] == 480
    assert off["offset_px"] == pytest.approx(0.6, abs=0.04)
    few = lidar.estimate_disparity_offset(d[20:30], z[20:30], 389.0)
    assert not few["valid"] and few["offset_px"] == 0.0
    with pytest.raises(ValueError, match="disparities"):
        lidar.estimate_disparity_offset(d, z[:-1], 389.0)


# --- real KITTI 0001 ---------------------------------------------------------------------

DYNAMIC = ("Car", "Van", "Truck", "Pedestrian", "Person_sitting", "Cyclist", "Tram", "Misc")
BANDS = ((5, 15), (15, 30), (30, 60))  # m, LiDAR depth


def static_mask(labels, frame):
    """0 on the 2D boxes of a-priori dynamic classes (labels stand in for segmentation)."""
    mask = np.ones((H, W), np.uint8)
    table = labels.in_frame(frame)
    for cls, (x0, y0, x1, y1) in zip(table.cls, table.box_2d):
        if cls in DYNAMIC:
            mask[max(int(y0), 0):int(np.ceil(y1)) + 1, max(int(x0), 0):int(np.ceil(x1)) + 1] = 0
    return mask


def collect_real_pairs():
    """Per frame: (measured disparity, LiDAR depth) of keypoints with both, static only."""
    root = require_real_data("kitti_tracking_lidar") / "training"
    calib = read_calibration(root / "calib" / "0001.txt")
    labels = read_labels(root / "label_02" / "0001.txt")
    cam = calib.stereo_camera(W, H)
    assert cam.disparity_offset == 0.0  # raw disparities: the offset is what we estimate
    T = calib.T_c_velo
    frames = []
    for i in range(27):
        left = read_image(root / "image_02" / "0001" / f"{i:06d}.png")
        right = read_image(root / "image_03" / "0001" / f"{i:06d}.png")
        velo = lidar.correct_kitti_scan(read_velodyne(root / "velodyne" / "0001" / f"{i:06d}.bin"))
        points_c = velo[:, :3] @ T[:3, :3].T + T[:3, 3]
        mask = static_mask(labels, i)
        scan = lidar.project_scan(points_c, cam, mask=mask)
        assert scan.num_masked > 0 or mask.all()
        assert mask[scan.uv[:, 1].astype(int), scan.uv[:, 0].astype(int)].all()
        m = features.match_stereo(left, right, cam, mask=mask)
        depth = lidar.lidar_depth_at(m["keypoints"], scan)
        both = m["matched"] & depth["valid"]
        disparity = m["keypoints"][both, 0] - m["u_right"][both]
        frames.append((disparity, depth["depth"][both]))
    return cam.fx * cam.baseline, frames


@pytest.fixture(scope="module")
def real_pairs():
    return collect_real_pairs()


def band_ratios(fx_b, disparity, z_lidar, offset):
    ratio = fx_b / (disparity + offset) / z_lidar  # stereo depth / LiDAR depth
    return {band: float(np.median(ratio[(z_lidar >= band[0]) & (z_lidar < band[1])]))
            for band in BANDS}


def test_real_lidar_depth_agrees_with_stereo_after_the_offset(real_pairs):
    fx_b, frames = real_pairs
    # Estimate on the even frames, check on the odd ones (held out).
    fit = [np.concatenate(x) for x in zip(*frames[0::2])]
    check = [np.concatenate(x) for x in zip(*frames[1::2])]
    off = lidar.estimate_disparity_offset(fit[0], fit[1], fx_b)
    assert off["valid"] and off["num_samples"] > 1000
    assert off["mad_px"] < 0.5  # LiDAR and stereo agree to a fraction of a pixel
    for band in BANDS:
        n = int(((check[1] >= band[0]) & (check[1] < band[1])).sum())
        assert n >= 200, f"only {n} held-out keypoints with LiDAR depth in {band} m"
    raw = band_ratios(fx_b, *check, 0.0)
    corrected = band_ratios(fx_b, *check, off["offset_px"])
    for band in BANDS:
        assert abs(corrected[band] - 1) < 0.01, (band, corrected, off)
    # Without the offset stereo is too deep, increasingly with range (so the check can fail).
    assert raw[(30, 60)] > 1.03 and raw[(30, 60)] > raw[(5, 15)]
