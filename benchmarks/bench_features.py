"""Timing of ORB extraction and stereo matching at KITTI size (1242 x 375).

    .venv/bin/python benchmarks/bench_features.py [--repeats 30] [--features 2000] [--data DIR]

Prints the median wall time (ms) of
- ``extract_orb`` on the left and the right image (two calls, one after the other),
- ``match_stereo`` (both images extracted in parallel, then matched), with its own split,
- cv2's ORB (``cv2.ORB_create(nfeatures)``, detect + compute) on the same two images, side by
  side in the same process when opencv-python(-headless) is importable (skipped otherwise),
on a textured synthetic pair (three fronto-parallel planes at 7, 15 and 40 m seen by KITTI
0000's cameras 2 and 3) and, when the real KITTI images are found, on the real stereo pair of
sequence 0001 frame 10 (``--data``, default ``$TWISTSLAM_DATA/kitti_tracking_lidar``, see
:func:`twistslam.datasets.data_root`; a root with left images only gets a right image
synthesised by a 10-px shift, for timing only).

The tracking budget is < 50 ms per frame for features + stereo on a 2-core machine.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from twistslam import geometry
from twistslam import features
from twistslam.datasets import data_root
from twistslam.sim.planes import KITTI_P2, KITTI_P3, KITTI_SIZE, PlaneScene

P2, P3, (W, H) = KITTI_P2, KITTI_P3, KITTI_SIZE


def synthetic_pair(cam):
    """Three textured fronto-parallel planes, ray-cast for the left and right cameras."""
    scene = PlaneScene.default(cam.fx)
    return [scene.render(cam, right, seed)[0] for right, seed in ((False, 100), (True, 101))]


def real_pair(data: Path):
    """``(name, left, right)``: the real KITTI stereo pair of 0001/000010, or its left image
    and a copy shifted left by 10 px (timing only) when the root has no right images."""
    path = data / "training" / "image_02" / "0001" / "000010.png"
    if not path.exists():
        return None
    from PIL import Image

    left = np.array(Image.open(path).convert("L"))
    right_path = data / "training" / "image_03" / "0001" / "000010.png"
    if right_path.exists():
        return "KITTI 0001/000010 (real stereo)", left, np.array(Image.open(right_path).convert("L"))
    right = np.empty_like(left)
    right[:, :-10] = left[:, 10:]
    right[:, -10:] = left[:, -10:]
    return "KITTI 0001/000010 (shifted right)", left, right


def median_ms(fn, repeats: int) -> tuple[float, float]:
    """Median wall time and median process CPU time (all threads) of fn, in ms."""
    fn()  # warm-up (thread pools, page faults)
    wall, cpu = [], []
    for _ in range(repeats):
        c0, t0 = time.process_time(), time.perf_counter()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return 1e3 * float(np.median(wall)), 1e3 * float(np.median(cpu))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=30)
    parser.add_argument("--features", type=int, default=2000)
    parser.add_argument("--data", default=str(data_root() / "kitti_tracking_lidar"),
                        help="KITTI tracking root with sequence 0001 (default: %(default)s)")
    args = parser.parse_args()
    try:
        import cv2
    except ImportError:
        cv2 = None

    cam = geometry.StereoCamera.from_kitti(P2, P3, W, H)
    pairs = {"synthetic planes": synthetic_pair(cam)}
    real = real_pair(Path(args.data))
    if real is not None:
        pairs[real[0]] = real[1:]
    n = args.features
    print(f"1242x375, {n} features, median of {args.repeats} runs, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}")
    print("wall ms / process CPU ms (all threads); on a shared machine the CPU time is the cost")
    if cv2 is None:
        print("cv2 not importable: the cv2 ORB column is skipped (pip install opencv-python-headless)")
    else:
        print(f"cv2 {cv2.__version__}, {cv2.getNumThreads()} threads")
    print(f"{'pair':<34} {'extract L+R':>13} {'match_stereo':>13} {'(extract':>9} {'match)':>7} "
          f"{'matched':>8} {'cv2 ORB L+R':>13}")
    for name, (left, right) in pairs.items():
        extract = median_ms(lambda: (features.extract_orb(left, num_features=n),
                                     features.extract_orb(right, num_features=n)), args.repeats)
        splits = []

        def stereo():
            r = features.match_stereo(left, right, cam, num_features=n)
            splits.append((r["extract_ms"], r["match_ms"], r["matched"].mean()))

        total = median_ms(stereo, args.repeats)
        ex, ma, rate = (float(np.median(c)) for c in zip(*splits))
        if cv2 is not None:
            orb = cv2.ORB_create(nfeatures=n)
            w, c = median_ms(lambda: (orb.detectAndCompute(left, None), orb.detectAndCompute(right, None)),
                             args.repeats)
            theirs = f"{w:6.1f} /{c:5.1f}"
        else:
            theirs = f"{'skipped':>13}"
        print(f"{name:<34} {extract[0]:6.1f} /{extract[1]:5.1f} {total[0]:6.1f} /{total[1]:5.1f} "
              f"{ex:9.1f} {ma:7.1f} {rate:8.0%} {theirs}")


if __name__ == "__main__":
    main()
