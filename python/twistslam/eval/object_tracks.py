"""Visual object tracks against the simulator's ground truth (issue 10's targets).

The ground truth, and which cars and frames are evaluated, is :mod:`.object_ground_truth`
(re-exported here). Per car: coverage of its evaluated frames, and its pose errors. In each
frame an estimated track stands for at most one object and the reverse (:mod:`.track_assignment`,
the CLEAR MOT rule): a track between two queued cars covers one of them.

Two variants of the pose errors of a car:

- **aligned** (what the issue's targets use): a visual cluster's object frame is created with
  the world's rotation at the centroid of its points, so it differs from the box frame by a
  constant right-multiplied offset ``T_off`` that no image can reveal (a gauge freedom, until
  detections give canonical frames in issue 11). ``T_off`` is estimated from the compared
  frames, in the camera frame (``T_off ~ T_c_o_gt^-1 T_c_o_est``: chordal mean of the
  rotations, mean of the translations, once more on the inliers), and removed:
  ``T_w_o_est T_off^-1``. RPE is then computed on these poses and ATE after an SE(3)
  Umeyama alignment of their positions onto the ground truth (the SLAM world drifts).
- **canonical**: the estimate as it is (no offset, no alignment), for tracks whose frame is
  the box frame (issue 11).

Heading: the mean yaw error (:mod:`.object_yaw`, modulo 2 pi) of the main track in each
compared frame's camera frame, for canonical tracks only (a cluster frame's x axis is not the
car's length). 3D TP rate and MOTP: :func:`detection_rates` runs ``twistslam eval``'s
evaluator on the KITTI tracking boxes of a run against the sequence's ``label_02``.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .object_ground_truth import (  # noqa: F401  (re-exported: callers import them from here)
    CAR_CLASS, MAX_OCCLUSION, MAX_RANGE_M, MAX_TRUNCATION, MIN_BOX_HEIGHT_PX, MIN_VISIBLE_FRAMES, GtTrack,
    SequenceGroundTruth, evaluated_cars, load_ground_truth, selected_frames,
)
from .object_poses import MIN_RPE_PATH_M, track_pose_errors  # noqa: F401  (re-exported)
from .object_yaw import mean_yaw_error_deg
from .track_assignment import assign_tracks
from .trajectory import invert, rotation_angle

#: an estimated position within the box grown by this much (m, every side) hits the object:
#: a cluster centroid lies inside the visible part of the car, 1 m covers a biased centroid
HIT_MARGIN_M = 1.0
#: estimated tracks shorter than this (frames) are never ghosts (the issue's "5+ frames")
GHOST_MIN_FRAMES = 5
#: a track is a ghost when it hits no object in at least this fraction of its frames
GHOST_MISS_FRACTION = 0.5
#: a car counts as tracked when covered in at least this fraction of its frames (issue: 90 %)
TRACKED_COVERAGE = 0.9
#: offset samples farther than this from the first mean (m, deg) are left out of the second
OFFSET_INLIER_M = 0.5
OFFSET_INLIER_DEG = 10.0


def to_gt_world(track, T_w_c_est: np.ndarray,
                T_w_c_gt: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An estimated track's poses mapped into the ground-truth world through each camera.

    ``T_w_c_gt inv(T_w_c_est) T_w_o_est``: the object as the camera saw it, free of the SLAM
    world's drift (what association and the offset use). Returns (frames, mapped poses, raw
    ``T_w_o_est``) of the frames where both camera poses and the object pose are finite.
    """
    frames = np.asarray(track.frames, dtype=np.int64)
    ok = (frames >= 0) & (frames < min(len(T_w_c_est), len(T_w_c_gt)))
    ok[ok] &= np.isfinite(T_w_c_est[frames[ok]]).all(axis=(1, 2))
    ok &= np.isfinite(np.asarray(track.T_w_o)).all(axis=(1, 2))
    f = frames[ok]
    raw = np.asarray(track.T_w_o, dtype=np.float64)[ok]
    return f, T_w_c_gt[f] @ invert(T_w_c_est[f]) @ raw, raw


