"""Camera accuracy with and without masking a priori dynamic classes (paper eq. 3).

    .venv/bin/python benchmarks/bench_masking.py --root .cache/sim/crowded-seed0-n100 [--seq 0000]

Runs the stereo SLAM twice on the same sequence: unmasked, and with the movable Cityscapes
classes of the simulator's panoptic images kept out of camera tracking (the demo's setting),
then prints one row per run: RPE (m/f, deg/f), ATE (m), lost frames and rate.
"""

from __future__ import annotations

import argparse
import os
import warnings

from twistslam import Config, run
from twistslam.datasets import KittiTracking
from twistslam.demo import MOVABLE_CLASSES
from twistslam.eval.camera import evaluate_camera


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--root", required=True, help="KITTI-layout root of the sequence")
    parser.add_argument("--seq", default="0000")
    args = parser.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        seq = KittiTracking(args.root, args.seq)
    rows = []
    for name, classes in [("unmasked", []), ("masked (movable classes)", MOVABLE_CLASSES)]:
        config = Config().override({"tracking.dynamic_class_ids": classes})
        result = run(seq, config, progress=False)
        m = evaluate_camera(gt_poses=seq.gt_poses[: len(result.camera_poses)], est_poses=result.camera_poses)
        hz = result.timings.summary()["hz"]
        rows.append((name, m.rpe_t_mean, m.rpe_r_mean, m.ate_rmse, result.num_lost, hz))
    print(f"sequence {args.root} {args.seq}, load {os.getloadavg()[0]:.1f}")
    print(f"{'run':<26} {'RPE_t (m/f)':>11} {'RPE_R (deg/f)':>13} {'ATE (m)':>8} {'lost':>5} {'Hz':>6}")
    for name, t, r, ate, lost, hz in rows:
        print(f"{name:<26} {t:>11.4f} {r:>13.4f} {ate:>8.3f} {lost:>5d} {hz:>6.1f}")


if __name__ == "__main__":
    main()
