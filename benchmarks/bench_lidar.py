"""Timing of the LiDAR depth association at KITTI size (docs/lidar.md).

    .venv/bin/python benchmarks/bench_lidar.py [--repeats 50] [--keypoints 2000] [--data DIR]

Prints the median wall time (ms) per frame of
- ``project_scan``: a full 360 deg scan projected into the left image and bucketed,
- ``lidar_depth_at``: the depth of every keypoint (gather, layer split, plane fit),
- their sum (the per-frame cost; target <= 4 ms on the 2-core development machine),
on the real KITTI 0001 frame 10 scan (~120k points; ``--data``, default
``$TWISTSLAM_DATA/kitti_tracking_lidar``) with the left image's ORB keypoints, and on a
synthetic 120k-point scan (64 lines x 1875 azimuths around a 20 m cylinder with a road) with
uniformly random keypoints. Points enter as (N, 4) float64 (x y z intensity; float32 scans are
converted once, outside the timing, as a caller holding float64 points would not pay it).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from twistslam import features, lidar
from twistslam.datasets import data_root, read_calibration, read_image, read_velodyne
from twistslam.geometry import StereoCamera
from twistslam.sim.planes import KITTI_P2, KITTI_P3, KITTI_SIZE


def median_ms(fn, repeats: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(times)), out


def synthetic_scan(n_lines: int = 64, n_azimuth: int = 1875) -> np.ndarray:
    """HDL-64-like scan (frame c: x right, y down, z forward) of a road 1.65 m below the
    sensor inside a 20 m cylinder of walls: every return has a surface."""
    elevation = np.radians(np.linspace(2.0, -24.8, n_lines))[:, None]
    azimuth = np.linspace(-np.pi, np.pi, n_azimuth, endpoint=False)[None, :]
    down = -np.sin(elevation)
    rng_road = np.where(down > 1e-3, 1.65 / np.maximum(down, 1e-3), np.inf)
    rng = np.minimum(rng_road, 20.0 / np.cos(elevation)) * np.ones_like(azimuth)
    x = rng * np.cos(elevation) * np.sin(azimuth)
    y = -rng * np.sin(elevation)
    z = rng * np.cos(elevation) * np.cos(azimuth)
    return np.c_[x.ravel(), y.ravel(), z.ravel(), np.ones(x.size)]


def real_frame(data: Path, n_keypoints: int):
    root = data / "training"
    velo = root / "velodyne" / "0001" / "000010.bin"
    if not velo.exists():
        return None
    calib = read_calibration(root / "calib" / "0001.txt")
    left = read_image(root / "image_02" / "0001" / "000010.png")
    cam = calib.stereo_camera(left.shape[1], left.shape[0])
    scan = lidar.correct_kitti_scan(read_velodyne(velo))
    T = calib.T_c_velo
    points = np.c_[scan[:, :3] @ T[:3, :3].T + T[:3, 3], scan[:, 3]]
    keypoints = features.extract_orb(left, num_features=n_keypoints)["keypoints"]
    return cam, points, keypoints


def bench(name: str, cam, points: np.ndarray, keypoints: np.ndarray, repeats: int) -> None:
    points = np.ascontiguousarray(points, dtype=np.float64)
    t_proj, scan = median_ms(lambda: lidar.project_scan(points, cam), repeats)
    t_depth, out = median_ms(lambda: lidar.lidar_depth_at(keypoints, scan), repeats)
    t_both, _ = median_ms(lambda: lidar.lidar_depth_at(keypoints, lidar.project_scan(points, cam)),
                          repeats)
    print(f"{name}: {len(points)} points ({scan.num_returns} in the image), "
          f"{len(keypoints)} keypoints ({int(out['valid'].sum())} with LiDAR depth)")
    print(f"  project_scan    {t_proj:7.3f} ms (median of {repeats})")
    print(f"  lidar_depth_at  {t_depth:7.3f} ms")
    print(f"  per frame       {t_both:7.3f} ms   (target <= 4 ms)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=50)
    ap.add_argument("--keypoints", type=int, default=2000)
    ap.add_argument("--data", type=Path, default=None)
    args = ap.parse_args()
    data = args.data or data_root() / "kitti_tracking_lidar"
    real = real_frame(data, args.keypoints)
    if real is not None:
        bench("real KITTI 0001/000010", *real, args.repeats)
    else:
        print(f"real KITTI scan not found under {data} (set TWISTSLAM_DATA): synthetic only")
    (W, H) = KITTI_SIZE
    cam = StereoCamera.from_kitti(KITTI_P2, KITTI_P3, W, H)
    rng = np.random.default_rng(0)
    keypoints = np.c_[rng.uniform(0, W, args.keypoints), rng.uniform(0, H, args.keypoints)]
    bench("synthetic 64 x 1875 scan", cam, synthetic_scan(), keypoints, args.repeats)


if __name__ == "__main__":
    main()