def inside_box(points_w: np.ndarray, T_w_o: np.ndarray, half_extents: np.ndarray,
               margin_m: float = HIT_MARGIN_M) -> np.ndarray:
    """(N,) bool: world points (N, 3) inside boxes ``T_w_o`` (N, 4, 4), grown by ``margin_m``."""
    T_o_w = invert(T_w_o)
    p_o = np.einsum("nij,nj->ni", T_o_w[:, :3, :3], points_w) + T_o_w[:, :3, 3]
    return (np.abs(p_o) <= np.asarray(half_extents) + margin_m).all(axis=-1)


def estimate_offset(T_c_o_gt: np.ndarray, T_c_o_est: np.ndarray) -> np.ndarray:
    """Constant right offset ``T_off`` with ``T_c_o_est ~ T_c_o_gt T_off`` (4, 4).

    Chordal mean of the per-frame rotations (SVD projection of their sum), mean of the
    translations; then the same on the samples within ``OFFSET_INLIER_M`` / ``_DEG`` of it.
    """
    samples = invert(T_c_o_gt) @ T_c_o_est

    def mean_pose(S: np.ndarray) -> np.ndarray:
        U, _, Vt = np.linalg.svd(S[:, :3, :3].sum(axis=0))
        D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = U @ D @ Vt, S[:, :3, 3].mean(axis=0)
        return T

    first = mean_pose(samples)
    dev = invert(first) @ samples
    keep = ((np.linalg.norm(dev[:, :3, 3], axis=1) <= OFFSET_INLIER_M)
            & (np.rad2deg(rotation_angle(dev[:, :3, :3])) <= OFFSET_INLIER_DEG))
    return mean_pose(samples[keep]) if keep.any() else first


@dataclass
class CarTrackRow:
    """One evaluated ground-truth car.

    Attributes
    ----------
    gt_id : ground-truth track id.
    frames : its evaluated frames (labelled, within range, box tall enough).
    coverage : fraction of them in which an estimated track stands for it (one-to-one per
        frame, :mod:`.track_assignment`).
    n_compared : evaluated frames where the main estimated track has a pose.
    path_m : ground-truth distance travelled over the compared frames (m).
    rpe_t, rpe_r, ate_aligned : aligned variant (m/m, deg/m, m), NaN without a main track;
        RPE is NaN (left out of the means) when ``path_m < MIN_RPE_PATH_M``.
    rpe_t_canonical, rpe_r_canonical, ate_canonical : canonical variant (no offset, no
        alignment; ATE in the ground-truth world seen through the estimated cameras).
    est_ids : estimated tracks that stood for it, main (most frames) first.
    offset : (4, 4) the removed ``T_off`` (identity when no main track).
    yaw_deg : mean heading error (deg, modulo 2 pi: a flipped box is 180) of the main track
        over the compared frames, each in its camera frame; NaN without a main track or
        when it is not canonical.
    """

    gt_id: int
    frames: int
    coverage: float
    n_compared: int
    path_m: float
    rpe_t: float
    rpe_r: float
    ate_aligned: float
    rpe_t_canonical: float
    rpe_r_canonical: float
    ate_canonical: float
    est_ids: list[int]
    offset: np.ndarray
    yaw_deg: float = float("nan")


