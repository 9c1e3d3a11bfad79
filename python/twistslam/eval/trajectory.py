"""Trajectory errors: Umeyama alignment, ATE and RPE on (N, 4, 4) pose arrays.

Poses are ``T_w_x`` (DESIGN.md): they map points of the moving frame ``x`` (camera or
object) into the world. Ground truth is ``Q``, the estimate ``P``. The definitions follow
Zhang & Scaramuzza's tutorial (as evo implements them), so our numbers are comparable with
evo's ``APE``/``RPE`` with ``PoseRelation.translation_part`` / ``rotation_angle_deg`` and
``delta = 1``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def invert(T: np.ndarray) -> np.ndarray:
    """Inverse of one (4, 4) or a stack (N, 4, 4) of rigid transforms, in closed form."""
    R = np.swapaxes(T[..., :3, :3], -1, -2)
    out = np.zeros_like(T)
    out[..., :3, :3] = R
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", R, T[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def rotation_angle(R: np.ndarray) -> np.ndarray:
    """Angle (rad) of rotation matrices (..., 3, 3), via the rotation vector.

    ``arccos((trace - 1) / 2)`` loses half the digits near zero, where frame-to-frame errors
    live; the rotation-vector norm keeps full precision.
    """
    flat = np.asarray(R, dtype=np.float64).reshape(-1, 3, 3)
    return Rotation.from_matrix(flat).magnitude().reshape(np.shape(R)[:-2])


def valid_pose_mask(poses: np.ndarray) -> np.ndarray:
    """(N,) bool: the pose is finite everywhere (NaN marks a frame the system did not output)."""
    return np.isfinite(poses.reshape(len(poses), -1)).all(axis=1)


def umeyama_alignment(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Rigid transform ``T`` (4, 4) minimising ``sum |dst_i - T src_i|^2`` (no scale).

    Umeyama (1991), SE(3) case: SVD of the cross-covariance, with the sign correction that
    keeps ``det(R) = +1`` when the points are (nearly) planar or collinear.

    Parameters
    ----------
    src, dst : (N, 3) corresponding points, N >= 1 (N = 1 gives a pure translation).
    """
    src = np.asarray(src, dtype=np.float64)
    dst = np.asarray(dst, dtype=np.float64)
    mu_s, mu_d = src.mean(axis=0), dst.mean(axis=0)
    cov = (dst - mu_d).T @ (src - mu_s) / len(src)
    U, _, Vt = np.linalg.svd(cov)
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        S[2, 2] = -1.0
    R = U @ S @ Vt
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = mu_d - R @ mu_s
    return T


def align(gt: np.ndarray, est: np.ndarray) -> np.ndarray:
    """``est`` moved by the SE(3) Umeyama transform of its positions onto ``gt``'s."""
    T = umeyama_alignment(est[:, :3, 3], gt[:, :3, 3])
    return T @ est


def ate_errors(gt: np.ndarray, est: np.ndarray, aligned: bool = False) -> np.ndarray:
    """Per-pose absolute translation error ``|t(Q_i^-1 P_i)| = |p_i - q_i|`` (m).

    With ``aligned=True`` the estimate is first moved onto the ground truth by
    :func:`align` (for systems whose world frame is arbitrary).
    """
    if aligned and len(gt):
        est = align(gt, est)
    return np.linalg.norm(est[:, :3, 3] - gt[:, :3, 3], axis=1)


def relative_errors(
    gt: np.ndarray, est: np.ndarray, pairs: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Translation (m) and rotation (rad) of ``E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)``.

    Parameters
    ----------
    gt, est : (N, 4, 4) poses with matching rows.
    pairs : (K, 2) row indices ``(i, j)``; default consecutive rows ``(k, k+1)``. Callers
        choose the rows (adjacent frames for the camera, common frames for an object track).

    Returns
    -------
    (trans, rot) : two (K,) arrays.
    """
    if pairs is None:
        idx = np.arange(max(len(gt) - 1, 0))
        pairs = np.stack([idx, idx + 1], axis=1)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if not len(pairs):
        return np.zeros(0), np.zeros(0)
    i, j = pairs[:, 0], pairs[:, 1]
    dq = invert(gt[i]) @ gt[j]
    dp = invert(est[i]) @ est[j]
    E = invert(dq) @ dp
    return np.linalg.norm(E[:, :3, 3], axis=1), rotation_angle(E[:, :3, :3])


def rmse(values: np.ndarray) -> float:
    """Root mean square, NaN for an empty array (no silent zero for 'no data')."""
    return float(np.sqrt(np.mean(np.square(values)))) if len(values) else float("nan")


def mean(values: np.ndarray) -> float:
    return float(np.mean(values)) if len(values) else float("nan")
