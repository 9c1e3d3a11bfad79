"""Detections linked into tracks and evaluated: the evaluator on real KITTI files.

The PointRCNN car detections of sequence 0001 (the detector the paper's LiDAR branch
stands on) are linked into tracks frame to frame with the paper's association rule (nearest
box centre, valid under 2 m), written in the KITTI tracking result format, read back and
evaluated against the ground-truth labels. The output is the paper's table layout.

Writes ``OUT/results/tracking/0001.txt``, ``OUT/metrics.json``, ``OUT/report.md`` and
``OUT/plots/*.png``.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

from .datasets import DATA_ENV, ObjectTable, read_detections, write_tracking_results
from .datasets import data_root as default_data_root

#: m, centre distance under which a detection continues a track (the paper's 2 m rule)
ASSOCIATION_GATE = 2.0
#: detections below this PointRCNN score are dropped (its logit; ~0.5 probability)
MIN_SCORE = 0.0


def link_detections(detections: ObjectTable, gate: float = ASSOCIATION_GATE) -> ObjectTable:
    """Track ids for per-frame detections: each frame's boxes are assigned to the previous
    frame's by Hungarian matching on centre distance, pairs farther than ``gate`` metres are
    not linked, and unlinked boxes start new tracks."""
    track_id = np.full(len(detections), -1, dtype=np.int64)
    next_id = 0
    prev_rows = np.zeros(0, dtype=np.int64)
    for frame in detections.frames:
        rows = np.flatnonzero(detections.frame == frame)
        if len(prev_rows) and len(rows):
            dist = np.linalg.norm(
                detections.box_3d[prev_rows, None, :3] - detections.box_3d[None, rows, :3], axis=2
            )
            cost = np.where(dist < gate, dist, 1e6)
            for i, j in zip(*linear_sum_assignment(cost)):
                if dist[i, j] < gate:
                    track_id[rows[j]] = track_id[prev_rows[i]]
        for r in rows[track_id[rows] < 0]:
            track_id[r] = next_id
            next_id += 1
        prev_rows = rows
    return ObjectTable(**{**vars(detections), "track_id": track_id})


def run_detection_demo(data_root: Path, out: Path, seq: str = "0001") -> dict:
    """Link, write, evaluate; returns the metrics dictionary (the ``metrics.json`` layout)."""
    from .eval.plots import plot_trajectories
    from .eval.report import render_markdown, render_text
    from .eval.sequence import evaluate_sequence

    det_path = data_root / "detections" / "pointrcnn_car_val" / f"{seq}.txt"
    detections = read_detections(det_path)
    detections = detections.select(detections.score >= MIN_SCORE)
    tracks = link_detections(detections)
    results = out / "results"
    write_tracking_results(results / "tracking" / f"{seq}.txt", tracks)
    print(f"{det_path.name}: {len(detections)} detections linked into "
          f"{len(tracks.track_ids)} tracks -> {results / 'tracking' / f'{seq}.txt'}")

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # e.g. no oxts (camera-frame objects): said in the report
        metrics = evaluate_sequence(data_root, results, seq)
    print(render_text(metrics), end="")
    as_dict = metrics.to_dict()
    (out / "metrics.json").write_text(json.dumps(as_dict, indent=2) + "\n", encoding="utf-8")
    (out / "report.md").write_text(render_markdown(metrics), encoding="utf-8")
    plots = plot_trajectories(metrics, out / "plots")
    print(f"wrote {out / 'metrics.json'}, {out / 'report.md'}, {len(plots)} plot(s) in {out / 'plots'}")
    return as_dict


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m twistslam.detection_demo", description=__doc__.split("\n")[0])
    parser.add_argument("--data", default=None,
                        help=f"KITTI tracking root (default: ${DATA_ENV}/kitti_tracking, "
                             f"now {default_data_root() / 'kitti_tracking'})")
    parser.add_argument("--out", default="demo_out/detections", help="output directory")
    parser.add_argument("--seq", default="0001")
    args = parser.parse_args(argv)
    data = Path(args.data) if args.data else default_data_root() / "kitti_tracking"
    if not (data / "training" / "calib").is_dir():
        print(f"demo: no KITTI tracking data at {data} (expected {data}/training/calib; "
              f"give --data or set {DATA_ENV})", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    run_detection_demo(data, out, args.seq)
    return 0


if __name__ == "__main__":
    sys.exit(main())
