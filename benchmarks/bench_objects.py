"""Ablation of the visual object tracking (issue 10) on simulated sequences.

    .venv/bin/python benchmarks/bench_objects.py [--scenarios urban crowded] [--seeds 0]
        [--frames 100] [--rows default dis ...] [--set section.key=value ...] [--per-car]
        [--gt-as-estimate] [--raft-weights FILE] [--raft-frames N]

Rows (each a ``twistslam.run(seq, config=cfg, progress=False, segmentation=SEG, flow=FLOW)``
on the simulator's sequence, ``.cache/sim/SCENARIO-seedS-nF``, generated when missing):

* ``default``: panoptic and flow from the simulator's files, planar link for vehicles;
* ``free-link``: ``visual_objects.planar_class_ids = []`` (every link free; the planar link
  must lower RPE_r);
* ``no-const``: ``visual_objects.use_const = False`` (no e_const in the BA);
* ``dis``: OpenCV DIS flow instead of the flow files;
* ``stereo``: ``lidar.use_depth = False``, the camera alone without any LiDAR (the scan is
  not read; every other row reads it: static keypoints take its depth, and a vehicle mask's
  own returns check and complete its stereo points, docs/visual_objects.md);
* ``online`` / ``det-reg-online``: ``visual_objects.final_smoothing = False``, the poses as
  the online tracking left them (no final smoothing of the whole tracks);
* ``boxes-seg``: instance masks from the oracle detections instead of the panoptic files;
* ``kp-only`` / ``kp-extra``: ``visual_objects.extra_keypoints`` False / True;
* ``det`` / ``det-reg``: LiDAR fusion with the simulator's oracle 3D detections
  (``detector="files"``): canonical poses, sizes, e_det, then also GICP of the object scans
  (e_reg); ``classical``: the same with the core's classical LiDAR detector instead of the
  oracle (no precomputed files); ``classical-masks``: the same with the instance masks from
  those boxes too (no panoptic files: the system from raw stereo + LiDAR); every other row
  runs with ``detector="none"`` (no 3D detections);
* ``raft``: RAFT flow (``raft_small``) from the state-dict file ``--raft-weights FILE`` (or
  ``$TWISTSLAM_RAFT_WEIGHTS``) over the first ``--raft-frames`` frames only (default 10: RAFT
  is slow on a CPU), so its object metrics still count every car of the whole sequence and
  mainly its flow ms is comparable; without weights it prints "not available".

Per row: mean object RPE_t (m/m), RPE_r (deg/m) and aligned ATE (m) over the moving cars
seen 20+ frames within 50 m (:mod:`twistslam.eval.object_tracks`), cars tracked in >= 90 %
of those frames, ghost tracks, camera ATE (m, aligned) and RPE (m/frame, deg/frame) against
``poses/SEQ.txt``, median ms per object per frame of every timing stage named ``object*``,
median flow ms, the loop's Hz and the final smoothing's ms (once, after the loop). A row whose config key or run argument does not exist
yet prints "not available" and the reason.

Issue 11's figures, per row: the canonical ATE / RPE columns (no offset, no alignment), the
mean yaw error of the canonical tracks (deg, modulo 2 pi; in the camera-only rows, of the
boxes the output gives camera-only tracks), and the 3D TP rate and 3D MOTP
(percent) of the run's KITTI tracking boxes (what ``twistslam run --out`` writes) scored by
``twistslam eval``'s evaluator against ``label_02`` (moderate level, IoU 0.25), means over the
same moving cars. At the end: issue 10's targets per row (the aligned errors averaged over
the moving cars of all the sequences, the cars tracked in >= 90 % of their frames, the ghost
tracks), each row's means over the sequences against issue 11's targets (met / missed), and the
ablation ratio RPE_t det-reg / default (aligned RPE_t: the default row's cluster frames are not
box frames) per sequence and on the means, the same with the classical detector's boxes
(classical / default), and the same ratio on masks made from 3D boxes (boxes-det-reg / boxes-seg, classical-masks / classical-cam)
when those rows ran;
``--targets`` also prints the targets line after every row.

``--gt-as-estimate`` skips the SLAM: the camera poses are the ground truth and
``result.objects`` the ground-truth tracks of every object in its labelled frames, with an
identity-rotation-at-centroid-like object frame and per-frame noise (``GT_NOISE_*``), to run
the evaluation end to end before the tracker exists (a row whose config is not available
is then still evaluated, after a note).
"""

