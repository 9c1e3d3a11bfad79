"""Generalized ICP of object scans: ours against small_gicp, Open3D and PCL in one run.

    .venv/bin/python benchmarks/bench_gicp.py [--sim .cache/sim/urban-seed0-n100]
        [--max-pairs 60] [--repeats 3] [--seed 0]

Scan pairs (points inside a labelled car's box enlarged by ``OBJECT_SCAN_MARGIN_M``, its road
cut off, at least ``--min-points`` in both):

* ``real-consecutive``: KITTI tracking 0001 (frames 0-26 under the data root), the same car
  in frames i and i+1. Ground truth = the labels' box difference, itself only good to a few
  cm and ~0.1-0.3 deg, and KITTI scans are not de-skewed: errors here are vs the labels.
* ``real-known``: each real car scan against itself moved by a known random motion
  (0.2-0.5 m, 2-5 deg about the car) with 1 cm Gaussian noise on the moved copy: exact
  ground truth, real scan geometry (the same samples though, which is easier than reality).
* ``sim-consecutive`` (with ``--sim``): a cached simulated sequence, the same car in
  consecutive frames; ground truth from the simulator's labels (exact poses, 1e-6 rounding).

Every method gets the same points, the same initial guess (ground truth moved by 0.2 m and
2 deg in a random direction), 20 neighbours per covariance, a 1 m correspondence distance, at
most 30 iterations, and runs single-threaded (small_gicp ``num_threads=1``; Open3D's OpenMP
loops limited by ``OMP_NUM_THREADS=1``, set before it is imported; PCL 1.13's GICP has no
threads). Each method stops by its own convergence test: ours and small_gicp at an update
below 1 mm and 1e-3 rad, PCL at a change below the same (its transformation and rotation
epsilons), Open3D at its default relative fitness / RMSE change of 1e-6 (its normal call; it
has no update-size test). Times are wall times of the whole call from numpy arrays (every
method builds both scans' trees and covariances inside the timed call, then aligns;
``ours-reuse`` is ours with the target scan built beforehand, as in the tracker); each pair is
timed ``--repeats`` times per method, interleaved, and the fastest kept (the machine is
shared).
Errors: how far the car centre lands from where ground truth puts it (cm; the translation of
T itself would mix in rotation error times the car's distance) and the rotation angle (deg).
"""

from __future__ import annotations

import argparse
import os
import time
from importlib.metadata import version
from pathlib import Path

# Single-threaded peers: Open3D's covariance and correspondence loops are OpenMP-parallel.
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import open3d as o3d  # noqa: E402
import small_gicp  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

from twistslam import registration as reg  # noqa: E402
from twistslam._core import registration as _core_registration  # noqa: E402
from twistslam.datasets import KittiTracking, data_path  # noqa: E402

#: Same for every method (issue 11: "same max correspondence distance and neighbour count").
NUM_NEIGHBORS = 20
MAX_CORRESPONDENCE_DISTANCE_M = 1.0
MAX_ITERATIONS = 30
#: Convergence: an update below 1 mm and 1e-3 rad (our defaults; given to small_gicp too).
TRANSLATION_EPS_M = 1e-3
ROTATION_EPS_RAD = 1e-3
#: Initial guess = ground truth moved by this much: a constant-velocity prediction's typical
#: miss for a car at 10 Hz.
INIT_OFFSET_M, INIT_OFFSET_DEG = 0.2, 2.0
#: Noise (m) on the moved copy of the real-known pairs: KITTI's HDL-64 range noise, ~1-2 cm.
KNOWN_NOISE_M = 0.01
#: The issue's accuracy target on exact ground truth.
TARGET_CM, TARGET_DEG = 1.0, 0.1


def random_motion(centre: np.ndarray, dist_m: float, angle_deg: float,
                  rng: np.random.Generator) -> np.ndarray:
    """A rigid motion rotating by angle_deg about a random axis through `centre`, then moving
    by dist_m in a random direction."""
    axis, direction = rng.normal(size=3), rng.normal(size=3)
    R = Rotation.from_rotvec(np.radians(angle_deg) * axis / np.linalg.norm(axis)).as_matrix()
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = centre - R @ centre + dist_m * direction / np.linalg.norm(direction)
    return T


