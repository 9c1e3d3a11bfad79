"""Camera trajectory metrics: RPE per frame (mean, RMSE) and ATE RMSE."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .trajectory import ate_errors, mean, relative_errors, rmse, valid_pose_mask


@dataclass
class CameraMetrics:
    """Camera accuracy of one sequence.

    Attributes
    ----------
    rpe_t_mean, rpe_t_rmse : RPE translation (m/frame) over consecutive frames.
    rpe_r_mean, rpe_r_rmse : RPE rotation (deg/frame) over consecutive frames.
    ate_rmse : ATE RMSE (m) after SE(3) Umeyama alignment of the estimate onto the ground
        truth. This is the value written as ``ate_rmse`` in ``metrics.json``.
    ate_rmse_unaligned : ATE RMSE (m) with no alignment (both trajectories start in the
        first camera frame, so a good system scores well here too).
    n_frames : ground-truth frames.
    n_evaluated : frames with a finite estimate (used by ATE).
    n_skipped : frames whose estimate is NaN or missing (file shorter than the sequence).
    n_pairs : consecutive frame pairs used by RPE.
    n_beyond_gt : frames with an estimate past the end of the ground truth (not evaluated).
    """

    rpe_t_mean: float
    rpe_r_mean: float
    rpe_t_rmse: float
    rpe_r_rmse: float
    ate_rmse: float
    ate_rmse_unaligned: float
    n_frames: int
    n_evaluated: int
    n_skipped: int
    n_pairs: int
    n_beyond_gt: int = 0

    def to_dict(self) -> dict[str, float]:
        """The ``camera`` section of ``metrics.json``."""
        keys = ("rpe_t_mean", "rpe_r_mean", "rpe_t_rmse", "rpe_r_rmse", "ate_rmse")
        return {k: getattr(self, k) for k in keys}


def evaluate_camera(gt_poses: np.ndarray, est_poses: np.ndarray) -> CameraMetrics:
    """Compare estimated camera poses ``T_w_c`` with ground truth, frame by frame.

    Parameters
    ----------
    gt_poses : (N, 4, 4) ground truth, frame ``i`` at row ``i``.
    est_poses : (M, 4, 4) estimate, same indexing. Rows that hold NaN, and frames past the
        end of a shorter estimate, are skipped and counted in ``n_skipped``; rows past the
        end of the ground truth are ignored.

    Notes
    -----
    RPE is a per-frame quantity (m/frame), so it only uses pairs of *adjacent* frames
    ``(i, i+1)`` that both have an estimate; a gap does not create a longer pair.
    """
    gt = np.asarray(gt_poses, dtype=np.float64)
    est = np.full_like(gt, np.nan)
    m = min(len(gt), len(est_poses))
    est[:m] = np.asarray(est_poses, dtype=np.float64)[:m]
    ok = valid_pose_mask(est) & valid_pose_mask(gt)
    beyond = np.asarray(est_poses, dtype=np.float64)[len(gt):]  # no ground truth to compare

    ate = ate_errors(gt[ok], est[ok], aligned=False)
    ate_al = ate_errors(gt[ok], est[ok], aligned=True)

    starts = np.flatnonzero(ok[:-1] & ok[1:])
    t_err, r_err = relative_errors(gt, est, np.stack([starts, starts + 1], axis=1))
    r_err = np.rad2deg(r_err)

    return CameraMetrics(
        rpe_t_mean=mean(t_err), rpe_r_mean=mean(r_err),
        rpe_t_rmse=rmse(t_err), rpe_r_rmse=rmse(r_err),
        ate_rmse=rmse(ate_al), ate_rmse_unaligned=rmse(ate),
        n_frames=len(gt), n_evaluated=int(ok.sum()), n_skipped=int(len(gt) - ok.sum()),
        n_pairs=len(starts),
        n_beyond_gt=int(np.isfinite(beyond.reshape(len(beyond), -1)).all(axis=1).sum())
        if len(beyond) else 0,
    )