from __future__ import annotations

import argparse
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import twistslam
from twistslam.datasets import read_poses
from twistslam.demo import MOVABLE_CLASSES, cached_sequence
from twistslam.eval import evaluate_camera
from twistslam.eval.object_tracks import (
    MAX_OCCLUSION, MAX_TRUNCATION, TRACKED_COVERAGE, detection_rates, evaluate_object_tracks,
    load_ground_truth,
)
from twistslam.objects.result import TrackedObject
from twistslam.objects.visual import VisualObjects
from twistslam.timings import Timings

SEQ = "0000"
CACHE = Path(__file__).resolve().parents[1] / ".cache" / "sim"
#: per-frame noise of the --gt-as-estimate objects (m, deg): a good visual tracker's level
GT_NOISE_M, GT_NOISE_DEG = 0.02, 0.2
#: centroid offset of the --gt-as-estimate object frames (m): points lie on the visible side
GT_CENTROID_OFFSET_M = 0.5


@dataclass
class Row:
    """One ablation: config overrides (nested sections) and the perception sources."""

    name: str
    overrides: dict = field(default_factory=dict)
    segmentation: str = "files"
    flow: str = "files"
    detector: str = "none"


#: config section of the visual object tracking (python/twistslam/config_visual_objects.py)
SECTION = "visual_objects"

ROWS = {r.name: r for r in [
    Row("default"),
    Row("free-link", {SECTION: {"planar_class_ids": []}}),
    Row("no-const", {SECTION: {"use_const": False}}),
    Row("dis", flow="dis"),
    # the camera alone, strictly: no LiDAR at all (the other camera rows read the scan for
    # static keypoints' depth and vehicle masks' returns, tracking/object_lidar_seed.cpp)
    Row("stereo", {"lidar": {"use_depth": False}}),
    # the poses as tracked online: no final smoothing of the whole tracks
    Row("online", {SECTION: {"final_smoothing": False}}),
    Row("boxes-seg", segmentation="boxes"),
    Row("kp-only", {SECTION: {"extra_keypoints": False}}),
    Row("kp-extra", {SECTION: {"extra_keypoints": True}}),
    Row("raft", flow="raft"),
    # e_dyna in the keyframe BA (off by default): the camera columns are the comparison
    Row("dyn-ba", {"local_ba": {"dynamic_objects": True}}),
    # LiDAR fusion (issue 11) with the oracle detections: + detections (canonical pose, size,
    # e_det), + detections + registration (e_reg)
    Row("det", {"lidar_objects": {"use_registration": False}}, detector="files"),
    Row("det-reg", detector="files"),
    Row("det-reg-online", {SECTION: {"final_smoothing": False}}, detector="files"),
    # the whole system from raw stereo + LiDAR: the classical LiDAR detector of the core
    Row("classical", detector="classical"),
    # ... and its masks from the classical boxes too (no panoptic files: raw stereo + LiDAR)
    Row("classical-masks", segmentation="boxes", detector="classical"),
    # the same masks without the LiDAR terms (the boxes make the masks only): the camera alone
    # on the perception real KITTI runs with, the base of the second ablation pair below
    Row("classical-cam", {"lidar_objects": {"use_detections": False}}, segmentation="boxes",
        detector="classical"),
    # the oracle boxes' masks, with the LiDAR terms (pairs with boxes-seg, the camera alone)
    Row("boxes-det-reg", segmentation="boxes", detector="files"),
]}
#: environment variable naming the RAFT state-dict file when --raft-weights is not given
RAFT_WEIGHTS_ENV = "TWISTSLAM_RAFT_WEIGHTS"
#: frames of the raft row: raft_small takes about a second per KITTI-size pair on a CPU
RAFT_FRAMES = 10


#: issue 11's targets on the moving cars, canonical: (label, summary key, sense, bound, unit)
TARGETS = [("ATE", "ate_canonical", "<=", 0.12, "m"), ("RPE_t", "rpe_t_canonical", "<=", 0.08, "m/m"),
           ("RPE_r", "rpe_r_canonical", "<=", 0.2, "deg/m"), ("yaw", "yaw_deg", "<=", 2.0, "deg"),
           ("TP3D", "tp_3d", ">=", 60.0, "%"), ("MOTP3D", "motp_3d", ">=", 60.0, "%")]