def consecutive_pairs(seq: KittiTracking, min_points: int, max_pairs: int) -> list[dict]:
    cars = seq.gt_objects.of_class("Car")
    frames = {}
    pairs = []
    for f in cars.frames[:-1]:
        now, nxt = cars.in_frame(f), cars.in_frame(f + 1)
        for i, tid in enumerate(now.track_id):
            j = np.flatnonzero(nxt.track_id == tid)
            if len(j) == 0:
                continue
            for k in (f, f + 1):
                if k not in frames:
                    frames[k] = seq.frame(k).points_c
            src = reg.object_scan(frames[f], now.box_3d[i])
            tgt = reg.object_scan(frames[f + 1], nxt.box_3d[j[0]])
            if min(len(src), len(tgt)) < min_points:
                continue
            pairs.append({"source": src, "target": tgt, "centre": nxt.box_3d[j[0], :3],
                          "T_true": reg.box_motion(now.box_3d[i], nxt.box_3d[j[0]])})
            if len(pairs) >= max_pairs:
                return pairs
    return pairs


def known_pairs(real_pairs: list[dict], rng: np.random.Generator) -> list[dict]:
    out = []
    for p in real_pairs:
        target, centre = p["target"], p["centre"]
        T = random_motion(centre, rng.uniform(0.2, 0.5), rng.uniform(2.0, 5.0), rng)
        T_inv = np.linalg.inv(T)
        source = target @ T_inv[:3, :3].T + T_inv[:3, 3] + rng.normal(0, KNOWN_NOISE_M, target.shape)
        out.append({"source": source, "target": target, "centre": centre, "T_true": T})
    return out


# --- the four methods: (source, target, T_init) -> T_target_source ---------------------------

def ours(source, target, T_init):
    return reg.gicp(source, target, T_init, max_correspondence_distance_m=MAX_CORRESPONDENCE_DISTANCE_M,
                    max_iterations=MAX_ITERATIONS, num_neighbors=NUM_NEIGHBORS,
                    convergence_translation_m=TRANSLATION_EPS_M,
                    convergence_rotation_rad=ROTATION_EPS_RAD).T_target_source


def with_small_gicp(source, target, T_init):
    s, t = small_gicp.PointCloud(source), small_gicp.PointCloud(target)
    s_tree, t_tree = small_gicp.KdTree(s, 1), small_gicp.KdTree(t, 1)
    small_gicp.estimate_covariances(s, s_tree, num_neighbors=NUM_NEIGHBORS, num_threads=1)
    small_gicp.estimate_covariances(t, t_tree, num_neighbors=NUM_NEIGHBORS, num_threads=1)
    result = small_gicp.align(t, s, t_tree, init_T_target_source=T_init, registration_type="GICP",
                              max_correspondence_distance=MAX_CORRESPONDENCE_DISTANCE_M,
                              num_threads=1, max_iterations=MAX_ITERATIONS,
                              rotation_epsilon=ROTATION_EPS_RAD,
                              translation_epsilon=TRANSLATION_EPS_M)
    return result.T_target_source


def with_open3d(source, target, T_init):
    knn = o3d.geometry.KDTreeSearchParamKNN(NUM_NEIGHBORS)
    s = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(source))
    t = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(target))
    s.estimate_covariances(knn)
    t.estimate_covariances(knn)
    result = o3d.pipelines.registration.registration_generalized_icp(
        s, t, MAX_CORRESPONDENCE_DISTANCE_M, T_init,
        o3d.pipelines.registration.TransformationEstimationForGeneralizedICP(),
        o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=MAX_ITERATIONS))
    return np.asarray(result.transformation)


def with_pcl(source, target, T_init):
    T, _ = _core_registration._pcl_gicp(source, target, T_init, MAX_CORRESPONDENCE_DISTANCE_M,
                                        MAX_ITERATIONS, NUM_NEIGHBORS,
                                        transformation_epsilon=TRANSLATION_EPS_M,
                                        rotation_epsilon=ROTATION_EPS_RAD)
    return T


