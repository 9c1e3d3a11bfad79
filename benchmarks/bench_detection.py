"""Speed and quality of the classical LiDAR detector (docs/detection.md).

    .venv/bin/python benchmarks/bench_detection.py [--data DIR] [--repeats 5]
        [--tracking ROOT --seq 0001] [--sim ROOT [ROOT ...] --frames 100]
        [--set KEY=VALUE ...]

Real KITTI object frames (``--data``, default ``$TWISTSLAM_DATA/kitti_object``; ~120k points
per scan): median wall ms per scan of the whole detector and of each stage (region of
interest, road, clustering, fit + classes), ``--repeats`` runs per frame (0: no timing); then,
against ``label_2`` Cars, recall and precision at BEV IoU 0.5 and 0.7 (greedy matching by
score, a detection on a Van or DontCare box is neither right nor wrong), for labels within
30 m and within the detector's range, and the KITTI AP_R40 of the Car class (BEV and 3D, IoU
0.7 / 0.5, per difficulty). ``--tracking ROOT`` adds the recall table on a real tracking
sequence (``--seq``, default 0001); the per-box table (below) follows over all real frames.
``--sim ROOT ...`` adds, per simulated KITTI-layout sequence (its ``label_02/0000.txt``) and
over all of them, the recall table and the per-box table: each label's Car matched to one
detection (BEV IoU > 0.3 or centres < 2 m, best score first), median / p90 of the BEV centre
error, yaw error mod pi, |dl|, |dw|, the signed depth error along the line of sight, by
range bin and by view (which faces of the true box the sensor sees), and the duplicates (a
second car box on a matched car). The time includes the float32 -> float64 conversion.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from twistslam._core import detection as _d
from twistslam.datasets import KittiObject, KittiTracking, data_root
from twistslam.eval.detection_ap import evaluate_detections
from twistslam.geometry import box_iou_bev
from twistslam.perception.detection import Detections3D

RANGES_M = (30.0, 60.0)  # m, label ranges the table reports (horizontal distance)
IOUS = (0.5, 0.7)        # BEV IoU thresholds: the loose and the strict KITTI Car thresholds
IGNORED = ("Van", "DontCare")


def greedy_match(det_boxes, det_scores, gt_boxes, iou_threshold):
    """Index of the matched label of every detection (-1: none), best score first."""
    match = np.full(len(det_boxes), -1)
    if not len(det_boxes) or not len(gt_boxes):
        return match
    iou = box_iou_bev(det_boxes, gt_boxes)
    taken = np.zeros(len(gt_boxes), bool)
    for i in np.argsort(-det_scores, kind="stable"):
        candidates = np.where(taken, -1.0, iou[i])
        j = int(np.argmax(candidates))
        if candidates[j] >= iou_threshold:
            match[i], taken[j] = j, True
    return match


def score_frame(out: dict, labels, max_range: float, iou: float, stats: dict) -> None:
    """Adds one frame's counts (true / false positives, labels) to ``stats``."""
    dist = np.hypot(labels.box_3d[:, 0], labels.box_3d[:, 2])
    cars = (labels.cls == "Car") & (dist <= max_range)
    ignored = np.isin(labels.cls, IGNORED) | ((labels.cls == "Car") & ~cars)
    is_car = np.array([c == "Car" for c in out["classes"]], bool)
    boxes, scores = out["boxes"][is_car], out["scores"][is_car]
    in_range = np.hypot(boxes[:, 0], boxes[:, 2]) <= max_range
    boxes, scores = boxes[in_range], scores[in_range]
    gt = labels.box_3d[cars | ignored]
    matched = greedy_match(boxes, scores, gt, iou)
    is_gt_car = cars[cars | ignored]
    hit = matched >= 0
    tp = int(np.sum(is_gt_car[matched[hit]]))
    on_ignored = int(np.sum(~is_gt_car[matched[hit]]))
    stats["tp"] += tp
    stats["dets"] += len(boxes) - on_ignored
    stats["labels"] += int(cars.sum())
    for i in np.flatnonzero(matched >= 0):
        g = gt[matched[i]]
        if is_gt_car[matched[i]]:
            e = abs(boxes[i, 6] - g[6]) % np.pi
            stats["yaw_err"].append(np.degrees(min(e, np.pi - e)))
            stats["size_err"].append(np.abs(boxes[i, 3:6] - g[3:6]))


