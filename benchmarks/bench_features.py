"""Timing of ORB extraction and stereo matching at KITTI size (1242 x 375).

    .venv/bin/python benchmarks/bench_features.py [--repeats 30] [--features 2000]

Prints the median wall time (ms) of
- ``extract_orb`` on the left and the right image (two calls, one after the other),
- ``match_stereo`` (both images extracted in parallel, then matched), with its own split,
- cv2's ORB (``cv2.ORB_create(nfeatures)``, detect + compute) on the same two images, side by
  side in the same process when opencv-python(-headless) is importable (skipped otherwise),
on a textured synthetic pair (three fronto-parallel planes at 7, 15 and 40 m seen by KITTI
0000's cameras 2 and 3) and, when the bundled KITTI images are found, on a real left image
(its right image is synthesised by a 10-px shift, for timing only).

The tracking budget is < 50 ms per frame for features + stereo on a 2-core machine.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter, map_coordinates

from twistslam import geometry
from twistslam._core import features

P2 = np.array([[721.5377, 0, 609.5593, 44.85728], [0, 721.5377, 172.854, 0.2163791],
               [0, 0, 1, 0.002745884]])
P3 = np.array([[721.5377, 0, 609.5593, -339.5242], [0, 721.5377, 172.854, 2.199936],
               [0, 0, 1, 0.002729905]])
W, H = 1242, 375


def texture(shape, seed):
    rng = np.random.default_rng(seed)
    acc = np.zeros(shape)
    for sigma, weight in ((0.8, 0.6), (2.0, 0.8), (5.0, 1.0)):
        n = gaussian_filter(rng.normal(size=shape), sigma)
        acc += weight * n / n.std()
    return (acc - acc.mean()) * (40.0 / acc.std()) + 128.0


def synthetic_pair(cam):
    """Three textured fronto-parallel planes, ray-cast for the left and right cameras."""
    planes = [(40.0, (-40, -12, 40, 12)), (15.0, (-1.0, -3.0, 6.0, 1.5)), (7.0, (-5.0, -2.0, -0.5, 1.2))]
    textures = []
    for k, (z, (x0, y0, x1, y1)) in enumerate(planes):
        texel = 1.3 * z / cam.fx
        shape = (int(np.ceil((y1 - y0) / texel)) + 3, int(np.ceil((x1 - x0) / texel)) + 3)
        textures.append((texel, texture(shape, k + 1)))
    v, u = np.mgrid[0:H, 0:W].astype(float)
    images = []
    for offset, seed in ((cam.t_left, 100), (cam.t_right, 101)):
        o = -np.asarray(offset)
        best, img = np.full(u.shape, np.inf), np.zeros(u.shape)
        for (z, (x0, y0, x1, y1)), (texel, tex) in zip(planes, textures):
            s = z - o[2]
            X = o[0] + s * (u - cam.cx) / cam.fx
            Y = o[1] + s * (v - cam.cy) / cam.fy
            take = (X >= x0) & (X <= x1) & (Y >= y0) & (Y <= y1) & (s < best)
            best[take] = s
            img[take] = map_coordinates(tex, [1 + (Y[take] - y0) / texel, 1 + (X[take] - x0) / texel], order=1)
        img += np.random.default_rng(seed).normal(0, 1.0, img.shape)
        images.append(np.clip(np.rint(img), 0, 255).astype(np.uint8))
    return images


def real_pair(data: Path):
    """A real KITTI left image and a copy shifted left by 10 px (timing only)."""
    path = data / "training" / "image_02" / "0001" / "000010.png"
    if not path.exists():
        return None
    from PIL import Image

    left = np.array(Image.open(path).convert("L"))
    right = np.empty_like(left)
    right[:, :-10] = left[:, 10:]
    right[:, -10:] = left[:, -10:]
    return left, right


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
    parser.add_argument("--data", default=str(Path(__file__).resolve().parents[2] / "shared/data/kitti_tracking"))
    args = parser.parse_args()
    try:
        import cv2
    except ImportError:
        cv2 = None

    cam = geometry.StereoCamera.from_kitti(P2, P3, W, H)
    pairs = {"synthetic planes": synthetic_pair(cam)}
    real = real_pair(Path(args.data))
    if real is not None:
        pairs["KITTI 0001/000010 (shifted right)"] = real
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