def ours_target_reused(source, target_scan, T_init):
    """The tracker's use: the target (frame i) scan was built as frame i's source already, so
    a pair costs one scan build and the alignment."""
    return reg.gicp(reg.make_scan(source, NUM_NEIGHBORS), target_scan, T_init,
                    max_correspondence_distance_m=MAX_CORRESPONDENCE_DISTANCE_M,
                    max_iterations=MAX_ITERATIONS, convergence_translation_m=TRANSLATION_EPS_M,
                    convergence_rotation_rad=ROTATION_EPS_RAD).T_target_source


METHODS = {"ours": ours, "small_gicp": with_small_gicp, "open3d": with_open3d, "pcl": with_pcl,
           "ours-reuse": ours_target_reused}


def run(pairs: list[dict], repeats: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Per method: (n_pairs, 3) best time (ms), centre error (cm), rotation error (deg)."""
    rows: dict[str, list] = {m: [] for m in METHODS}
    for p in pairs:
        T_init = random_motion(p["centre"], INIT_OFFSET_M, INIT_OFFSET_DEG, rng) @ p["T_true"]
        best = {m: np.inf for m in METHODS}
        estimate = {}
        target_scan = reg.make_scan(p["target"], NUM_NEIGHBORS)  # outside the timing
        for _ in range(repeats):
            for name, method in METHODS.items():
                target = target_scan if method is ours_target_reused else p["target"]
                t0 = time.perf_counter()
                estimate[name] = method(p["source"], target, T_init)
                best[name] = min(best[name], time.perf_counter() - t0)
        for name in METHODS:
            dt, dr = reg.motion_error(p["T_true"], estimate[name], p["centre"])
            rows[name].append((1e3 * best[name], 100 * dt, dr))
    return {m: np.array(r) for m, r in rows.items()}


def print_table(title: str, pairs: list[dict], results: dict[str, np.ndarray], exact: bool) -> None:
    sizes = np.array([len(p["source"]) + len(p["target"]) for p in pairs]) / 2
    print(f"\n{title}: {len(pairs)} pairs, median {np.median(sizes):.0f} points per scan "
          f"({sizes.min():.0f}-{sizes.max():.0f})")
    head = f"{'method':<11} {'median ms':>9} {'x ours':>7} {'err cm':>7} {'err deg':>8}"
    print(head + (f" {'<1cm&<0.1deg':>13}" if exact else ""))
    t_ours = np.median(results["ours"][:, 0])
    for name, r in results.items():
        t = np.median(r[:, 0])
        line = (f"{name:<11} {t:9.2f} {t / t_ours:7.1f} {np.median(r[:, 1]):7.2f} "
                f"{np.median(r[:, 2]):8.3f}")
        if exact:
            ok = np.mean((r[:, 1] < TARGET_CM) & (r[:, 2] < TARGET_DEG))
            line += f" {100 * ok:12.0f}%"
        print(line)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sim", type=Path, help="cached simulated sequence root "
                        "(e.g. .cache/sim/urban-seed0-n100)")
    parser.add_argument("--max-pairs", type=int, default=60, help="pairs per set")
    parser.add_argument("--min-points", type=int, default=100, help="points per scan, at least")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per pair and method")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    print(f"small_gicp {version('small_gicp')}, open3d {o3d.__version__}; k = {NUM_NEIGHBORS}, "
          f"d_max = {MAX_CORRESPONDENCE_DISTANCE_M} m, init {INIT_OFFSET_M} m / "
          f"{INIT_OFFSET_DEG} deg off, best of {args.repeats}, "
          f"OMP_NUM_THREADS={os.environ['OMP_NUM_THREADS']}")
    real = consecutive_pairs(KittiTracking(data_path("kitti_tracking_lidar"), 1),
                             args.min_points, args.max_pairs)
    sets = [("real-consecutive (0001, vs labels)", real, False),
            ("real-known (0001 scans, exact motion, 1 cm noise)", known_pairs(real, rng), True)]
    if args.sim is not None:
        sim = consecutive_pairs(KittiTracking(args.sim, 0), args.min_points, args.max_pairs)
        sets.append((f"sim-consecutive ({args.sim.name})", sim, True))
    for title, pairs, exact in sets:
        print_table(title, pairs, run(pairs, args.repeats, rng), exact)


if __name__ == "__main__":
    main()