#: issue 10's targets on the moving cars, aligned: (label, CarTrackRow attribute, bound, unit);
#: besides, every such car tracked in >= 90 % of its frames and no ghost track of 5+ frames
ISSUE10_TARGETS = [("RPE_t", "rpe_t", 0.15, "m/m"), ("RPE_r", "rpe_r", 0.35, "deg/m"),
                   ("ATE", "ate_aligned", 0.15, "m")]
#: ablation target: the LiDAR terms cut RPE_t by at least half (det-reg / default)
ABLATION_MAX_RATIO = 0.5
#: the ablation's rows: keypoints only, and + detection + registration
ABLATION_ROWS = ("default", "det-reg")
#: the same with the classical LiDAR detector's boxes (the default without weights)
CLASSICAL_ABLATION_ROWS = ("default", "classical")
#: the same ablation where the masks come from 3D boxes (real KITTI has no panoptic files),
#: both rows of a pair on the same masks: the oracle boxes', the classical detector's
MASK_ABLATION_ROWS = (("boxes-seg", "boxes-det-reg"), ("classical-cam", "classical-masks"))


class NotAvailable(Exception):
    """A config key or run argument this row needs does not exist (yet)."""


def build_config(row: Row, extra: list[str]) -> twistslam.Config:
    """Defaults + the demo's dynamic classes + the row's overrides + ``--set`` items."""
    data = {"tracking": {"dynamic_class_ids": list(MOVABLE_CLASSES)}}
    for section, values in row.overrides.items():
        data.setdefault(section, {}).update(values)
    try:
        return twistslam.Config.from_dict(data).override(extra)
    except ValueError as exc:
        raise NotAvailable(f"config: {exc}") from None


def raft_settings(row: Row, weights: Path | None, frames: int) -> tuple[Path | None, list[str]]:
    """The weight file and the frame-limit override of a RAFT row (nothing for other rows)."""
    if row.flow != "raft":
        return None, []
    if weights is None:
        raise NotAvailable("no RAFT weights (--raft-weights)")
    if not weights.is_file():
        raise NotAvailable(f"RAFT weights {weights} not found (--raft-weights)")
    return weights, [f"run.max_frames={frames}"]


def run_slam(root: Path, row: Row, config, flow_weights: Path | None = None) -> object:
    try:
        return twistslam.run((root, SEQ), config=config, progress=False,
                             segmentation=row.segmentation, flow=row.flow, flow_weights=flow_weights,
                             detector=row.detector)
    except TypeError as exc:  # the perception arguments are being added (issue 10)
        if "segmentation" in str(exc) or "flow" in str(exc):
            raise NotAvailable(f"twistslam.run: {exc}") from None
        raise


@dataclass
class FakeResult:
    """The parts of a :class:`twistslam.Result` this bench reads."""

    camera_poses: np.ndarray
    objects: list
    timings: Timings = field(default_factory=Timings)


def gt_as_estimate(gt, rng: np.random.Generator) -> FakeResult:
    """Ground truth as a tracker's output: offset object frames and per-frame noise."""
    objects = []
    for tid, track in sorted(gt.tracks.items()):
        seen = np.flatnonzero(track.labelled)
        if not len(seen):
            continue
        T_off = np.eye(4)  # world axes at a point near the box centre, as a new cluster
        T_off[:3, :3] = track.T_w_o[seen[0], :3, :3].T
        T_off[:3, 3] = rng.uniform(-GT_CENTROID_OFFSET_M, GT_CENTROID_OFFSET_M, 3)
        poses = track.T_w_o[seen] @ T_off
        for k in range(len(poses)):
            noise = np.eye(4)
            noise[:3, :3] = Rotation.from_rotvec(np.deg2rad(rng.normal(0, GT_NOISE_DEG, 3))).as_matrix()
            noise[:3, 3] = rng.normal(0, GT_NOISE_M, 3)
            poses[k] = poses[k] @ noise
        n = len(seen)
        objects.append(TrackedObject(
            track_id=tid, cls=track.cls, state="confirmed", link="planar",
            frames=track.frames[seen], T_w_o=poses, size=track.size.copy(),
            velocity_kmh=np.zeros(n), detected=np.ones(n, bool), reported=np.ones(n, bool),
            score=np.ones(n), mean_score=1.0))
    return FakeResult(camera_poses=gt.T_w_c.copy(), objects=VisualObjects(objects=objects))


