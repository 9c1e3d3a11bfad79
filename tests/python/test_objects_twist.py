"""Object twist estimation (paper eq. 4) through ``twistslam._core.objects``: a synthetic car
seen by the KITTI stereo rig moves on the road plane; outliers, mono input, bad shapes."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from twistslam import _core
from twistslam import geometry as g

P2 = np.array([[721.5377, 0, 609.5593, 44.85728], [0, 721.5377, 172.854, 0.2163791],
               [0, 0, 1, 0.002745884]])
P3 = np.array([[721.5377, 0, 609.5593, -339.5242], [0, 721.5377, 172.854, 2.199936],
               [0, 0, 1, 0.002729905]])
UP = np.array([0.0, -1.0, 0.0])  # world = first camera frame, y down


def pose(rotvec, t):
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    T[:3, 3] = t
    return T


def project(cam, X_c):
    """[u, v, u_right] of camera-frame points, as StereoCamera does (incl. disparity_offset)."""
    K = np.array([[cam.fx, 0, cam.cx], [0, cam.fy, cam.cy], [0, 0, 1]])
    left = (K @ (X_c + np.asarray(cam.t_left)).T).T
    right = (K @ (X_c + np.asarray(cam.t_right)).T).T
    return left[:, :2] / left[:, 2:], right[:, 0] / right[:, 2] + cam.disparity_offset


@pytest.fixture(scope="module")
def scene():
    rng = np.random.default_rng(0)
    cam = g.StereoCamera.from_kitti(P2, P3, 1242, 375)
    T_c_w = np.eye(4)
    T_w_o_prev = pose([0, 0.4, 0], [1.5, 0.9, 10.0])
    T_w_o_new = T_w_o_prev @ pose([0, np.radians(3), 0], [1.2, 0, 0])
    X_o = rng.uniform(-1, 1, (200, 3)) * [2.1, 0.75, 0.85]
    X_c = (T_c_w @ T_w_o_new @ np.c_[X_o, np.ones(200)].T).T[:, :3]
    uv, ur = project(cam, X_c)
    uv += rng.normal(0, 0.5, uv.shape)
    ur += rng.normal(0, 0.5, ur.shape)
    bad = rng.uniform(size=200) < 0.3
    uv[bad] = rng.uniform([5, 5], [1237, 370], (bad.sum(), 2))
    ur[bad] = uv[bad, 0] - rng.uniform(1, 80, bad.sum())
    return dict(cam=cam, T_c_w=T_c_w, T_w_o_prev=T_w_o_prev, T_w_o_new=T_w_o_new, X_o=X_o,
                uv=uv, u_right=ur, bad=bad)


def test_planar_twist_with_outliers(scene):
    Pi = g.projector_planar(UP)
    r = _core.objects.estimate_object_twist(scene["cam"], scene["T_c_w"], scene["T_w_o_prev"], Pi,
                                            scene["X_o"], scene["uv"], scene["u_right"])
    assert r["valid"], r["failure"]
    assert np.linalg.norm(r["T_w_o"][:3, 3] - scene["T_w_o_new"][:3, 3]) < 0.015
    np.testing.assert_allclose((np.eye(6) - Pi) @ r["xi"], 0, atol=1e-12)
    assert not (r["inlier"] & scene["bad"]).any()  # every outlier flagged
    assert r["inlier"].dtype == bool and r["inlier"].shape == (200,)
    assert r["covariance"].shape == (6, 6) and r["num_inliers"] > 120


def test_mono_and_options(scene):
    r = _core.objects.estimate_object_twist(scene["cam"], scene["T_c_w"], scene["T_w_o_prev"],
                                            g.projector_planar(UP), scene["X_o"], scene["uv"],
                                            max_iterations=50, min_inliers=20)
    assert r["valid"], r["failure"]
    assert np.linalg.norm(r["T_w_o"][:3, 3] - scene["T_w_o_new"][:3, 3]) < 0.05
    assert "huber_k" in _core.objects.default_twist_estimation_options()


def test_too_few_points_is_not_an_error(scene):
    r = _core.objects.estimate_object_twist(scene["cam"], scene["T_c_w"], scene["T_w_o_prev"],
                                            np.eye(6), scene["X_o"][:5], scene["uv"][:5])
    assert not r["valid"] and "too few" in r["failure"]


def test_bad_shapes_and_options(scene):
    f = _core.objects.estimate_object_twist
    args = (scene["cam"], scene["T_c_w"], scene["T_w_o_prev"], np.eye(6))
    with pytest.raises(ValueError, match="uv"):
        f(*args, scene["X_o"], scene["uv"][:10])
    with pytest.raises(ValueError, match="points_o"):
        f(*args, scene["X_o"][:, :2], scene["uv"])
    with pytest.raises(ValueError, match="u_right"):
        f(*args, scene["X_o"], scene["uv"], scene["u_right"][:3])
    with pytest.raises(ValueError, match="Pi"):
        f(scene["cam"], scene["T_c_w"], scene["T_w_o_prev"], np.eye(5), scene["X_o"], scene["uv"])
    with pytest.raises((TypeError, ValueError)):
        f(*args, scene["X_o"], scene["uv"], no_such_option=1)
