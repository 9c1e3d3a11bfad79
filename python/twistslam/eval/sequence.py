"""``evaluate_sequence``: every metric of one KITTI tracking sequence from a results dir."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..datasets import KittiTracking, MissingDataWarning, ObjectTable
from .camera import evaluate_camera
from .difficulty import Difficulty, get_difficulty
from .matching import MODES, Matching, iou_function, sequence_overlaps
from .metrics import EvalSettings, ObjectTrackMetrics, SequenceMetrics, Trajectories
from .mot import sequence_mot
from .object_poses import TrackPoseErrors, track_pose_errors, world_poses
from .object_yaw import heading_error_deg
from .protocol import Protocol, get_protocol
from .results import load_results, seq_name
from .track_metrics import pair_tracks, track_detection


def open_dataset(root: str | Path, seq: int | str, split: str = "training") -> KittiTracking:
    """A :class:`KittiTracking` for evaluation: only labels, poses and calibration are used,
    so warnings about missing images or LiDAR are silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MissingDataWarning)
        return KittiTracking(root, seq, split=split)


def _image_size(dataset) -> tuple[int, int]:
    """(width, height) of the sequence's left images, (0, 0) when none is on disk."""
    base, seq = getattr(dataset, "base", None), getattr(dataset, "seq", None)
    if base is None or seq is None:
        return 0, 0
    first = next(iter(sorted((Path(base) / "image_02" / str(seq)).glob("*.png"))), None)
    if first is None:
        return 0, 0
    from PIL import Image

    with Image.open(first) as im:
        return im.size


def fill_missing_box_2d(table: ObjectTable, dataset) -> ObjectTable:
    """Rows without an image box (``-1`` placeholders, the devkit's "no 2D") get the
    projection of their 3D box through ``P2`` (the paper's "projected 3D box"), clipped to
    the image when the sequence's images are on disk."""
    missing = (table.box_2d == -1).any(axis=1)
    if not missing.any():
        return table
    from .matching import _geometry

    box_2d = table.box_2d.copy()
    width, height = _image_size(dataset)
    box_2d[missing] = _geometry().project_boxes(
        table.box_3d[missing], dataset.calib.P2, width, height
    )
    return ObjectTable(**{**vars(table), "box_2d": box_2d})


def ground_truth(dataset, name: str) -> ObjectTable:
    """The sequence's labels; ``FileNotFoundError`` naming the label file looked for."""
    gt = dataset.gt_objects
    if gt is None:
        base = getattr(dataset, "base", None)
        where = (Path(base) / "label_02" / f"{name}.txt" if base is not None
                 else f"{dataset!r} has no gt_objects")
        raise FileNotFoundError(f"sequence {name}: ground-truth labels not found: {where}")
    return gt


def _object_rows(
    seq: str, cls: str, gt: ObjectTable, est: ObjectTable, matchings: dict[str, Matching],
    gt_T_w_c: np.ndarray | None, est_T_w_c: np.ndarray | None, traj: Trajectories,
) -> list[ObjectTrackMetrics]:
    """One row per ground-truth track counted by CLEAR MOT (evaluated class, at least one
    frame inside the difficulty level); its estimate is the tracker paired in 3D."""
    detection = {mode: track_detection(m) for mode, m in matchings.items()}
    pairs = pair_tracks(matchings["3d"])
    no_pose = TrackPoseErrors(0, float("nan"), float("nan"), float("nan"), float("nan"), 0.0)
    rows = []
    for tid in sorted(detection["3d"]):
        g = gt.select(gt.track_id == tid)
        Q, ok = world_poses(g.frame, g.box_3d, gt_T_w_c)
        gt_frames, Q = g.frame[ok], Q[ok]
        pose, est_xyz, est_tid = no_pose, None, pairs.get(tid)
        yaw = float("nan")
        if est_tid is not None:
            e = est.select(est.track_id == est_tid)
            P, ok = world_poses(e.frame, e.box_3d, est_T_w_c)
            pose = track_pose_errors(gt_frames, Q, e.frame[ok], P[ok])
            est_xyz = P[ok][np.argsort(e.frame[ok]), :3, 3]
            # headings in each frame's own camera (the boxes' ry): no camera error enters
            _, gi, ei = np.intersect1d(g.frame, e.frame, return_indices=True)
            if len(gi):
                yaw = float(np.mean(heading_error_deg(e.box_3d[ei, 6], g.box_3d[gi, 6])))
        traj.objects[tid] = (Q[np.argsort(gt_frames), :3, 3], est_xyz)
        d = {mode: detection[mode][tid] for mode in MODES}
        rows.append(ObjectTrackMetrics(
            seq=seq, track_id=tid, cls=cls, est_track_id=est_tid,
            n_frames=d["3d"].n_frames, n_pose_frames=pose.n_frames,
            ate=pose.ate, ate_aligned=pose.ate_aligned, rpe_t=pose.rpe_t, rpe_r=pose.rpe_r,
            yaw=yaw, tp_2d=d["2d"].tp_rate, motp_2d=d["2d"].motp,
            tp_bv=d["bv"].tp_rate, motp_bv=d["bv"].motp,
            tp_3d=d["3d"].tp_rate, motp_3d=d["3d"].motp,
        ))
    return rows


