"""3D multi-object tracking from PointRCNN detections: twistslam vs AB3DMOT, one run, one
evaluator (the KITTI devkit protocol, Car, 3D IoU 0.25).

    .venv/bin/python benchmarks/bench_mot.py [--seqs 0001 0006 0008 0010 0012] [--no-ablation]
    .venv/bin/python benchmarks/bench_mot.py --sim .cache/sim/urban-seed0-n100 [--seqs 0000]

Data: ``$TWISTSLAM_DATA`` (default ``shared/data`` beside the repository): labels and
detections in ``kitti_tracking/``, AB3DMOT's outputs in ``ab3dmot/``. Two splits of the 15
labelled sequences with detections: the *validation* split of 3D MOT papers (0001 0006 0008
0010 0012; AB3DMOT's outputs exist for these) and the *tuning* split (the other 10: 0000
0002 0003 0004 0005 0007 0009 0011 0017 0020), on which every value of the ``objects``
config was chosen (docs/objects.md) before the validation figures were read. Prints

1. validation, per sequence and overall, every output box (no threshold) of both, then both
   at their score threshold (ours: ``objects.min_track_score``, chosen on the tuning split;
   AB3DMOT: its shipped 3.240738, chosen on the validation split itself): MOTA, MOTP, IDSW,
   FRAG, FP, FN, sAMOTA, AMOTA, HOTA; then the tuning split overall (ours only: AB3DMOT's
   outputs are not shipped for it);
2. an ablation row per design choice, overall on both splits (same protocol);
3. smoothness of the tracks (RMS of the frame-to-frame change of speed and of yaw rate, in
   each frame's camera frame, tracks of >= 10 frames), ours vs AB3DMOT's Kalman tracks vs
   the ground-truth labels;
4. speed: frames/s of the C++ tracker per sequence (median), peak memory (RSS). AB3DMOT
   (Python, not installable here) is given by its published speed, marked as such.

``--sim ROOT``: a simulated sequence (``twistslam sim``; ``make demo`` caches the urban one)
with its noisy oracle detections (``ROOT/detections/oracle``) and exact ground truth. No
AB3DMOT output exists there; the reference row is our tracker without the window
optimisation (detection boxes linked by the motion model). Prints MOT (devkit protocol) and
the paper's object-pose metrics, canonical (no alignment), averaged over the moving cars
(ground-truth world displacement > 1 m): ATE (m), RPE translation (m/m), rotation (deg/m),
and the yaw error of the reported boxes (deg).
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import warnings
from pathlib import Path

import numpy as np

import twistslam
from twistslam.datasets import KittiTracking, data_path, read_labels, read_tracking_results
from twistslam.eval.mot import evaluate_mot

SEQS = ["0001", "0006", "0008", "0010", "0012"]  # validation split
TUNING_SEQS = ["0000", "0002", "0003", "0004", "0005", "0007", "0009", "0011", "0017", "0020"]
AB3DMOT_THRESHOLD = 3.240738  # its shipped Car threshold for PointRCNN (ab3dmot/README.md)
AB3DMOT_PUBLISHED_HZ = 207.4  # AB3DMOT paper, KITTI, Python (not measured here)
COLUMNS = ("mota", "motp", "idsw", "frag", "fp", "fn", "samota", "amota", "hota")

ABLATIONS = {
    "defaults": [],
    "cost: iou_bev": ["objects.association=iou_bev", "objects.max_cost=0.99"],
    "cost: centre_distance (2 m)": ["objects.association=centre_distance", "objects.max_cost=2.0",
                                    "objects.second_pass_max_cost=1.0"],
    "no second pass": ["objects.second_pass=false"],
    "no e_const": ["objects.use_const=false"],
    "no e_det": ["objects.use_det_twist=false"],
    "no detection prior": ["objects.use_prior=false"],
    "no window optimisation": ["objects.optimize=false"],
    "free link (no planar)": ["objects.planar_classes=[]"],
    "camera frame (no ego motion)": ["objects.frame=camera"],
    "AB3DMOT's birth: 3 hits": ["objects.birth_hits=3"],
    "raw score (no range correction)": ["objects.range_score_slope=0"],
    "no backcast of far-born tracks": ["objects.backcast_frames=0"],
    "gaps predicted, not interpolated": ["objects.interpolate_gaps=false"],
    "turn kept through misses (decay 1)": ["objects.miss_turn_decay=1"],
    "short life: max_misses 2, gap 3": ["objects.max_misses=2", "objects.max_reported_gap=3"],
    "births from score 1": ["objects.birth_score=1"],
    "all of the 6 above (before)": ["objects.range_score_slope=0", "objects.backcast_frames=0",
                                    "objects.interpolate_gaps=false", "objects.miss_turn_decay=1",
                                    "objects.max_misses=2", "objects.max_reported_gap=3",
                                    "objects.birth_score=1"],
}


def track_all(root: Path, seqs: list[str], overrides: list[str], out: Path) -> list[float]:
    """Run the tracker on every sequence, write ``out/tracking_all`` and ``out/tracking``;
    returns frames/s per sequence."""
    config = twistslam.Config()
    config.override(overrides)
    fps = []
    for seq in seqs:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # labels-only root: no images, no scans
            sequence = KittiTracking(root, seq)
        result = twistslam.track_detections(sequence, root / "detections" / "pointrcnn_car_val",
                                            config)
        result.save(out)
        fps.append(result.frames_per_second)
    return fps


def has_labels(root: Path, seq: str) -> bool:
    """The sequence has Car or Van labels. The evaluator's devkit bookkeeping needs some
    (0017 has none: pedestrians only); such a sequence's boxes are counted, not scored."""
    labels = read_labels(root / "training" / "label_02" / f"{seq}.txt")
    return bool(np.isin(labels.cls, ["Car", "Van"]).any())


