"""Timing of the evaluator on the real KITTI tracking labels (ground truth as the result).

    .venv/bin/python benchmarks/bench_eval.py [--data DIR]   # default $TWISTSLAM_DATA/kitti_tracking

Prints, per sequence, the number of labelled boxes and the median wall time of
``evaluate_sequence`` over repeats, and the throughput of the C++ pairwise IoUs.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from twistslam import geometry
from twistslam.datasets import data_root, read_labels
from twistslam.eval.sequence import evaluate_sequence


def median_time(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", default=str(data_root() / "kitti_tracking"),
                        help="KITTI tracking root with training/label_02 (default: %(default)s)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    data = Path(args.data)
    if not (data / "training" / "label_02").is_dir():
        raise SystemExit(f"bench_eval: no KITTI tracking labels in {data}/training/label_02 "
                         "(give --data or set TWISTSLAM_DATA)")
    work = Path(tempfile.mkdtemp())
    print(f"{'seq':>5} {'boxes':>7} {'eval median (s)':>16}")
    try:
        for label in sorted((data / "training" / "label_02").glob("*.txt")):
            seq = label.stem
            results = work / seq
            (results / "tracking").mkdir(parents=True)
            shutil.copy(label, results / "tracking" / label.name)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t = median_time(lambda: evaluate_sequence(data, results, seq), args.repeats)
            print(f"{seq:>5} {len(read_labels(label)):>7} {t:>16.3f}")
    finally:
        shutil.rmtree(work)

    rng = np.random.default_rng(0)
    boxes = np.column_stack([
        rng.uniform(-20, 20, 400), rng.uniform(0.5, 2, 400), rng.uniform(5, 60, 400),
        rng.uniform(3.5, 5, 400), rng.uniform(1.6, 2, 400), rng.uniform(1.4, 1.8, 400),
        rng.uniform(-np.pi, np.pi, 400),
    ])
    for name, fn in [("box_iou_bev", geometry.box_iou_bev), ("box_iou_3d", geometry.box_iou_3d)]:
        t = median_time(lambda: fn(boxes, boxes), 5)
        print(f"{name}: 400 x 400 pairs in {t * 1e3:.2f} ms ({160000 / t / 1e6:.2f} M pairs/s)")


if __name__ == "__main__":
    main()
