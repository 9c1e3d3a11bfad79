"""Result types of a sequence evaluation and their ``metrics.json`` form."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .camera import CameraMetrics
from .clear_mot import MotMetrics
from .difficulty import DIFFICULTIES, Difficulty

#: per-object metric keys, in the paper's column order
OBJECT_KEYS = (
    "ate", "rpe_t", "rpe_r", "yaw",
    "tp_2d", "motp_2d", "tp_bv", "motp_bv", "tp_3d", "motp_3d",
)


def json_value(x):
    """numpy scalars -> Python numbers; NaN / inf -> None (``null``, valid JSON)."""
    if isinstance(x, (np.integer, bool, np.bool_)):
        return int(x) if not isinstance(x, (bool, np.bool_)) else bool(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x


@dataclass(frozen=True)
class EvalSettings:
    """How objects are evaluated.

    ``object_alignment``: ``"none"`` reports the canonical object ATE (estimated boxes taken
    as they are), ``"se3"`` the ATE after Umeyama alignment of each estimated track onto its
    ground-truth track, for systems whose object frames are not canonical.
    ``protocol``: the rules that produced the object and MOT numbers, ``"clear"`` or
    ``"kitti"`` (:mod:`.protocol`).
    """

    iou_threshold: float = 0.25
    difficulty: Difficulty = DIFFICULTIES["easy"]
    cls: str = "car"
    object_alignment: str = "none"
    protocol: str = "clear"

    def to_dict(self) -> dict:
        """The ``settings`` section of ``metrics.json``."""
        return {
            "protocol": self.protocol, "difficulty": self.difficulty.name,
            "iou_threshold": self.iou_threshold, "class": self.cls,
            "object_alignment": self.object_alignment,
        }


@dataclass
class ObjectTrackMetrics:
    """One row of the paper's object tables: a ground-truth track and its paired estimate.

    Pose errors (``ate``, ``ate_aligned`` in m, ``rpe_t`` m/m, ``rpe_r`` deg/m) are NaN
    when no estimated track was ever matched to it in 3D; ``yaw`` (deg) is the mean heading
    error of the paired estimate's boxes over their common frames, each in its own camera
    frame, modulo 2 pi (a box facing backwards is 180 deg off); TP rates and MOTPs are in
    percent.
    """

    seq: str
    track_id: int
    cls: str
    est_track_id: int | None
    n_frames: int  # frames of the track inside the difficulty level
    n_pose_frames: int  # frames where both it and its paired estimate have a pose
    ate: float
    ate_aligned: float
    rpe_t: float
    rpe_r: float
    yaw: float
    tp_2d: float
    motp_2d: float
    tp_bv: float
    motp_bv: float
    tp_3d: float
    motp_3d: float

    def values(self, aligned: bool = False) -> dict[str, float]:
        """Metric values by :data:`OBJECT_KEYS`; ``aligned`` picks the aligned ATE."""
        out = {k: getattr(self, k) for k in OBJECT_KEYS}
        if aligned:
            out["ate"] = self.ate_aligned
        return out

    def to_dict(self, aligned: bool = False) -> dict:
        head = {"seq": self.seq, "track_id": int(self.track_id), "class": self.cls}
        return head | {k: json_value(v) for k, v in self.values(aligned).items()}


@dataclass
class Trajectories:
    """Poses kept for plots: camera ``T_w_c`` and object positions in the world frame."""

    camera_gt: np.ndarray | None = None
    camera_est: np.ndarray | None = None
    #: gt track id -> (gt positions (K, 3), paired estimate's positions (L, 3) or None)
    objects: dict[int, tuple[np.ndarray, np.ndarray | None]] = field(default_factory=dict)


@dataclass
class SequenceMetrics:
    """Everything ``twistslam eval`` reports for one sequence.

    ``camera`` is None without ``camera_poses.txt`` (or without ground-truth poses);
    ``objects`` is empty and ``mot`` is ``{}`` without tracking results.
    ``world_frame`` says where object poses were compared: ``"estimated camera poses"``,
    ``"ground-truth camera poses"`` or ``"camera frame"`` (no ground-truth poses).
    """

    seq: str
    settings: EvalSettings
    camera: CameraMetrics | None = None
    objects: list[ObjectTrackMetrics] = field(default_factory=list)
    mot: dict[str, MotMetrics] = field(default_factory=dict)
    world_frame: str = ""
    trajectories: Trajectories = field(default_factory=Trajectories, repr=False)

    @property
    def objects_mean(self) -> dict[str, float]:
        """Mean of each object metric over the tracks that have it (the paper's mean row)."""
        aligned = self.settings.object_alignment == "se3"
        rows = [o.values(aligned) for o in self.objects]
        out = {}
        for k in OBJECT_KEYS:
            vals = np.array([r[k] for r in rows], dtype=np.float64)
            vals = vals[np.isfinite(vals)]
            out[k] = float(vals.mean()) if len(vals) else float("nan")
        return out

    def to_dict(self) -> dict:
        """The ``metrics.json`` structure; absent inputs leave their section out.

        With tracking results, ``settings`` names the protocol, difficulty and IoU threshold
        behind ``objects`` and ``mot``, and every ``mot`` entry repeats its protocol.
        """
        out: dict = {}
        if self.camera is not None:
            out["camera"] = {k: json_value(v) for k, v in self.camera.to_dict().items()}
        if self.mot:
            out["settings"] = self.settings.to_dict()
            aligned = self.settings.object_alignment == "se3"
            out["objects"] = [o.to_dict(aligned) for o in self.objects]
            out["objects_mean"] = {k: json_value(v) for k, v in self.objects_mean.items()}
            out["mot"] = {
                mode: {k: json_value(v) for k, v in m.to_dict().items()}
                for mode, m in self.mot.items()
            }
        return out