def quality_table(frames, options: dict) -> None:
    """Recall / precision rows for every (range, IoU), over (points_c, labels) pairs."""
    runs = [(_d.detect(points, options), labels) for points, labels in frames]
    print(f"{'labels within':>13} {'BEV IoU':>7} {'labels':>6} {'dets':>5} {'recall':>6} "
          f"{'precision':>9} {'yaw err':>7} {'|dl| |dw| |dh| (m, median)':>27}")
    for max_range in RANGES_M:
        for iou in IOUS:
            stats = {"tp": 0, "dets": 0, "labels": 0, "yaw_err": [], "size_err": []}
            for out, labels in runs:
                score_frame(out, labels, max_range, iou, stats)
            recall = stats["tp"] / max(stats["labels"], 1)
            precision = stats["tp"] / max(stats["dets"], 1)
            yaw = np.median(stats["yaw_err"]) if stats["yaw_err"] else float("nan")
            size = np.median(stats["size_err"], axis=0) if stats["size_err"] else [np.nan] * 3
            print(f"{max_range:>11.0f} m {iou:>7.1f} {stats['labels']:>6} {stats['dets']:>5} "
                  f"{recall:>6.2f} {precision:>9.2f} {yaw:>5.1f} d "
                  f"{size[0]:>9.2f} {size[1]:>5.2f} {size[2]:>5.2f}")


def timing_table(scans, options: dict, repeats: int) -> None:
    total, stages = [], {"select_ms": [], "ground_ms": [], "cluster_ms": [], "fit_ms": []}
    for points in scans:
        for _ in range(repeats):
            t0 = time.perf_counter()
            out = _d.detect(points, options)
            total.append((time.perf_counter() - t0) * 1e3)
            for k in stages:
                stages[k].append(out["timings"][k])
    n = np.median([len(s) for s in scans])
    print(f"median ms per scan ({len(scans)} scans, median {n:.0f} points, {repeats} runs each, "
          f"load {os.getloadavg()[0]:.2f}): whole {np.median(total):.2f} ms "
          f"(p90 {np.percentile(total, 90):.2f}); "
          + ", ".join(f"{k[:-3]} {np.median(v):.2f}" for k, v in stages.items()))


def ap_table(frames, options: dict) -> None:
    """KITTI AP_R40 (%) of the Car class, BEV and 3D at IoU 0.7 / 0.5, per difficulty, over
    real frames (``Frame`` objects with ``points_c``, ``calib``, ``image_left`` and
    ``objects_gt``)."""
    gt, dets = {}, {}
    for f in frames:
        out = _d.detect(f.points_c, options)
        height, width = f.image_left.shape[:2]
        dets[f.index] = Detections3D(out["boxes"], out["scores"], np.asarray(out["classes"], dtype=object)
                                     ).to_table(f.index, f.calib, (width, height))
        gt[f.index] = f.objects_gt
    result = evaluate_detections(gt, dets, classes=("Car",), metrics=("bev", "3d"))
    print(result.table(), end="")


#: m, range bins of the per-box table (horizontal distance of the true box centre)
BOX_RANGE_BINS = ((0.0, 20.0), (20.0, 40.0), (40.0, 60.0))
#: a detection is a true car's box if their BEV IoU exceeds this or their centres lie within
#: BOX_MATCH_CENTRE_M: loose, so that a box with a biased centre still has its error measured
BOX_MATCH_IOU = 0.3
BOX_MATCH_CENTRE_M = 2.0
#: m, an unmatched car detection whose centre lies within this of a matched car's box (BEV,
#: its own frame) is a duplicate of that car (a second box over the same returns, e.g. one
#: mirrored about the visible face)
DUPLICATE_REACH_M = 1.0