def canonical_track_ids(objects) -> set[int]:
    """Ids of the tracks whose object frame is their box frame (a 3D detection gave it).

    A track's own ``canonical`` flag when it has one; else :func:`twistslam.objects.visual.
    visual_objects`' rule: a canonical cluster keeps the identity box offset ``T_o_box`` and
    a positive size (a box fitted to points is never exactly the identity).
    """
    out = set()
    T_o_box = getattr(objects, "T_o_box", {})
    for obj in objects:
        flag = getattr(obj, "canonical", None)
        if flag is None:
            T = T_o_box.get(obj.track_id)
            flag = T is not None and np.array_equal(T, np.eye(4)) and bool((obj.size > 0).all())
        if flag:
            out.add(int(obj.track_id))
    return out


def issue11_figures(root: Path, result, ev) -> dict[str, float]:
    """The evaluation summary plus the mean 3D TP rate and MOTP (percent) of its cars."""
    figures = ev.summary()
    tracking = getattr(result.objects, "tracking", None)
    rates = ({} if tracking is None else
             detection_rates(root, SEQ, tracking, gt_ids=[c.gt_id for c in ev.cars]))
    for k, key in enumerate(("tp_3d", "motp_3d")):
        values = np.array([r[k] for r in rates.values()], dtype=np.float64)
        figures[key] = float(np.nanmean(values)) if np.isfinite(values).any() else float("nan")
    return figures


def targets_line(figures: dict[str, float]) -> str:
    """``ATE 0.10<=0.12 met, ...``: each issue-11 figure against its target."""
    items = []
    for label, key, sense, bound, _ in TARGETS:
        value = figures.get(key, float("nan"))
        ok = np.isfinite(value) and (value <= bound if sense == "<=" else value >= bound)
        items.append(f"{label} {value:.3g}{sense}{bound:g} {'met' if ok else 'MISSED'}")
    return ", ".join(items)


def issue10_line(evaluations: list) -> str:
    """``RPE_t 0.042<=0.15 met, ..., cars 74/74 met, ghosts 1 MISSED``: issue 10's targets
    on one row's evaluations (one per sequence), the errors averaged over all their cars."""
    cars = [c for ev in evaluations for c in ev.cars]
    items = []
    for label, key, bound, _ in ISSUE10_TARGETS:
        values = np.array([getattr(c, key) for c in cars], dtype=np.float64)
        value = float(np.nanmean(values)) if np.isfinite(values).any() else float("nan")
        ok = np.isfinite(value) and value <= bound
        items.append(f"{label} {value:.3g}<={bound:g} {'met' if ok else 'MISSED'}")
    tracked = sum(c.coverage >= TRACKED_COVERAGE for c in cars)
    ghosts = sum(ev.n_ghosts for ev in evaluations)
    items.append(f"cars >= {TRACKED_COVERAGE:.0%} {tracked}/{len(cars)} "
                 f"{'met' if tracked == len(cars) else 'MISSED'}")
    items.append(f"ghosts {ghosts} {'met' if ghosts == 0 else 'MISSED'}")
    return ", ".join(items)


def ablation_ratio(figures: dict[str, dict], pair: tuple[str, str] = ABLATION_ROWS) -> float:
    """RPE_t (aligned) of the pair's second row (with the LiDAR terms) over its first (the
    camera alone); NaN when either row is missing."""
    base, fused = (figures.get(name, {}).get("rpe_t", float("nan")) for name in pair)
    return fused / base if np.isfinite(base) and base > 0 else float("nan")


