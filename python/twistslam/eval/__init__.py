"""Evaluation against KITTI tracking ground truth: camera RPE / ATE, per-object ATE / RPE,
TP rate and MOTP in 2D, bird view and 3D, CLEAR MOT under two protocols (``clear``, the
definitions; ``kitti``, the devkit as 3D MOT papers run it), sAMOTA / AMOTA / AMOTP, HOTA,
paper-style tables and plots.

>>> from twistslam.eval import evaluate_mot, evaluate_sequence
>>> m = evaluate_sequence("kitti_tracking", "results/", seq="0001")  # doctest: +SKIP
>>> m.to_dict()["mot"]["3d"]["mota"]  # doctest: +SKIP
>>> r = evaluate_mot("kitti_tracking", "results/", ["0001", "0006"])  # doctest: +SKIP
>>> r.overall.samota, r.sequences["0001"].idsw  # doctest: +SKIP
"""

from .amota import ScoreSweep, recall_thresholds, score_sweep
from .box_ends import BoxEndsResult, box_end_offsets, evaluate_box_ends
from .camera import CameraMetrics, evaluate_camera
from .clear_mot import MotMetrics, clear_mot, pool_mot
from .devkit import devkit_mot
from .difficulty import DIFFICULTIES, Difficulty, get_difficulty
from .hota import HotaFrames, HotaResult, hota, hota_frames, pool_hota
from .matching import (
    MODES, Matching, SequenceOverlaps, assign, iou_function, match_sequence, sequence_overlaps,
)
from .metrics import EvalSettings, ObjectTrackMetrics, SequenceMetrics
from .mot import MotEvaluation, evaluate_mot, sequence_mot
from .object_poses import TrackPoseErrors, box_poses, track_pose_errors, world_poses
from .protocol import PROTOCOLS, Protocol, get_protocol
from .report import build_tables, load_paper_tables, render_markdown, render_text
from .results import ResultsNotFoundError, SequenceResults, load_results
from .sequence import evaluate_sequence
from .track_metrics import TrackDetection, pair_tracks, track_detection
from .trajectory import align, ate_errors, relative_errors, umeyama_alignment

__all__ = [
    "DIFFICULTIES", "MODES", "PROTOCOLS",
    "BoxEndsResult", "CameraMetrics", "Difficulty", "EvalSettings", "HotaFrames", "HotaResult", "Matching",
    "MotEvaluation", "MotMetrics", "ObjectTrackMetrics", "Protocol", "ResultsNotFoundError",
    "ScoreSweep", "SequenceMetrics", "SequenceOverlaps", "SequenceResults",
    "TrackDetection", "TrackPoseErrors",
    "align", "assign", "ate_errors", "box_end_offsets", "box_poses", "build_tables", "clear_mot", "devkit_mot",
    "evaluate_box_ends", "evaluate_camera", "evaluate_mot", "evaluate_sequence", "get_difficulty", "get_protocol",
    "hota", "hota_frames", "iou_function", "load_paper_tables", "load_results",
    "match_sequence", "pair_tracks", "plot_trajectories", "pool_hota", "pool_mot",
    "recall_thresholds", "relative_errors", "render_markdown", "render_text", "score_sweep",
    "sequence_mot", "sequence_overlaps", "track_detection", "track_pose_errors",
    "umeyama_alignment", "world_poses",
]


def plot_trajectories(*args, **kwargs):
    """See :func:`twistslam.eval.plots.plot_trajectories` (imports matplotlib on first use)."""
    from .plots import plot_trajectories as _plot

    return _plot(*args, **kwargs)
from .object_tracks import ObjectTrackEvaluation, evaluate_object_tracks, load_ground_truth  # noqa: E402,F401
