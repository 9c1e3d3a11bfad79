"""Object trajectories from boxes, and per-track ATE / RPE.

An object pose is ``T_w_o = T_w_c(frame) @ T_c_o`` where ``T_c_o`` comes from the box:
origin at the box's geometric centre, rotated about the camera y axis by ``ry`` (so the
object x axis, its length, is camera x when ``ry = 0``; see ``datasets/objects.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .trajectory import ate_errors, invert, relative_errors, rmse, valid_pose_mask

#: below this total ground-truth path length (m) RPE per metre is undefined (a parked car
#: seen with exact ground truth); reported as NaN rather than a huge number
MIN_TRACK_LENGTH = 1e-9


def box_poses(box_3d: np.ndarray) -> np.ndarray:
    """(N, 4, 4) ``T_c_o`` of boxes ``[cx, cy, cz, l, w, h, ry]``."""
    box_3d = np.asarray(box_3d, dtype=np.float64).reshape(-1, 7)
    c, s = np.cos(box_3d[:, 6]), np.sin(box_3d[:, 6])
    T = np.tile(np.eye(4), (len(box_3d), 1, 1))
    T[:, 0, 0], T[:, 0, 2] = c, s
    T[:, 2, 0], T[:, 2, 2] = -s, c
    T[:, :3, 3] = box_3d[:, :3]
    return T


def world_poses(
    frames: np.ndarray, box_3d: np.ndarray, camera_poses: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """Object poses ``T_w_o`` and a validity mask.

    Parameters
    ----------
    frames : (N,) frame index of each box.
    box_3d : (N, 7) boxes in the camera frame of their frame.
    camera_poses : (F, 4, 4) ``T_w_c`` indexed by frame, or None to stay in each frame's
        camera frame (``T_w_c = I``). Boxes whose frame has no finite camera pose are
        flagged invalid.
    """
    T_c_o = box_poses(box_3d)
    if camera_poses is None:
        return T_c_o, np.ones(len(T_c_o), dtype=bool)
    frames = np.asarray(frames, dtype=np.int64)
    valid = (frames >= 0) & (frames < len(camera_poses))
    T_w_c = np.tile(np.eye(4), (len(frames), 1, 1))
    T_w_c[valid] = camera_poses[frames[valid]]
    valid &= valid_pose_mask(T_w_c)
    return T_w_c @ T_c_o, valid


@dataclass
class TrackPoseErrors:
    """Pose accuracy of one estimated track against its ground-truth track.

    Attributes
    ----------
    n_frames : frames where both tracks have a pose (the compared poses).
    ate, ate_aligned : ATE RMSE (m), canonical (no alignment) and after SE(3) Umeyama
        alignment of the estimated positions onto the ground truth.
    rpe_t : RPE translation (m/m) = sum of the translation errors of consecutive compared
        poses / sum of the ground-truth distances between them. Summing before dividing
        keeps a car that is parked for a while from dividing by zero (per-step ratios
        would); only a track that never moves has no value (NaN).
    rpe_r : RPE rotation (deg/m), the rotation errors summed the same way.
        A rigid alignment moves every pose alike, so RPE is the same in both variants.
    length : ground-truth distance travelled over the compared poses (m).
    """

    n_frames: int
    ate: float
    ate_aligned: float
    rpe_t: float
    rpe_r: float
    length: float


def track_pose_errors(
    gt_frames: np.ndarray, gt_poses: np.ndarray, est_frames: np.ndarray, est_poses: np.ndarray
) -> TrackPoseErrors:
    """Compare two trajectories on their common frames (consecutive common frames form
    the RPE pairs, so a gap in the estimate yields one longer step, still per metre)."""
    common, gi, ei = np.intersect1d(gt_frames, est_frames, return_indices=True)
    Q, P = gt_poses[gi], est_poses[ei]
    t_err, r_err = relative_errors(Q, P)
    steps = invert(Q[:-1]) @ Q[1:] if len(Q) > 1 else np.zeros((0, 4, 4))
    length = float(np.linalg.norm(steps[:, :3, 3], axis=1).sum())
    nan = float("nan")
    per_m = length > MIN_TRACK_LENGTH
    return TrackPoseErrors(
        n_frames=len(common),
        ate=rmse(ate_errors(Q, P)),
        ate_aligned=rmse(ate_errors(Q, P, aligned=True)),
        rpe_t=float(t_err.sum() / length) if per_m else nan,
        rpe_r=float(np.rad2deg(r_err).sum() / length) if per_m else nan,
        length=length,
    )