def print_summary(figures: dict[str, dict[str, dict]], rows: list[str],
                  evaluations: dict[str, list] | None = None) -> None:
    """Per row the means over the sequences against the targets; the ablation ratios.
    ``evaluations``: row -> its evaluations (one per sequence), for issue 10's targets."""
    if not figures:
        return
    if evaluations:
        print(f"\nissue 10 targets (aligned errors averaged over the moving cars of all "
              f"{len(figures)} sequence(s); ghost tracks of 5+ frames):")
        for name in rows:
            if evaluations.get(name):
                print(f"  {name:<10} {issue10_line(evaluations[name])}")
    print(f"\nissue 11 targets (means over moving cars, canonical; TP/MOTP 3D in %), means over "
          f"{len(figures)} sequence(s):")
    means: dict[str, dict[str, float]] = {}
    for name in rows:
        per_seq = [f[name] for f in figures.values() if name in f]
        if not per_seq:
            continue
        means[name] = {key: float(np.nanmean([f.get(key, np.nan) for f in per_seq]))
                       if any(np.isfinite(f.get(key, np.nan)) for f in per_seq) else float("nan")
                       for key in ("rpe_t", *[t[1] for t in TARGETS])}
        print(f"  {name:<10} {targets_line(means[name])}")
    for pair in (ABLATION_ROWS, CLASSICAL_ABLATION_ROWS, *MASK_ABLATION_ROWS):
        if not all(name in rows for name in pair):
            continue
        print(f"ablation: RPE_t (aligned) {pair[1]} / {pair[0]}, target <= "
              f"{ABLATION_MAX_RATIO:g} (the LiDAR terms cut it by half):")
        for label, per_row in figures.items():
            print(f"  {label:<14} {ablation_ratio(per_row, pair):.2f}")
        ratio = ablation_ratio(means, pair)
        verdict = "met" if np.isfinite(ratio) and ratio <= ABLATION_MAX_RATIO else "MISSED"
        print(f"  {'mean':<14} {ratio:.2f} {verdict}")


def per_object_ms(result) -> dict[str, float]:
    """Median over frames of each ``object*`` stage's ms divided by the live tracks."""
    n_frames = len(result.camera_poses)
    live = np.zeros(n_frames)
    for obj in result.objects:
        f = np.asarray(obj.frames)
        live[f[(f >= 0) & (f < n_frames)]] += 1
    out = {}
    for name, ms in result.timings.stages.items():
        if "object" in name and len(ms) == n_frames:
            ok = np.isfinite(ms) & (live > 0)
            out[name] = float(np.median(ms[ok] / live[ok])) if ok.any() else float("nan")
    return out


def camera_box_frames(row: Row, objects, canonical: set[int]) -> dict[int, np.ndarray] | None:
    """The camera-only rows' box frames (their yaw is the boxes' heading rules,
    :mod:`twistslam.objects.camera_boxes`); None for the rows with 3D boxes, whose yaw column
    stays issue 11's figure (canonical tracks only)."""
    if row.detector != "none":
        return None
    return {tid: T for tid, T in getattr(objects, "T_o_box", {}).items() if tid not in canonical}


def median_stage(result, word: str) -> float:
    values = [ms for name, ms in result.timings.stages.items() if word in name]
    finite = np.concatenate(values)[np.isfinite(np.concatenate(values))] if values else []
    return float(np.median(finite)) if len(finite) else float("nan")


HEADER = (f"{'scenario':<14} {'row':<10} {'RPE_t':>6} {'RPE_r':>6} {'ATE_al':>6} "
          f"{'tracked':>8} {'ghosts':>6} {'camATE':>7} {'camRPEt':>8} {'camRPEr':>8} "
          f"{'flow ms':>7} {'Hz':>6}  object ms/obj/frame; canonical RPE_t RPE_r ATE; "
          f"yaw deg (canonical tracks; camera rows: their boxes); TP3D MOTP3D %")


def format_row(label: str, name: str, ev, cam, result, figures: dict[str, float]) -> str:
    obj_ms = ", ".join(f"{k} {v:.2f}" for k, v in per_object_ms(result).items()) or "-"
    return (f"{label:<14} {name:<10} {ev.rpe_t:>6.3f} {ev.rpe_r:>6.3f} {ev.ate_aligned:>6.3f} "
            f"{f'{ev.n_tracked}/{len(ev.cars)}':>8} {ev.n_ghosts:>6} {cam.ate_rmse:>7.3f} "
            f"{cam.rpe_t_mean:>8.4f} {cam.rpe_r_mean:>8.4f} {median_stage(result, 'flow'):>7.1f} "
            f"{result.timings.hz:>6.1f}  {obj_ms}{smoothing_ms(result)}{canonical_columns(ev)}; yaw "
            f"{figures['yaw_deg']:.2f}; TP3D {figures['tp_3d']:.1f} MOTP3D {figures['motp_3d']:.1f}")


def smoothing_ms(result) -> str:
    """The final smoothing's time (ms, once after the last frame, outside the loop's Hz)."""
    ms = getattr(result.timings, "after_loop_ms", {}).get("object_smoothing")
    return "" if ms is None else f"; final smoothing {ms:.0f} ms"