def evaluate_sequence(
    dataset_or_root,
    results_dir: str | Path,
    seq: int | str | None = None,
    *,
    iou_threshold: float = 0.25,
    difficulty: str | Difficulty | None = None,
    cls: str = "car",
    object_alignment: str = "none",
    split: str = "training",
    protocol: str | Protocol = "clear",
    score_metrics: bool = True,
) -> SequenceMetrics:
    """Evaluate a system's output for one sequence against KITTI tracking ground truth.

    Parameters
    ----------
    dataset_or_root : a :class:`~twistslam.datasets.KittiTracking` (or any object with
        ``gt_objects``, ``gt_poses``, ``calib``) or the dataset root directory.
    results_dir : holds ``camera_poses.txt`` and/or ``tracking/<seq>.txt``.
    seq : sequence number; defaults to the dataset's own.
    iou_threshold : minimum IoU of a true positive (2D, BV and 3D alike).
    difficulty : ``"easy"``, ``"moderate"``, ``"hard"`` or a :class:`Difficulty`; None
        takes the protocol's default (``clear``: easy, ``kitti``: hard).
    cls : evaluated class (``car`` or ``pedestrian``; others have no neighbour class).
    object_alignment : ``"none"`` (canonical object ATE) or ``"se3"`` (Umeyama-aligned).
    protocol : ``"clear"`` (CLEAR MOT definitions, the paper's object tables) or
        ``"kitti"`` (the KITTI devkit as AB3DMOT runs it); see :mod:`.protocol`. It decides
        CLEAR MOT, sAMOTA and HOTA, and which ground truth the per-object TP rates count.
    score_metrics : compute sAMOTA / AMOTA / AMOTP (about 40 re-matchings per overlap
        mode); False leaves them NaN.

    Notes
    -----
    Estimated objects are placed in the world with the estimated camera poses when the
    results hold ``camera_poses.txt``, else with the ground-truth poses. Without any
    ground-truth camera poses (KITTI tracking without oxts) both sides stay in each
    frame's camera frame (``T_w_c = I``) and a warning says so.
    """
    if not 0.0 < iou_threshold <= 1.0:
        raise ValueError(f"iou_threshold must be in (0, 1], got {iou_threshold}")
    if object_alignment not in ("none", "se3"):
        raise ValueError(f"object_alignment must be 'none' or 'se3', got {object_alignment!r}")
    if isinstance(dataset_or_root, (str, Path)):
        if seq is None:
            raise ValueError("evaluate_sequence: give seq when passing a dataset root")
        dataset = open_dataset(dataset_or_root, seq, split)
    else:
        dataset = dataset_or_root
        seq = seq if seq is not None else getattr(dataset, "seq")
    name = seq_name(seq)
    protocol = get_protocol(protocol)
    settings = EvalSettings(
        iou_threshold, get_difficulty(difficulty or protocol.default_difficulty), cls.lower(),
        object_alignment, protocol.name,
    )
    results = load_results(results_dir, name)
    gt_T_w_c = dataset.gt_poses
    out = SequenceMetrics(seq=name, settings=settings)

    if gt_T_w_c is None:
        # one warning for everything the missing poses change
        consequences = []
        if results.camera_poses is not None:
            consequences.append("the camera is not evaluated")
        if results.tracking is not None:
            consequences.append("objects are compared in each frame's camera frame (T_w_c = I)")
        warnings.warn(f"sequence {name}: no ground-truth camera poses (no poses/ or oxts/): "
                      + " and ".join(consequences), stacklevel=2)
    elif results.camera_poses is not None:
        out.camera = evaluate_camera(gt_T_w_c, results.camera_poses)
        if out.camera.n_beyond_gt:
            n = len(gt_T_w_c)
            warnings.warn(f"sequence {name}: {results.camera_path} has poses for "
                          f"{out.camera.n_beyond_gt} frames past the ground truth's {n}: the "
                          f"camera is evaluated on frames 0-{n - 1} only", stacklevel=2)
        out.trajectories.camera_gt = gt_T_w_c
        out.trajectories.camera_est = results.camera_poses

    if results.tracking is not None and dataset.gt_objects is None and out.camera is not None:
        # a run on a sequence without labels (its objects came from a detector): the camera
        # is still evaluated, the objects cannot be (with nothing else to evaluate, the
        # missing labels stay an error, below)
        try:
            ground_truth(dataset, name)
        except FileNotFoundError as exc:
            warnings.warn(f"{exc}: the objects are not evaluated", stacklevel=2)
    elif results.tracking is not None:
        gt = ground_truth(dataset, name)
        if gt_T_w_c is None:
            est_T_w_c, out.world_frame = None, "camera frame"
        elif results.camera_poses is not None:
            est_T_w_c, out.world_frame = results.camera_poses, "estimated camera poses"
        else:
            est_T_w_c, out.world_frame = gt_T_w_c, "ground-truth camera poses"
        est = fill_missing_box_2d(results.tracking, dataset)
        overlaps = {
            mode: sequence_overlaps(
                gt, est, iou_function(mode), cls=settings.cls, difficulty=settings.difficulty,
                threshold=iou_threshold, mode=mode, gt_min_height=protocol.gt_min_height,
            )
            for mode in MODES
        }
        matchings = {mode: o.match() for mode, o in overlaps.items()}
        out.mot = {
            mode: sequence_mot(o, protocol, score_metrics=score_metrics)[0]
            for mode, o in overlaps.items()
        }
        out.objects = _object_rows(name, settings.cls, gt, est, matchings,
                                   gt_T_w_c, est_T_w_c, out.trajectories)
    return out