@dataclass
class ObjectTrackEvaluation:
    """Per-car rows, ghost tracks and their summary (means over the cars with a value)."""

    cars: list[CarTrackRow]
    ghost_ids: list[int]

    def _mean(self, name: str) -> float:
        values = np.array([getattr(c, name) for c in self.cars], dtype=np.float64)
        return float(np.nanmean(values)) if np.isfinite(values).any() else float("nan")

    @property
    def rpe_t(self) -> float:
        return self._mean("rpe_t")

    @property
    def rpe_r(self) -> float:
        return self._mean("rpe_r")

    @property
    def ate_aligned(self) -> float:
        return self._mean("ate_aligned")

    @property
    def coverage(self) -> float:
        return self._mean("coverage")

    @property
    def n_tracked(self) -> int:
        """Cars covered in at least ``TRACKED_COVERAGE`` of their frames."""
        return sum(c.coverage >= TRACKED_COVERAGE for c in self.cars)

    @property
    def n_ghosts(self) -> int:
        return len(self.ghost_ids)

    def summary(self) -> dict[str, float]:
        return {"cars": len(self.cars), "rpe_t": self.rpe_t, "rpe_r": self.rpe_r,
                "ate_aligned": self.ate_aligned, "coverage": self.coverage,
                "tracked": self.n_tracked, "ghosts": self.n_ghosts,
                "rpe_t_canonical": self._mean("rpe_t_canonical"),
                "rpe_r_canonical": self._mean("rpe_r_canonical"),
                "ate_canonical": self._mean("ate_canonical"), "yaw_deg": self._mean("yaw_deg")}

    def format_table(self) -> str:
        """Plain-text table: one line per car, then the means."""
        head = (f"{'gt':>5} {'frames':>6} {'cover':>6} {'cmp':>4} {'path m':>7} {'RPE_t m/m':>10} "
                f"{'RPE_r deg/m':>11} {'ATE_al m':>9} {'yaw deg':>7}  est tracks")
        lines = [head]
        for c in self.cars:
            lines.append(f"{c.gt_id:>5} {c.frames:>6} {c.coverage:>6.2f} {c.n_compared:>4} {c.path_m:>7.1f} "
                         f"{c.rpe_t:>10.3f} {c.rpe_r:>11.3f} {c.ate_aligned:>9.3f} {c.yaw_deg:>7.2f}  "
                         f"{','.join(map(str, c.est_ids)) or '-'}")
        lines.append(f"{'mean':>5} {len(self.cars):>6} {self.coverage:>6.2f} {'':>4} {'':>7} "
                     f"{self.rpe_t:>10.3f} {self.rpe_r:>11.3f} {self.ate_aligned:>9.3f} "
                     f"{self._mean('yaw_deg'):>7.2f}")
        lines.append(f"tracked >= {TRACKED_COVERAGE:.0%}: {self.n_tracked}/{len(self.cars)}; "
                     f"ghost tracks ({GHOST_MIN_FRAMES}+ frames): {self.n_ghosts} "
                     f"{self.ghost_ids if self.ghost_ids else ''}".rstrip())
        return "\n".join(lines)


def _car_row(gt: SequenceGroundTruth, car: GtTrack, frames: np.ndarray,
             mapped: dict[int, tuple], assignment: dict[int, dict[int, int]],
             canonical_ids: set[int] | None = None,
             box_frames: dict[int, np.ndarray] | None = None) -> CarTrackRow:
    """Coverage and errors of one car; ``mapped`` = estimated tracks in the GT world;
    ``assignment``: :func:`.track_assignment.assign_tracks`'s pairs (a frame counts for the
    track that stands for this car in it, one-to-one);
    ``canonical_ids``: the tracks whose yaw is evaluated (None: every track);
    ``box_frames``: other tracks' ``T_o_box``, whose yaw is evaluated with it."""
    row_of = {int(f): k for k, f in enumerate(car.frames)}
    hits: dict[int, set[int]] = {}
    for f in frames.tolist():
        for est_id, gt_id in assignment.get(int(f), {}).items():
            if gt_id == car.track_id:
                hits.setdefault(est_id, set()).add(int(f))
    covered = set().union(*hits.values()) if hits else set()
    order = sorted(hits, key=lambda i: (-len(hits[i]), min(hits[i])))
    nan = float("nan")
    values = dict(n_compared=0, path_m=0.0, rpe_t=nan, rpe_r=nan, ate_aligned=nan, rpe_t_canonical=nan,
                  rpe_r_canonical=nan, ate_canonical=nan, offset=np.eye(4), yaw_deg=nan)
    if order:
        est_frames, poses, raw = mapped[order[0]]
        common, ei, _ = np.intersect1d(est_frames, frames, return_indices=True)
        gt_poses = car.T_w_o[[row_of[int(f)] for f in common]]
        T_c_w = invert(gt.T_w_c[common])  # mapped poses: the estimated camera view in GT world
        offset = estimate_offset(T_c_w @ gt_poses, T_c_w @ poses[ei])
        aligned = track_pose_errors(common, gt_poses, common, raw[ei] @ invert(offset))
        canonical = track_pose_errors(common, gt_poses, common, raw[ei])
        values.update(n_compared=len(common), path_m=aligned.length,
                      rpe_t=aligned.rpe_t, rpe_r=aligned.rpe_r,
                      ate_aligned=aligned.ate_aligned, ate_canonical=canonical.ate,
                      rpe_t_canonical=canonical.rpe_t, rpe_r_canonical=canonical.rpe_r, offset=offset)
        if canonical_ids is None or order[0] in canonical_ids:
            values["yaw_deg"] = mean_yaw_error_deg(T_c_w @ gt_poses, T_c_w @ poses[ei])
        elif box_frames and order[0] in box_frames:
            values["yaw_deg"] = mean_yaw_error_deg(T_c_w @ gt_poses,
                                                   T_c_w @ poses[ei] @ box_frames[order[0]])
    return CarTrackRow(gt_id=car.track_id, frames=len(frames),
                       coverage=len(covered) / len(frames), est_ids=order, **values)