def canonical_columns(ev) -> str:
    """The canonical variant (no offset, no alignment; issue 11) where every car has it."""
    s = ev.summary()
    if not np.isfinite(s["ate_canonical"]):
        return ""
    return (f"; canonical {s['rpe_t_canonical']:.3f} {s['rpe_r_canonical']:.3f} "
            f"{s['ate_canonical']:.3f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenarios", nargs="+", default=["urban", "crowded"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--rows", nargs="+", default=list(ROWS), choices=list(ROWS))
    parser.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE",
                        help="extra config override for every row")
    parser.add_argument("--cache", type=Path, default=CACHE)
    parser.add_argument("--per-car", action="store_true", help="print each row's per-car table")
    parser.add_argument("--targets", action="store_true",
                        help="print issue 11's targets (met / missed) after every row")
    parser.add_argument("--gt-as-estimate", action="store_true",
                        help="debug: noisy ground truth instead of a SLAM run")
    parser.add_argument("--raft-weights", type=Path, metavar="FILE",
                        default=os.environ.get(RAFT_WEIGHTS_ENV) or None,
                        help=f"raft_small state dict for the raft row (default: ${RAFT_WEIGHTS_ENV})")
    parser.add_argument("--raft-frames", type=int, default=RAFT_FRAMES, metavar="N",
                        help="frames of the raft row")
    parser.add_argument("--max-occlusion", type=int, default=MAX_OCCLUSION, choices=[0, 1, 2],
                        help="evaluate car frames up to this KITTI occlusion level "
                             f"(default {MAX_OCCLUSION}, moderate; 2: every occlusion)")
    parser.add_argument("--max-truncation", type=int, default=MAX_TRUNCATION, choices=[0, 1, 2],
                        help="evaluate car frames up to this truncation level (default "
                             f"{MAX_TRUNCATION}: half of the box in the image; 2: every frame)")
    args = parser.parse_args(argv)

    print(f"RPE_t m/m, RPE_r deg/m, ATE_al m (means over moving cars); camera ATE m, RPE m and "
          f"deg per frame{'; GROUND TRUTH AS ESTIMATE (debug)' if args.gt_as_estimate else ''}")
    print(HEADER)
    figures: dict[str, dict[str, dict]] = {}  # sequence label -> row -> issue-11 figures
    evaluations: dict[str, list] = {}  # row -> its ObjectTrackEvaluation per sequence
    for scenario in args.scenarios:
        for seed in args.seeds:
            root = cached_sequence(args.cache, scenario=scenario, frames=args.frames, seed=seed,
                                   progress=False)
            gt = load_ground_truth(root, SEQ)
            gt_cam = read_poses(root / "training" / "poses" / f"{SEQ}.txt")
            label = f"{scenario}-s{seed}"
            for name in args.rows:
                row = ROWS[name]
                try:
                    weights, limit = raft_settings(row, args.raft_weights, args.raft_frames)
                    config = build_config(row, args.set + limit)
                    result = None if args.gt_as_estimate else run_slam(root, row, config, weights)
                except NotAvailable as exc:
                    print(f"{label:<14} {name:<10} not available: {str(exc).split(';')[0]}")
                    if not args.gt_as_estimate:
                        continue
                if args.gt_as_estimate:  # the config does not matter here
                    result = gt_as_estimate(gt, np.random.default_rng(seed))
                canonical = canonical_track_ids(result.objects)
                ev = evaluate_object_tracks(result.objects.reported(), result.camera_poses, gt,
                                            max_occlusion=args.max_occlusion,
                                            max_truncation=args.max_truncation,
                                            canonical_ids=canonical,
                                            box_frames=camera_box_frames(row, result.objects,
                                                                         canonical))
                cam = evaluate_camera(gt_cam, result.camera_poses)
                evaluations.setdefault(name, []).append(ev)
                row_figures = figures.setdefault(label, {})[name] = issue11_figures(root, result, ev)
                print(format_row(label, name, ev, cam, result, row_figures), flush=True)
                if args.targets:
                    print(f"{'':<14} {'targets':<10} {targets_line(row_figures)}")
                if args.per_car:
                    print(ev.format_table())
                    canonical = [f"{c.gt_id}: {c.ate_canonical:.3f} m" for c in ev.cars
                                 if np.isfinite(c.ate_canonical)]
                    if canonical:  # issue 11's figure, car by car
                        print("canonical ATE per car: " + ", ".join(canonical))
    print_summary(figures, args.rows, evaluations)
    return 0


if __name__ == "__main__":
    sys.exit(main())
