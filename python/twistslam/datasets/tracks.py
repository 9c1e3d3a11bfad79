"""Object tracks as world-frame pose sequences, from per-frame boxes.

An object pose is ``T_w_o = T_w_c(frame) @ T_c_o`` where ``T_c_o`` comes from the box: origin
at the box's geometric centre, rotated about the camera y axis by ``ry``, so the object x
axis (its length) is camera x when ``ry = 0`` (the box convention of :mod:`.objects`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .objects import DONT_CARE, ObjectTable


def box_poses(box_3d: np.ndarray) -> np.ndarray:
    """(N, 4, 4) ``T_c_o`` of boxes ``[cx, cy, cz, l, w, h, ry]``."""
    box_3d = np.asarray(box_3d, dtype=np.float64).reshape(-1, 7)
    c, s = np.cos(box_3d[:, 6]), np.sin(box_3d[:, 6])
    T = np.tile(np.eye(4), (len(box_3d), 1, 1))
    T[:, 0, 0], T[:, 0, 2] = c, s
    T[:, 2, 0], T[:, 2, 2] = -s, c
    T[:, :3, 3] = box_3d[:, :3]
    return T


def _finite_rigid(T: np.ndarray) -> np.ndarray:
    return np.isfinite(T).all(axis=(1, 2))


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
    valid &= _finite_rigid(T_w_c)
    return T_w_c @ T_c_o, valid


@dataclass
class ObjectTrack:
    """One object through the sequence: its poses, size and label attributes per frame."""

    track_id: int
    cls: str
    frames: np.ndarray  # (K,) int64, increasing
    T_w_o: np.ndarray  # (K, 4, 4) world pose (camera frame of each frame if no camera poses)
    size: np.ndarray  # (K, 3) l, w, h in metres
    truncation: np.ndarray  # (K,)
    occlusion: np.ndarray  # (K,)

    @property
    def velocity(self) -> np.ndarray:
        """(K-1, 3) m/s of the centre between consecutive labelled frames, 0.1 s a frame."""
        dt = np.diff(self.frames)[:, None] * 0.1
        return np.diff(self.T_w_o[:, :3, 3], axis=0) / dt


def object_tracks(table: ObjectTable, camera_poses: np.ndarray | None = None) -> dict[int, ObjectTrack]:
    """Tracks of every object with a track id (DontCare regions left out), keyed by id."""
    table = table.select((table.track_id >= 0) & (table.cls != DONT_CARE)).sorted()
    tracks = {}
    for tid in table.track_ids:
        rows = table.select(table.track_id == tid)
        T_w_o, ok = world_poses(rows.frame, rows.box_3d, camera_poses)
        rows = rows.select(ok)
        tracks[int(tid)] = ObjectTrack(
            track_id=int(tid), cls=str(rows.cls[0]) if len(rows) else "", frames=rows.frame,
            T_w_o=T_w_o[ok], size=rows.box_3d[:, 3:6], truncation=rows.truncation,
            occlusion=rows.occlusion,
        )
    return tracks