def gt_boxes_by_frame(gt: SequenceGroundTruth) -> dict[int, list[tuple[int, np.ndarray, np.ndarray]]]:
    """frame -> [(gt id, ``T_w_o``, half extents)] of every object (any class, hidden or not)."""
    by_frame: dict[int, list[tuple[int, np.ndarray, np.ndarray]]] = {}
    for track in gt.tracks.values():
        half = track.half_extents()
        for f, T in zip(track.frames.tolist(), track.T_w_o):
            by_frame.setdefault(f, []).append((track.track_id, T, half))
    return by_frame


def ghost_tracks(gt: SequenceGroundTruth, mapped: dict[int, tuple],
                 margin_m: float = HIT_MARGIN_M) -> list[int]:
    """Estimated tracks of ``GHOST_MIN_FRAMES``+ frames that hit no ground-truth object (any
    class, moving or parked) in at least ``GHOST_MISS_FRACTION`` of their frames (a second
    track on an object is no ghost: it is where an object is)."""
    by_frame = gt_boxes_by_frame(gt)
    ghosts = []
    for est_id, (frames, poses, _) in mapped.items():
        if len(frames) < GHOST_MIN_FRAMES:
            continue
        misses = 0
        for f, P in zip(frames.tolist(), poses):
            boxes = by_frame.get(f, [])
            if not boxes:
                misses += 1
                continue
            T = np.stack([b[1] for b in boxes])
            half = np.stack([b[2] for b in boxes])
            misses += not inside_box(np.repeat(P[None, :3, 3], len(T), 0), T, half, margin_m).any()
        if misses >= GHOST_MISS_FRACTION * len(frames):
            ghosts.append(est_id)
    return ghosts


