"""Camera trajectories in the KITTI odometry format: one row-major 3x4 ``T_w_c`` per line."""

from __future__ import annotations

import numpy as np

from ._parsing import PathLike, ensure_parent, format_float, iter_lines, parse_error, to_floats


def read_poses(path: PathLike) -> np.ndarray:
    """Read ``(N, 4, 4)`` float64 poses ``T_w_c`` (12 numbers per line, row-major 3x4).

    Raises
    ------
    ValueError
        ``"<file>:<line>: expected 12 values, got n"``, an unparsable number, or a row
        that is neither 12 finite numbers nor 12 NaN (the rows ``Result.save`` writes for
        frames without a pose, which the evaluator skips).
    """
    rows = []
    for line_no, tokens in iter_lines(path):
        if len(tokens) != 12:
            raise parse_error(path, line_no, f"expected 12 values, got {len(tokens)}")
        row = to_floats(tokens, path, line_no, "pose", finite=False)
        if not np.isfinite(row).all() and not np.isnan(row).all():
            raise parse_error(path, line_no, "pose: expected 12 finite numbers, or 12 NaN for "
                              "a frame without a pose")
        rows.append(row)
    poses = np.tile(np.eye(4), (len(rows), 1, 1))
    if rows:
        poses[:, :3, :] = np.stack(rows).reshape(-1, 3, 4)
    return poses


def write_poses(path: PathLike, poses: np.ndarray) -> None:
    """Write ``(N, 4, 4)`` (or ``(N, 3, 4)``) poses, one row-major 3x4 per line, losslessly."""
    poses = np.asarray(poses, dtype=np.float64)
    if poses.ndim != 3 or poses.shape[1:] not in ((4, 4), (3, 4)):
        raise ValueError(f"write_poses: expected (N, 4, 4) poses, got shape {poses.shape}")
    path = ensure_parent(path)
    with open(path, "w", encoding="utf-8") as f:
        for T in poses:
            f.write(" ".join(format_float(v) for v in T[:3, :].reshape(-1)) + "\n")
