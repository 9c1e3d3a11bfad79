"""Geometry bindings against scipy and numerical derivatives; shape checks at the boundary."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from twistslam import geometry as g

ANGLES = [0.0, 1e-10, 1e-5, 0.5, 2.0, np.pi - 1e-5, np.pi - 1e-9]


def random_twist(rng, angle):
    xi = rng.normal(size=6)
    xi[3:] *= angle / np.linalg.norm(xi[3:])
    return xi


@pytest.mark.parametrize("angle", ANGLES)
def test_so3_matches_scipy(angle):
    rng = np.random.default_rng(0)
    for _ in range(10):
        w = rng.normal(size=3)
        w *= angle / np.linalg.norm(w)
        R = g.so3_exp(w)
        np.testing.assert_allclose(R, Rotation.from_rotvec(w).as_matrix(), atol=1e-13)
        back = g.so3_log(R)
        # Compare rotations: at pi, w and -w are the same rotation.
        np.testing.assert_allclose(Rotation.from_rotvec(back).as_matrix(), R, atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(back), angle, atol=1e-9)


@pytest.mark.parametrize("angle", ANGLES)
def test_se3_exp_log_and_jacobians(angle):
    rng = np.random.default_rng(1)
    xi = random_twist(rng, angle)
    T = g.se3_exp(xi)
    np.testing.assert_allclose(T[:3, :3], Rotation.from_rotvec(xi[3:]).as_matrix(), atol=1e-13)
    np.testing.assert_allclose(g.se3_exp(g.se3_log(T)), T, atol=1e-9)
    # Left Jacobian by central differences of log(exp(xi + d) exp(xi)^-1).
    h = 1e-6
    J_num = np.zeros((6, 6))
    for k in range(6):
        d = np.zeros(6)
        d[k] = h
        plus = g.se3_log(g.se3_exp(xi + d) @ g.se3_inverse(T))
        minus = g.se3_log(g.se3_exp(xi - d) @ g.se3_inverse(T))
        J_num[:, k] = (plus - minus) / (2 * h)
    np.testing.assert_allclose(g.se3_left_jacobian(xi), J_num, atol=1e-6)
    # Right Jacobian: exp(xi + d) ~= exp(xi) exp(J_r d).
    J_r_num = np.zeros((6, 6))
    for k in range(6):
        d = np.zeros(6)
        d[k] = h
        plus = g.se3_log(g.se3_inverse(T) @ g.se3_exp(xi + d))
        minus = g.se3_log(g.se3_inverse(T) @ g.se3_exp(xi - d))
        J_r_num[:, k] = (plus - minus) / (2 * h)
    np.testing.assert_allclose(g.se3_right_jacobian(xi), J_r_num, atol=1e-6)
    np.testing.assert_allclose(
        g.se3_left_jacobian_inverse(xi) @ g.se3_left_jacobian(xi), np.eye(6), atol=1e-9
    )


def test_so3_jacobian_numeric():
    w = np.array([0.4, -1.1, 0.7])
    h = 1e-6
    J = np.zeros((3, 3))
    for k in range(3):
        d = np.zeros(3)
        d[k] = h
        J[:, k] = (g.so3_log(g.so3_exp(w + d) @ g.so3_exp(w).T) - g.so3_log(g.so3_exp(w - d) @ g.so3_exp(w).T)) / (2 * h)
    np.testing.assert_allclose(g.so3_left_jacobian(w), J, atol=1e-7)
    np.testing.assert_allclose(g.so3_right_jacobian(w), g.so3_left_jacobian(-w), atol=1e-15)


def test_adjoint_inverse_compose_transform():
    rng = np.random.default_rng(2)
    A, B = g.se3_exp(random_twist(rng, 1.0)), g.se3_exp(random_twist(rng, 2.5))
    xi = random_twist(rng, 0.3)
    np.testing.assert_allclose(g.se3_exp(g.se3_adjoint(A) @ xi), A @ g.se3_exp(xi) @ np.linalg.inv(A), atol=1e-12)
    np.testing.assert_allclose(g.se3_inverse(A), np.linalg.inv(A), atol=1e-12)
    np.testing.assert_allclose(g.se3_compose(A, B), A @ B, atol=1e-15)
    X = rng.normal(size=(50, 3))
    np.testing.assert_allclose(g.transform_points(A, X), X @ A[:3, :3].T + A[:3, 3], atol=1e-12)
    np.testing.assert_allclose(g.transform_points(A, X.astype(np.float32)), X @ A[:3, :3].T + A[:3, 3], atol=1e-5)
    np.testing.assert_allclose(g.twist_between(A, g.se3_exp(xi) @ A), xi, atol=1e-12)
    assert g.transform_points(A, np.zeros((0, 3))).shape == (0, 3)


def test_planar_projector():
    n = np.array([0.0, -1.0, 0.0])
    Pi = g.projector_planar(n)
    xi = np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])
    np.testing.assert_allclose(Pi @ xi, [1.0, 0.0, 3.0, 0.0, 0.2, 0.0], atol=1e-15)
    np.testing.assert_allclose(g.projector_free(), np.eye(6))
    with pytest.raises(ValueError):
        g.projector_planar([0.0, 0.0, 0.0])


@pytest.mark.parametrize(
    "call",
    [
        lambda: g.se3_exp(np.zeros(5)),
        lambda: g.se3_log(np.eye(3)),
        lambda: g.transform_points(np.eye(4), np.zeros((4, 2))),
        lambda: g.transform_points(np.eye(4), np.zeros(3)),
        lambda: g.box_iou_bev(np.zeros((2, 6)), np.zeros((2, 7))),
        lambda: g.box_iou_2d(np.zeros((2, 4)), np.zeros((2, 3, 4))),
        lambda: g.fit_plane_ransac(np.zeros((2, 3))),
        lambda: g.fit_plane_ransac(np.full((10, 3), np.nan)),
    ],
)
def test_wrong_shapes_raise_value_error(call):
    with pytest.raises(ValueError):
        call()


@pytest.mark.parametrize("call, message", [
    (lambda: g.so3_exp([np.nan, 0, 0]), r"w: contains NaN or Inf at \[0\]"),
    (lambda: g.se3_exp([0, 0, 0, 0, np.inf, 0]), r"xi: contains NaN or Inf at \[4\]"),
    (lambda: g.so3_left_jacobian([0, -np.inf, 0]), "w: contains NaN or Inf"),
    (lambda: g.projector_planar([0, np.nan, 1]), "normal: contains NaN or Inf"),
    (lambda: g.se3_log(np.ones((4, 4))), r"T: not a rigid transform .*last row"),
    (lambda: g.so3_log(3 * np.eye(3)), r"R: not a rotation: R\^T R differs from I by 8"),
    (lambda: g.so3_log(np.diag([1.0, 1.0, -1.0])), "R: not a rotation: det R = -1"),
    (lambda: g.se3_inverse(np.diag([2.0, 1, 1, 1])), "T: not a rigid transform"),
    (lambda: g.se3_compose(np.eye(4), np.diag([1.0, 1, 1, 2])), "B: not a rigid transform"),
    (lambda: g.twist_between(np.eye(4), np.full((4, 4), np.nan)), "T_b: contains NaN"),
    (lambda: g.transform_points(np.diag([1.0, 1, 1, 0]), np.zeros((2, 3))), "T: not a rigid"),
    (lambda: g.predict_constant_velocity(np.eye(4), 2 * np.eye(4)), "T_last: not a rigid"),
])
def test_non_finite_and_non_rigid_inputs_are_refused_by_name(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_rigid_transforms_rounded_to_text_precision_are_accepted():
    # poses read from KITTI-style text files carry ~6 significant digits
    rng = np.random.default_rng(7)
    T = g.se3_exp(rng.normal(size=6))
    rounded = np.array([[float(f"{v:.6e}") for v in row] for row in T])
    np.testing.assert_allclose(g.se3_exp(g.se3_log(rounded)), rounded, atol=1e-5)


def test_constant_velocity_prediction_repeats_the_last_motion():
    rng = np.random.default_rng(5)
    T_a = g.se3_exp(rng.normal(size=6))
    motion = g.se3_exp([0.8, 0.0, 0.1, 0.0, 0.02, 0.0])  # ~1 m forward, a slight turn
    T_b = motion @ T_a
    predicted = g.predict_constant_velocity(T_a, T_b)
    np.testing.assert_allclose(predicted, motion @ T_b, atol=1e-12)
    # the prediction of the inverses is the inverse of the prediction (T_w_c vs T_c_w)
    inverse = g.predict_constant_velocity(np.linalg.inv(T_a), np.linalg.inv(T_b))
    np.testing.assert_allclose(inverse, np.linalg.inv(predicted), atol=1e-12)
    # no motion: the last pose again
    np.testing.assert_allclose(g.predict_constant_velocity(T_b, T_b), T_b, atol=1e-12)


def test_facade_functions_are_typed_and_documented():
    import inspect
    import typing

    for name in g.__all__:
        obj = getattr(g, name)
        if inspect.isclass(obj):
            continue
        assert obj.__module__ == "twistslam.geometry", name
        hints = typing.get_type_hints(obj)
        assert "return" in hints and len(hints) == len(inspect.signature(obj).parameters) + 1, name
        assert obj.__doc__ and not obj.__doc__.startswith(name + "("), name


def test_non_numeric_input_raises_type_error():
    with pytest.raises(TypeError):
        g.se3_exp(np.array(["a"] * 6))
    with pytest.raises(TypeError):
        g.transform_points(np.eye(4), "points")


def test_plane_fit_from_python():
    rng = np.random.default_rng(3)
    xz = rng.uniform(-10, 10, size=(500, 2))
    road = np.column_stack([xz[:, 0], np.full(500, 1.65), xz[:, 1] + 15]) + rng.normal(0, 0.01, (500, 3))
    clutter = rng.uniform([-10, -3, 5], [10, 1, 25], size=(200, 3))
    fit = g.fit_plane_ransac(np.vstack([road, clutter]), inlier_threshold=0.05, seed=1)
    np.testing.assert_allclose(fit.plane, [0, -1, 0, 1.65], atol=5e-3)
    assert fit.inliers[:500].mean() > 0.99 and fit.inliers.dtype == bool
    assert fit.num_inliers == fit.inliers.sum()


def test_box_iou_matrices_and_corners():
    a = np.array([[0, 1, 10, 4, 2, 1.5, 0.0], [5, 1, 20, 4, 1.8, 1.5, 1.0]])
    b = a.copy()
    b[:, 0] += 0.5  # along the length axis of the first box (yaw 0)
    iou = g.box_iou_bev(a, b)
    assert iou.shape == (2, 2)
    assert iou[0, 0] == pytest.approx(3.5 / 4.5)
    assert iou[0, 1] == 0.0
    np.testing.assert_allclose(np.diag(g.box_iou_3d(a, a)), 1.0)
    corners = g.box_corners(a)
    assert corners.shape == (2, 8, 3)
    np.testing.assert_allclose(corners.mean(axis=1), a[:, :3], atol=1e-12)
    boxes_2d = np.array([[0, 0, 10, 10.0]])
    assert g.box_iou_2d(boxes_2d, boxes_2d + [5, 0, 5, 0])[0, 0] == pytest.approx(1 / 3)


def test_project_boxes_matches_corner_projection():
    P = np.array([[721.5, 0, 609.6, 44.86], [0, 721.5, 172.9, 0.216], [0, 0, 1, 0.0027]])
    boxes = np.array([[2.0, 1.0, 15.0, 4.0, 1.7, 1.5, 0.4], [-5.0, 1.0, 30.0, 3.5, 1.6, 1.4, -1.2]])
    corners = g.box_corners(boxes)
    uvw = np.einsum("ij,nkj->nki", P[:, :3], corners) + P[:, 3]
    uv = uvw[..., :2] / uvw[..., 2:]
    expected = np.column_stack([uv[..., 0].min(1), uv[..., 1].min(1), uv[..., 0].max(1), uv[..., 1].max(1)])
    np.testing.assert_allclose(g.project_boxes(boxes, P), expected, atol=1e-9)


def test_stereo_camera_from_kitti(tmp_path):
    P2 = np.array([[721.5377, 0, 609.5593, 44.85728], [0, 721.5377, 172.854, 0.2163791], [0, 0, 1, 0.002745884]])
    P3 = np.array([[721.5377, 0, 609.5593, -339.5242], [0, 721.5377, 172.854, 2.199936], [0, 0, 1, 0.002729905]])
    cam = g.StereoCamera.from_kitti(P2, P3, 1242, 375)
    assert cam.baseline == pytest.approx(0.5327, abs=1e-3)
    X = np.array([[2.0, 1.0, 15.0], [0.0, 0.0, -5.0]])
    uv = cam.project(X)
    np.testing.assert_allclose(uv[0], (P2 @ np.append(X[0], 1))[:2] / (P2 @ np.append(X[0], 1))[2])
    assert np.isnan(uv[1]).all()
    uv_r = cam.project(X[:1], right=True)
    back = cam.triangulate(uv[:1], uv[:1, 0] - uv_r[:, 0])
    np.testing.assert_allclose(back, X[:1], atol=2e-3)
    with pytest.raises(ValueError):
        cam.triangulate(uv, np.ones(3))
    with pytest.raises(ValueError):
        g.StereoCamera.from_kitti(P2, P2 * [[1.1], [1], [1]], 1242, 375)