def evaluate(root: Path, results: Path, seqs: list[str], min_score=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return evaluate_mot(root, results, [s for s in seqs if has_labels(root, s)],
                            protocol="kitti", min_score=min_score)


def unscored_boxes(root: Path, results: Path, seqs: list[str], min_score: float) -> str:
    """Boxes at or above ``min_score`` on the sequences without labels (see has_labels)."""
    parts = []
    for seq in seqs:
        if not has_labels(root, seq):
            t = read_tracking_results(results / "tracking" / f"{seq}.txt")
            parts.append(f"{seq}: {int((t.score >= min_score).sum())} boxes >= {min_score:g} "
                         f"({len(t)} in all)")
    return "; ".join(parts)


def fmt(m) -> str:
    d = m.to_dict()
    out = []
    for k in COLUMNS:
        v = d.get(k, float("nan"))
        out.append(f"{v:7d}" if isinstance(v, (int, np.integer)) else f"{float(v):7.2f}")
    return " ".join(out)


def print_table(title: str, rows: list[tuple[str, object]]) -> None:
    print(f"\n{title}")
    print(f"{'':44s} " + " ".join(f"{c.upper():>7s}" for c in COLUMNS))
    for name, m in rows:
        print(f"{name:44s} {fmt(m)}")


def smoothness(table) -> tuple[float, float, int]:
    """RMS frame-to-frame change of speed (m/s per frame) and yaw rate (deg/s per frame)
    over tracks of at least 10 consecutive frames; and the number of such tracks."""
    d_speed, d_yaw = [], []
    n = 0
    for tid in table.track_ids:
        t = table.select(table.track_id == tid).sorted()
        runs = np.split(np.arange(len(t)), np.flatnonzero(np.diff(t.frame) != 1) + 1)
        for run in runs:
            if len(run) < 10:
                continue
            c = t.box_3d[run, :3][:, [0, 2]]
            speed = np.linalg.norm(np.diff(c, axis=0), axis=1) / 0.1
            yaw = np.unwrap(t.box_3d[run, 6] * 2) / 2  # heading modulo pi
            yaw_rate = np.degrees(np.diff(yaw)) / 0.1
            d_speed.append(np.diff(speed))
            d_yaw.append(np.diff(yaw_rate))
            n += 1
    rms = lambda parts: float(np.sqrt(np.mean(np.concatenate(parts) ** 2))) if parts else float("nan")  # noqa: E731
    return rms(d_speed), rms(d_yaw), n


def simulated(sim_root: Path, seqs: list[str]) -> None:
    """Ours with and without the window on a simulated sequence's oracle detections."""
    from twistslam.eval.sequence import evaluate_sequence

    print(f"simulated {sim_root} {' '.join(seqs)}: oracle detections, devkit protocol, Car, 3D IoU 0.25")
    rows = {"twistslam": [], "no window optimisation": ["objects.optimize=false"]}
    with tempfile.TemporaryDirectory() as tmp:
        for name, overrides in rows.items():
            out = Path(tmp) / name.replace(" ", "_")
            config = twistslam.Config()
            config.override(overrides)
            fps, poses, yaw = [], [], []
            for seq in seqs:
                sequence = KittiTracking(sim_root, seq)
                result = twistslam.track_detections(sequence, sim_root / "detections" / "oracle", config)
                result.save(out)
                (out / "every").mkdir(exist_ok=True)
                (out / "every" / "tracking").mkdir(exist_ok=True)
                (out / "every" / "tracking" / f"{seq}.txt").write_bytes(
                    (out / "tracking_all" / f"{seq}.txt").read_bytes())
                fps.append(result.frames_per_second)
                moving = {tid for tid, t in sequence.gt_tracks.items()
                          if np.ptp(t.T_w_o[:, :3, 3], axis=0).max() > 1.0}
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    metrics = evaluate_sequence(sequence, out / "every", seq, score_metrics=False)
                poses += [(o.ate, o.rpe_t, o.rpe_r) for o in metrics.objects
                          if o.track_id in moving and np.isfinite(o.ate)]
                yaw += list(yaw_errors(sequence.gt_objects, result.tracking))
            mot = evaluate(sim_root, out / "every", seqs).overall
            p = np.nanmean(np.array(poses), axis=0) if poses else [np.nan] * 3
            print(f"  {name:24s} {fmt(mot)}")
            print(f"  {'':24s} moving cars {len(poses)}: ATE {p[0]:.3f} m, RPE_t {p[1]:.3f} m/m, "
                  f"RPE_R {p[2]:.3f} deg/m, yaw error median {np.median(yaw):.2f} deg; "
                  f"{np.median(fps):.0f} frames/s")
    print(f"  columns: {' '.join(c.upper() for c in COLUMNS)}")


def yaw_errors(gt, est) -> np.ndarray:
    """|yaw difference| (deg, modulo 180) of each reported box to its best 3D-IoU label box."""
    from twistslam import geometry

    out = []
    for f in np.intersect1d(gt.frames, est.frames):
        g, e = gt.in_frame(f).of_class("Car"), est.in_frame(f)
        if not len(g) or not len(e):
            continue
        iou = geometry.box_iou_3d(e.box_3d, g.box_3d)
        k = iou.argmax(axis=1)
        ok = iou[np.arange(len(e)), k] >= 0.25
        d = np.abs(np.angle(np.exp(2j * (e.box_3d[ok, 6] - g.box_3d[k[ok], 6])))) / 2
        out += list(np.degrees(d))
    return np.array(out)


def run_split(root: Path, seqs: list[str], overrides: list[str], out: Path):
    """Track ``seqs`` with ``overrides``; ``out/every/tracking`` holds every box. Returns the
    frames/s per sequence."""
    fps = track_all(root, seqs, overrides, out)
    (out / "every").mkdir(exist_ok=True)
    if not (out / "every" / "tracking").exists():
        (out / "every" / "tracking").symlink_to(out / "tracking_all")
    return fps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seqs", nargs="+", default=None,
                        help="validation sequences (default: the validation split)")
    parser.add_argument("--tuning-seqs", nargs="*", default=None,
                        help="tuning sequences (default: the tuning split; none: skip it)")
    parser.add_argument("--no-ablation", action="store_true")
    parser.add_argument("--sim", metavar="ROOT", help="a simulated sequence root (see above)")
    args = parser.parse_args()
    if args.sim:
        simulated(Path(args.sim), args.seqs or ["0000"])
        return
    args.seqs = args.seqs or SEQS
    tuning = TUNING_SEQS if args.tuning_seqs is None else args.tuning_seqs
    root = data_path("kitti_tracking")
    ab3dmot = data_path("ab3dmot")
    threshold = twistslam.Config().objects.min_track_score
    print(f"load average {os.getloadavg()[0]:.2f}; protocol kitti (devkit), Car, 3D IoU 0.25")
    print(f"validation split {' '.join(args.seqs)}; tuning split {' '.join(tuning) or '(skipped)'}")

    with tempfile.TemporaryDirectory() as tmp:
        ours = Path(tmp) / "ours"
        fps = run_split(root, args.seqs, [], ours)
        all_boxes = ours / "every"
        runs = {
            "twistslam, every box": evaluate(root, all_boxes, args.seqs),
            "AB3DMOT raw, every box": evaluate(root, ab3dmot / "raw", args.seqs),
            f"twistslam, track score >= {threshold:g}": evaluate(root, all_boxes, args.seqs, threshold),
            "AB3DMOT thresholded (3.24)": evaluate(root, ab3dmot / "thresholded", args.seqs),
        }
        for seq in args.seqs:
            print_table(f"validation, sequence {seq}", [(k, v.sequences[seq]) for k, v in runs.items()])
        print_table("validation, overall (counts summed over the sequences)",
                    [(k, v.overall) for k, v in runs.items()])
        if tuning:
            tuned = Path(tmp) / "tuning"
            run_split(root, tuning, [], tuned)
            rows = [("twistslam, every box", evaluate(root, tuned / "every", tuning).overall),
                    (f"twistslam, track score >= {threshold:g}",
                     evaluate(root, tuned / "every", tuning, threshold).overall)]
            print_table("tuning split, overall (AB3DMOT's outputs are not shipped for it)", rows)
            note = unscored_boxes(root, tuned / "every", tuning, threshold)
            if note:
                print(f"  not scored (no Car / Van label): {note}")

        if not args.no_ablation:
            splits = {"validation": args.seqs} | ({"tuning": tuning} if tuning else {})
            for split, seqs in splits.items():
                rows = []
                for name, overrides in ABLATIONS.items():
                    out = Path(tmp) / f"ablation_{split}_{len(rows)}"
                    run_split(root, seqs, overrides, out)
                    rows.append((f"{name} (all)", evaluate(root, out / "every", seqs).overall))
                    rows.append((f"{name} (>= {threshold:g})",
                                 evaluate(root, out / "every", seqs, threshold).overall))
                print_table(f"ablation, {split} split (overall)", rows)

        print("\nsmoothness (validation, camera frame, tracks >= 10 frames): RMS d(speed) "
              "m/s/frame, RMS d(yaw rate) deg/s/frame, tracks")
        sources = {"twistslam (>= threshold)": lambda s: read_tracking_results(ours / "tracking" / f"{s}.txt"),
                   "AB3DMOT thresholded": lambda s: read_tracking_results(ab3dmot / "thresholded" / "tracking" / f"{s}.txt"),
                   "ground truth (labels)": lambda s: read_labels(root / "training" / "label_02" / f"{s}.txt").of_class("Car")}
        for name, load in sources.items():
            tables = [load(s) for s in args.seqs]
            per = [smoothness(t) for t in tables]
            n = sum(p[2] for p in per)
            w = np.array([p[2] for p in per], dtype=float)
            ds = np.sqrt(np.nansum(w * np.array([p[0] for p in per]) ** 2) / w.sum())
            dy = np.sqrt(np.nansum(w * np.array([p[1] for p in per]) ** 2) / w.sum())
            print(f"  {name:28s} {ds:8.3f} {dy:8.2f} {n:5d}")

    print("\nspeed: C++ tracker frames/s per sequence "
          + " ".join(f"{s}:{f:.0f}" for s, f in zip(args.seqs, fps))
          + f"; median {np.median(fps):.0f} frames/s")
    print(f"AB3DMOT: {AB3DMOT_PUBLISHED_HZ:.0f} frames/s published (Python; not run here) -> "
          f"ratio {np.median(fps) / AB3DMOT_PUBLISHED_HZ:.1f}x")
    print(f"peak memory (RSS of this process, all runs): "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")


if __name__ == "__main__":
    main()
