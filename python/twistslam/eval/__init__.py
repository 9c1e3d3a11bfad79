"""Evaluation against KITTI tracking ground truth: camera RPE / ATE, per-object ATE / RPE,
TP rate and MOTP in 2D, bird view and 3D, CLEAR MOT, paper-style tables and plots.

>>> from twistslam.eval import evaluate_sequence
>>> m = evaluate_sequence("/data/kitti_tracking", "results/", seq="0001")  # doctest: +SKIP
>>> m.to_dict()["mot"]["3d"]["mota"]  # doctest: +SKIP
"""

from .camera import CameraMetrics, evaluate_camera
from .clear_mot import MotMetrics, clear_mot
from .difficulty import DIFFICULTIES, Difficulty, get_difficulty
from .matching import MODES, Matching, assign, iou_function, match_sequence
from .metrics import EvalSettings, ObjectTrackMetrics, SequenceMetrics
from .object_poses import TrackPoseErrors, box_poses, track_pose_errors, world_poses
from .report import build_tables, load_paper_tables, render_markdown, render_text
from .results import ResultsNotFoundError, SequenceResults, load_results
from .sequence import evaluate_sequence
from .track_metrics import TrackDetection, pair_tracks, track_detection
from .trajectory import align, ate_errors, relative_errors, umeyama_alignment

__all__ = [
    "DIFFICULTIES", "MODES",
    "CameraMetrics", "Difficulty", "EvalSettings", "Matching", "MotMetrics",
    "ObjectTrackMetrics", "ResultsNotFoundError", "SequenceMetrics", "SequenceResults",
    "TrackDetection", "TrackPoseErrors",
    "align", "assign", "ate_errors", "box_poses", "build_tables", "clear_mot",
    "evaluate_camera", "evaluate_sequence", "get_difficulty", "iou_function",
    "load_paper_tables", "load_results", "match_sequence", "pair_tracks", "plot_trajectories",
    "relative_errors", "render_markdown", "render_text", "track_detection", "track_pose_errors",
    "umeyama_alignment", "world_poses",
]


def plot_trajectories(*args, **kwargs):
    """See :func:`twistslam.eval.plots.plot_trajectories` (imports matplotlib on first use)."""
    from .plots import plot_trajectories as _plot

    return _plot(*args, **kwargs)