def view_of(box) -> str:
    """Faces of a true box a sensor at the origin can see: ``L`` (an end and a side),
    ``end`` (rear or front only), ``side`` (one side only)."""
    c, s = np.cos(box[6]), np.sin(box[6])
    along = -(box[0] * c - box[2] * s)   # the sensor in the box frame: length axis (c, -s)
    across = -(box[0] * s + box[2] * c)  # width axis (s, c)
    end, side = abs(along) > 0.5 * box[3], abs(across) > 0.5 * box[4]
    return "L" if end and side else ("end" if end else "side")


def inside_bev(box, point, margin: float) -> bool:
    """Whether ``point`` (x, z) lies within ``box`` (BEV) enlarged by ``margin`` m."""
    c, s = np.cos(box[6]), np.sin(box[6])
    dx, dz = point[0] - box[0], point[1] - box[2]
    return (abs(dx * c - dz * s) <= 0.5 * box[3] + margin
            and abs(dx * s + dz * c) <= 0.5 * box[4] + margin)


def match_boxes(boxes, scores, gt):
    """One-to-one matches (detection index, label index), best score first, and the
    unmatched detections lying on a matched car (duplicates)."""
    if not len(boxes) or not len(gt):
        return [], []
    iou = box_iou_bev(boxes, gt)
    dist = np.hypot(boxes[:, None, 0] - gt[None, :, 0], boxes[:, None, 2] - gt[None, :, 2])
    taken, pairs, unmatched = np.zeros(len(gt), bool), [], []
    for i in np.argsort(-scores, kind="stable"):
        ok = ~taken & ((iou[i] > BOX_MATCH_IOU) | (dist[i] < BOX_MATCH_CENTRE_M))
        if ok.any():
            j = int(np.argmax(np.where(ok, iou[i] - 1e-3 * dist[i], -np.inf)))
            pairs.append((int(i), j))
            taken[j] = True
        else:
            unmatched.append(int(i))
    duplicates = [i for i in unmatched
                  if any(inside_bev(gt[j], boxes[i, [0, 2]], DUPLICATE_REACH_M) for _, j in pairs)]
    return pairs, duplicates


def box_errors(det, gt) -> dict:
    """Per-box errors of a matched detection against its true box."""
    e = abs(det[6] - gt[6]) % np.pi
    ray = gt[[0, 2]] / np.hypot(gt[0], gt[2])
    offset = det[[0, 2]] - gt[[0, 2]]
    return {"centre": float(np.hypot(*offset)), "depth": float(offset @ ray),
            "yaw": float(np.degrees(min(e, np.pi - e))),
            "dl": float(det[3] - gt[3]), "dw": float(det[4] - gt[4])}