def evaluate_object_tracks(objects, camera_poses: np.ndarray, gt: SequenceGroundTruth,
                           margin_m: float = HIT_MARGIN_M, min_frames: int = MIN_VISIBLE_FRAMES,
                           max_range_m: float = MAX_RANGE_M,
                           min_box_height_px: float = MIN_BOX_HEIGHT_PX,
                           max_occlusion: int = MAX_OCCLUSION,
                           max_truncation: int = MAX_TRUNCATION,
                           canonical_ids=None,
                           box_frames: dict[int, np.ndarray] | None = None) -> ObjectTrackEvaluation:
    """Evaluate estimated object tracks against the simulator's ground truth.

    Parameters
    ----------
    objects : estimated tracks (``result.objects``: anything with ``track_id``, ``frames``
        (K,) and ``T_w_o`` (K, 4, 4) in the SLAM world).
    camera_poses : (F, 4, 4) estimated ``T_w_c`` (NaN rows: frames without a pose, skipped).
    gt : :func:`load_ground_truth`'s result.
    margin_m, min_frames, max_range_m, min_box_height_px, max_occlusion, max_truncation : see
        ``HIT_MARGIN_M``, ``MIN_VISIBLE_FRAMES``, ``MAX_RANGE_M``, ``MIN_BOX_HEIGHT_PX`` (0:
        every labelled frame in range is evaluated, however small its box),
        ``MAX_OCCLUSION`` (2: however hidden) and ``MAX_TRUNCATION`` (2: however far outside
        the image). Ghosts are judged against every
        ground-truth box, small or not: a track on a hidden car is no ghost.
    canonical_ids : ids of the estimated tracks whose object frame is their box frame (LiDAR
        fusion); only their yaw error is evaluated. None: every track's (the caller knows
        its frames are box frames).
    box_frames : track id -> ``T_o_box`` (4, 4), the box a track without a canonical frame
        was given in its object frame (``VisualObjects.T_o_box``, camera-only boxes): those
        tracks' yaw is evaluated too, from ``T_w_o @ T_o_box``. None: not evaluated.
    """
    camera_poses = np.asarray(camera_poses, dtype=np.float64)
    mapped = {}
    for obj in objects:
        frames, poses, raw = to_gt_world(obj, camera_poses, gt.T_w_c)
        if len(frames):
            mapped[int(obj.track_id)] = (frames, poses, raw)
    cars = evaluated_cars(gt, min_frames, max_range_m, min_box_height_px, max_occlusion,
                          max_truncation)
    canonical = None if canonical_ids is None else {int(i) for i in canonical_ids}
    boxes = {int(k): np.asarray(v, dtype=np.float64) for k, v in (box_frames or {}).items()}
    est_positions: dict[int, list[tuple[int, np.ndarray]]] = {}
    for est_id, (est_frames, poses, _) in mapped.items():
        for f, P in zip(est_frames.tolist(), poses):
            est_positions.setdefault(f, []).append((est_id, P[:3, 3]))
    assignment = assign_tracks(gt_boxes_by_frame(gt), est_positions, margin_m)
    rows = [_car_row(gt, gt.tracks[tid], frames, mapped, assignment, canonical, boxes)
            for tid, frames in cars.items()]
    return ObjectTrackEvaluation(cars=rows, ghost_ids=ghost_tracks(gt, mapped, margin_m))


#: difficulty of :func:`detection_rates`: KITTI's moderate level, the frames the pose errors
#: also evaluate (box >= 25 px, occlusion <= 1; see :mod:`.object_ground_truth`)
DETECTION_DIFFICULTY = "moderate"
#: 3D IoU of a true positive: ``twistslam eval``'s default (the paper's object tables)
DETECTION_IOU = 0.25


def detection_rates(root: str | Path, seq: str, tracking, gt_ids=None,
                    difficulty: str = DETECTION_DIFFICULTY,
                    iou_threshold: float = DETECTION_IOU) -> dict[int, tuple[float, float]]:
    """3D TP rate and 3D MOTP (percent) of ground-truth tracks, as ``twistslam eval`` gives them.

    The boxes are written as ``twistslam run --out`` writes them (``tracking/SEQ.txt``, KITTI
    tracking format) into a temporary results directory, which
    :func:`~twistslam.eval.evaluate_sequence` scores against ``root``'s ``label_02`` (CLEAR
    protocol, its matcher; a box is matched in its frame's camera frame, so camera poses do
    not enter).

    Parameters
    ----------
    root : KITTI tracking layout root (``training/label_02``, ``calib``), e.g. a simulated one.
    seq : sequence name (``"0000"``).
    tracking : :class:`~twistslam.datasets.ObjectTable` of the estimated boxes (``result.
        objects.tracking``).
    gt_ids : ground-truth track ids to keep (None: every evaluated car).
    difficulty, iou_threshold : see ``DETECTION_DIFFICULTY``, ``DETECTION_IOU``.

    Returns
    -------
    ``{gt track id: (tp_3d, motp_3d)}``; a car with frames in the difficulty level and no
    matched box has TP 0 and MOTP NaN; a car with no frame in the level is absent.
    """
    from ..datasets import write_tracking_results
    from .sequence import evaluate_sequence

    with tempfile.TemporaryDirectory(prefix="twistslam-eval-") as tmp:
        write_tracking_results(Path(tmp) / "tracking" / f"{seq}.txt", tracking)
        metrics = evaluate_sequence(root, tmp, seq, iou_threshold=iou_threshold,
                                    difficulty=difficulty, protocol="clear", score_metrics=False)
    keep = None if gt_ids is None else {int(i) for i in gt_ids}
    return {int(o.track_id): (float(o.tp_3d), float(o.motp_3d)) for o in metrics.objects
            if keep is None or int(o.track_id) in keep}