def box_error_table(runs) -> None:
    """Per-box accuracy of the matched cars by range bin and by view (see ``view_of``)."""
    rows, labels, duplicates = [], 0, 0
    for out, table in runs:
        cars = table.cls == "Car"
        gt = table.box_3d[cars]
        is_car = np.array([c == "Car" for c in out["classes"]], bool)
        boxes, scores = out["boxes"][is_car], out["scores"][is_car]
        pairs, dups = match_boxes(boxes, scores, gt)
        labels += int(cars.sum())
        duplicates += len(dups)
        for i, j in pairs:
            rows.append({**box_errors(boxes[i], gt[j]), "range": float(np.hypot(gt[j, 0], gt[j, 2])),
                         "view": view_of(gt[j])})
    print(f"per-box errors of matched cars (BEV IoU > {BOX_MATCH_IOU} or centre < "
          f"{BOX_MATCH_CENTRE_M} m): {len(rows)} of {labels} labels, {duplicates} duplicates; "
          "median / p90; depth = signed centre error along the line of sight (+ = too far)")
    print(f"{'group':>10} {'n':>5} {'centre m':>11} {'depth m':>7} {'yaw deg':>11} "
          f"{'|dl| m':>11} {'|dw| m':>11} {'dl m':>6}")
    groups = [(f"{lo:.0f}-{hi:.0f} m", lambda r, lo=lo, hi=hi: lo <= r["range"] < hi)
              for lo, hi in BOX_RANGE_BINS]
    groups += [(f"view {v}", lambda r, v=v: r["view"] == v) for v in ("L", "end", "side")]
    groups.append(("all", lambda r: r["range"] < BOX_RANGE_BINS[-1][1]))
    for name, keep in groups:
        sel = [r for r in rows if keep(r)]
        if not sel:
            print(f"{name:>10} {0:>5}")
            continue
        col = {k: np.array([r[k] for r in sel]) for k in ("centre", "depth", "yaw", "dl", "dw")}

        def mp(v):
            return f"{np.median(v):>5.2f}/{np.percentile(v, 90):<5.2f}"
        print(f"{name:>10} {len(sel):>5} {mp(col['centre']):>11} {np.median(col['depth']):>7.2f} "
              f"{mp(col['yaw']):>11} {mp(np.abs(col['dl'])):>11} {mp(np.abs(col['dw'])):>11} "
              f"{np.median(col['dl']):>6.2f}")


def _setting(text: str):
    key, _, value = text.partition("=")
    for convert in (int, float):
        try:
            return key, convert(value)
        except ValueError:
            pass
    return key, value.lower() == "true"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, help="KITTI object root (default: data root / kitti_object)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--sim", type=Path, nargs="+", default=[],
                        help="simulated KITTI tracking roots (sequence 0000 each)")
    parser.add_argument("--frames", type=int, default=100, help="simulated frames used")
    parser.add_argument("--tracking", type=Path,
                        help="real KITTI tracking root with scans (e.g. the data root's "
                             "kitti_tracking_lidar): its sequence --seq as a second real table")
    parser.add_argument("--seq", default="0001")
    parser.add_argument("--set", dest="settings", action="append", type=_setting, default=[],
                        metavar="KEY=VALUE", help="detector option")
    args = parser.parse_args()
    options = dict(args.settings)
    root = args.data or data_root() / "kitti_object"
    ds = KittiObject(root)
    real = [ds.frame(i) for i in ds.ids]
    scans = [np.ascontiguousarray(f.points_c[:, :3], dtype=np.float64) for f in real]
    print(f"== real KITTI object frames ({root})")
    if args.repeats:
        timing_table([f.points_c for f in real], options, args.repeats)
    quality_table([(s, f.objects_gt) for s, f in zip(scans, real)], options)
    ap_table(real, options)
    real_runs = [(_d.detect(s, options), f.objects_gt) for s, f in zip(scans, real)]
    if args.tracking:
        seq = KittiTracking(args.tracking, args.seq)
        frames = [seq[i] for i in range(len(seq))]
        print(f"== real KITTI tracking {args.tracking} {args.seq} ({len(frames)} frames)")
        quality_table([(f.points_c, f.objects_gt) for f in frames], options)
        real_runs += [(_d.detect(f.points_c, options), f.objects_gt) for f in frames]
    print("== real KITTI, all frames above")
    box_error_table(real_runs)
    sim_runs = []
    for root in args.sim:
        seq = KittiTracking(root, "0000")
        n = min(args.frames, len(seq))
        frames = [seq[i] for i in range(n)]
        print(f"== simulated {root} ({n} frames)")
        if args.repeats:
            timing_table([f.points_c for f in frames[:10]], options, args.repeats)
        quality_table([(f.points_c, f.objects_gt) for f in frames], options)
        runs = [(_d.detect(f.points_c, options), f.objects_gt) for f in frames]
        box_error_table(runs)
        sim_runs += runs
    if len(args.sim) > 1:
        print(f"== all {len(args.sim)} simulated sequences")
        box_error_table(sim_runs)

if __name__ == "__main__":
    main()
