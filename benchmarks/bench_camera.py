"""Camera accuracy and speed of twistslam (stereo, and stereo + LiDAR depth when the sequence
has scans) side by side with KISS-ICP and small_gicp (LiDAR).

    .venv/bin/python benchmarks/bench_camera.py                        # cached urban-seed0-n100
    .venv/bin/python benchmarks/bench_camera.py --sweep --memory       # + ORB / BA sweep, peak RSS
    .venv/bin/python benchmarks/bench_camera.py --scenario static --frames 100
    .venv/bin/python benchmarks/bench_camera.py --real                 # real KITTI 0001, 27 frames
    .venv/bin/python benchmarks/bench_camera.py --root DIR --seq 0004     # your KITTI tracking

The sequence is either an existing KITTI-layout one (``--root DIR --seq 0000``; ``--real`` is
the 27 real frames of sequence 0001 with stereo and LiDAR in the data folder,
``$TWISTSLAM_DATA/kitti_tracking_lidar``, see :func:`twistslam.datasets.data_root`) or a simulated
one, generated once into ``CACHE/<scenario>-seed<seed>-n<frames>`` (the cache ``make demo``
uses; an existing complete sequence is reused).

The three systems run in this process, one after the other, on the same sequence:

* twistslam: :func:`twistslam.run` on the stereo images, with the demo's settings (movable
  classes masked with the sequence's panoptic labels when it has them, eq. 3) plus ``--set``,
  the camera alone: ``visual_objects.enabled=false`` unless ``--with-objects`` (the object
  tracking leaves the camera's poses unchanged while ``local_ba.dynamic_objects`` is off, the
  default, and about doubles the loop's time: urban seed 0 on 2026-12-06, 19.0 Hz alone, 8.7
  Hz with it, the same RPE and ATE to the digits printed).
  ms/frame is the loop's wall time per frame (the next frame is read in a background thread).
* KISS-ICP (``kiss_icp`` from PyPI, its default config) on the raw LiDAR scans of the same
  frames. ms/frame is ``register_frame`` alone, as KISS-ICP's own pipeline times it (reading
  the scan is excluded and reported beside). Its poses ``T_velo0_velo_i`` are moved into our
  camera frame, ``T_w_c = T_c_velo T_velo0_velo_i T_c_velo^-1`` (world = camera at frame 0).
  On real KITTI scans KISS-ICP's KITTI intrinsic correction is applied, as its KITTI reader
  does; the simulator's scans are exact and left as they are.
* small_gicp (``small_gicp`` from PyPI) as frame-to-frame GICP odometry on the same scans
  (its odometry example's settings, the last motion as the initial guess, 2 threads).
  ms/frame is the downsampling + covariance estimation + alignment of each scan.

All trajectories are scored with :func:`twistslam.eval.camera.evaluate_camera` against the
sequence's ground truth (ATE after SE(3) alignment). Prints one table with a row per system,
then with ``--sweep`` how ORB feature count and local-BA window move accuracy and speed, and
with ``--memory`` the peak RSS of each system run alone in a fresh subprocess. The 1-minute
load average is printed beside every timing: the 2 cores may be shared.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

#: overrides of each sweep row are built from these (section.key, values)
SWEEP_KEYS = ("orb.num_features", "local_ba.window")


# ----------------------------------------------------------------------------- sequence
def resolve_sequence(args) -> tuple[Path, str, str]:
    """``(root, seq, description)``; simulates into the cache when needed."""
    if args.real:
        from twistslam.datasets import data_path

        root = data_path("kitti_tracking_lidar")
        return root, "0001", f"real KITTI tracking 0001, frames 0-26 ({root})"
    if args.root:
        return Path(args.root), args.seq, f"{args.root} seq {args.seq}"
    from twistslam.demo import cached_sequence

    root = cached_sequence(Path(args.cache), scenario=args.scenario, frames=args.frames,
                           seed=args.seed, seq=args.seq, progress=False)
    return root, args.seq, f"simulated {args.scenario}, seed {args.seed} ({root})"


def open_sequence(root: Path, seq: str):
    from twistslam.datasets import KittiTracking

    sequence = KittiTracking(root, seq)
    if sequence.gt_poses is None:
        raise SystemExit(f"bench_camera: {sequence} has no ground-truth poses (poses/ or oxts/)")
    if not (sequence.base / "velodyne" / sequence.seq).is_dir():
        raise SystemExit(f"bench_camera: {sequence} has no velodyne/ scans for KISS-ICP")
    return sequence


def is_simulated(sequence) -> bool:
    """The simulator writes ``<split>/sim/<seq>.json`` beside its sequences."""
    return (sequence.base / "sim" / f"{sequence.seq}.json").is_file()


def n_frames(sequence, max_frames: int | None) -> int:
    n = min(len(sequence), len(sequence.gt_poses))
    return n if max_frames is None else min(n, max_frames)


# ------------------------------------------------------------------------------ config
def make_config(sequence, overrides: list[str], max_frames: int | None):
    """The demo's settings (panoptic masking of movable classes when the sequence has the
    labels), then ``--set`` overrides; ``(config, note)``."""
    from twistslam.config import Config
    from twistslam.demo import MOVABLE_CLASSES
    from twistslam.inputs import PanopticLabels

    config = Config()
    note = "no panoptic labels: camera tracking unmasked"
    if PanopticLabels.find(sequence, config.run.labels_dir) is not None:
        config.override({"tracking.dynamic_class_ids": MOVABLE_CLASSES})
        note = "movable classes masked with the sequence's panoptic labels (as make demo)"
    if max_frames is not None:
        config.override({"run.max_frames": max_frames})
    config.override(list(overrides))
    return config, note


# -------------------------------------------------------------------------------- runs
def load1() -> float:
    return os.getloadavg()[0]


def evaluate(sequence, est: np.ndarray, n: int):
    from twistslam.eval.camera import evaluate_camera

    # (gt, est): the evaluator's argument order
    return evaluate_camera(gt_poses=sequence.gt_poses[:n], est_poses=est)


def run_ours(sequence, config, n: int) -> dict:
    import twistslam

    cpu0, t0 = time.process_time(), time.perf_counter()
    result = twistslam.run(sequence, config, progress=False)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    est = np.full((n, 4, 4), np.nan)
    est[result.frames] = result.camera_poses
    summary = result.timings.summary()
    return {
        "metrics": evaluate(sequence, est, n),
        "median_ms": summary["per_frame_ms"]["median"],
        "hz": summary["hz"],
        "cpu_ms": 1e3 * cpu / len(result),
        "wall_s": wall,
        "load": load1(),
        "lost": result.num_lost,
        "keyframes": int(result.is_keyframe.sum()),
        "map_points": len(result.map_points.get("X_w", ())),
        "lidar_ms": summary["stages"].get("lidar_depth"),
        "offset": result.disparity_offset,
        "offset_source": result.disparity_offset_source,
        "path_ratio": path_length(result.camera_poses) / path_length(sequence.gt_poses[result.frames]),
    }


def path_length(poses: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1).sum())


def lidar_scans(sequence, n: int):
    """``(scan (N, 3) float64, read ms)`` of the first ``n`` frames; real KITTI scans get the
    intrinsic correction kiss_icp's KITTI reader applies (the simulator's scans are exact)."""
    from kiss_icp.pybind import kiss_icp_pybind

    from twistslam.datasets import read_velodyne

    correct = not is_simulated(sequence)
    for i in range(n):
        t0 = time.perf_counter()
        points = read_velodyne(sequence.base / "velodyne" / sequence.seq / f"{i:06d}.bin")
        points = points[:, :3].astype(np.float64)
        if correct:
            points = np.asarray(kiss_icp_pybind._correct_kitti_scan(
                kiss_icp_pybind._Vector3dVector(points)))
        yield points, 1e3 * (time.perf_counter() - t0)


def kiss_poses(sequence, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """KISS-ICP on the first ``n`` scans: ``(T_velo0_velo (n, 4, 4), register ms, read ms)``."""
    from kiss_icp.config import load_config
    from kiss_icp.kiss_icp import KissICP

    config = load_config(None)  # defaults; voxel size from max_range, as kiss_icp's pipeline
    odometry = KissICP(config)
    poses = np.zeros((n, 4, 4))
    register_ms, read_ms = np.zeros(n), np.zeros(n)
    no_timestamps = np.array([])
    for i, (points, read) in enumerate(lidar_scans(sequence, n)):
        t0 = time.perf_counter()
        odometry.register_frame(points, no_timestamps)
        register_ms[i], read_ms[i] = 1e3 * (time.perf_counter() - t0), read
        poses[i] = odometry.last_pose
    return poses, register_ms, read_ms


def gicp_poses(sequence, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """small_gicp frame-to-frame GICP odometry (its odometry example's settings: 0.25 m
    downsampling, 10 neighbours, 1 m correspondences; the last motion as the initial guess),
    2 threads like ours: ``(T_velo0_velo (n, 4, 4), register ms, read ms)``; register ms
    includes the downsampling and covariance estimation of each scan."""
    import small_gicp

    poses = np.zeros((n, 4, 4))
    poses[0] = np.eye(4)
    register_ms, read_ms = np.zeros(n), np.zeros(n)
    previous, motion = None, np.eye(4)
    for i, (points, read) in enumerate(lidar_scans(sequence, n)):
        t0 = time.perf_counter()
        cloud, tree = small_gicp.preprocess_points(points, downsampling_resolution=0.25,
                                                   num_neighbors=10, num_threads=2)
        if previous is not None:
            result = small_gicp.align(previous[0], cloud, previous[1], motion,
                                      registration_type="GICP", max_correspondence_distance=1.0,
                                      num_threads=2)
            motion = result.T_target_source
            poses[i] = poses[i - 1] @ motion
        register_ms[i], read_ms[i] = 1e3 * (time.perf_counter() - t0), read
        previous = (cloud, tree)
    return poses, register_ms, read_ms


def velo_to_camera(poses_velo: np.ndarray, T_c_velo: np.ndarray) -> np.ndarray:
    """``T_w_c = T_c_velo T_velo0_velo_i T_c_velo^-1`` (world = camera at frame 0)."""
    return T_c_velo @ poses_velo @ np.linalg.inv(T_c_velo)


def run_lidar_peer(sequence, n: int, poses_fn) -> dict:
    cpu0, t0 = time.process_time(), time.perf_counter()
    poses_velo, register_ms, read_ms = poses_fn(sequence, n)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    est = velo_to_camera(poses_velo, sequence.calib.T_c_velo)
    return {
        "metrics": evaluate(sequence, est, n),
        "median_ms": float(np.median(register_ms)),
        "hz": n / (register_ms.sum() / 1e3),
        "cpu_ms": 1e3 * cpu / n,  # includes reading the scans
        "wall_s": wall,
        "load": load1(),
        "read_ms": float(np.median(read_ms)),
        "path_ratio": path_length(est) / path_length(sequence.gt_poses[:n]),
    }


# ------------------------------------------------------------------------------ tables
COLUMNS = [("RPE_t mean (m/f)", 16), ("RPE_R mean (deg/f)", 18), ("ATE (m)", 8),
           ("median ms/f", 11), ("Hz", 6), ("CPU ms/f", 8), ("load 1m", 7)]


def row_cells(r: dict) -> list[str]:
    m = r["metrics"]
    return [f"{m.rpe_t_mean:.4f}", f"{m.rpe_r_mean:.4f}", f"{m.ate_rmse:.3f}",
            f"{r['median_ms']:.1f}", f"{r['hz']:.1f}", f"{r['cpu_ms']:.1f}", f"{r['load']:.2f}"]


def print_table(label_header: str, rows: list[tuple[str, dict]], extra_cols=()) -> None:
    """Fixed-width table; ``extra_cols`` are ``(header, width, row -> str)``."""
    width = max(len(label_header), *(len(name) for name, _ in rows))
    header = [f"{label_header:<{width}}"] + [f"{h:>{w}}" for h, w in COLUMNS] + \
        [f"{h:>{w}}" for h, w, _ in extra_cols]
    print("  ".join(header))
    print("  ".join("-" * len(h) for h in header))
    for name, r in rows:
        cells = [f"{name:<{width}}"] + [f"{c:>{w}}" for c, (_, w) in zip(row_cells(r), COLUMNS)]
        cells += [f"{fn(r):>{w}}" for _, w, fn in extra_cols]
        print("  ".join(cells))


# ------------------------------------------------------------------------------ memory
def _status_mb(field: str) -> float:
    """``VmRSS`` / ``VmHWM`` of this process from ``/proc/self/status``, in MB."""
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024
    return float("nan")


def _reset_peak() -> bool:
    """Reset this process's peak RSS (``VmHWM``; Linux >= 4.0), so that the peak read after
    the run is the run's own, not the imports'. False where /proc refuses it."""
    try:
        with open("/proc/self/clear_refs", "w", encoding="ascii") as f:
            f.write("5")
        return True
    except OSError:
        return False


def memory_child(args) -> int:
    """One system alone in this (fresh) process; prints one JSON line.

    ``resource.getrusage(...).ru_maxrss`` is reported too but not used for the table: in a
    child it also holds the parent's RSS at the fork (the kernel carries the pre-exec peak
    over), so the child's own ``VmHWM`` is what we read.
    """
    root, seq = Path(args.root), args.seq
    import twistslam  # noqa: F401  (imports counted in the baseline, as a user's script pays them)
    import kiss_icp.kiss_icp  # noqa: F401

    sequence = open_sequence(root, seq)
    n = n_frames(sequence, args.max_frames)
    _ = sequence[0]  # one frame read: the reader's buffers are part of the baseline
    import_peak = _status_mb("VmHWM")
    before = _status_mb("VmRSS")
    reset = _reset_peak()
    t0 = time.perf_counter()
    out = {"system": args.child, "frames": n, "before_mb": before, "import_peak_mb": import_peak}
    if args.child == "ours":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            config, _ = make_config(sequence, args.set, args.max_frames)
            result = twistslam.run(sequence, config, progress=False)
        out["map_points"] = len(result.map_points.get("X_w", ()))
        out["keyframes"] = int(result.is_keyframe.sum())
    else:
        kiss_poses(sequence, n)
    hwm = _status_mb("VmHWM")
    out.update(run_peak_mb=hwm if reset else float("nan"), peak_mb=max(hwm, import_peak),
               end_mb=_status_mb("VmRSS"), wall_s=time.perf_counter() - t0, load=load1(),
               ru_maxrss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    print("MEMORY " + json.dumps(out), flush=True)
    return 0


def measure_memory(root: Path, seq: str, system: str, args) -> dict:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", system, "--root", str(root),
           "--seq", seq]
    if args.max_frames is not None:
        cmd += ["--max-frames", str(args.max_frames)]
    if args.set:
        cmd += ["--set", *args.set]
    if args.with_objects:
        cmd += ["--with-objects"]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("MEMORY ")]
    if proc.returncode != 0 or not lines:
        raise RuntimeError(f"memory run of {system} failed ({proc.returncode}):\n{proc.stderr}")
    return json.loads(lines[-1][len("MEMORY "):])


# -------------------------------------------------------------------------------- main
def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--root", help="an existing KITTI-layout dataset root (else: simulate)")
    parser.add_argument("--real", action="store_true",
                        help="the real KITTI sequence 0001 of the data folder (TWISTSLAM_DATA)")
    parser.add_argument("--seq", default="0000", help="sequence (default 0000)")
    parser.add_argument("--scenario", default="urban", help="simulator scenario (without --root)")
    parser.add_argument("--frames", type=int, default=100, help="simulated frames (without --root)")
    parser.add_argument("--seed", type=int, default=0, help="simulator seed (without --root)")
    parser.add_argument("--cache", default=".cache/sim", help="where simulated sequences are kept")
    parser.add_argument("--max-frames", type=int, default=None,
                        help="only the first N frames, for both systems")
    parser.add_argument("--set", metavar="SECTION.KEY=VALUE", action="extend", nargs="+",
                        default=[], help="override a twistslam setting (all our runs)")
    parser.add_argument("--sweep", action="store_true",
                        help="ORB feature counts and local-BA windows (--features, --windows)")
    parser.add_argument("--features", default="1000,2000,3000", help="orb.num_features values")
    parser.add_argument("--windows", default="5,10,15", help="local_ba.window values")
    parser.add_argument("--memory", action="store_true",
                        help="peak RSS of each system alone, in a subprocess")
    parser.add_argument("--with-objects", action="store_true",
                        help="keep the visual object tracking on (the whole system's loop time)")
    parser.add_argument("--child", choices=("ours", "kiss"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if not args.with_objects:  # the camera alone (module docstring)
        args.set = ["visual_objects.enabled=false", *(args.set or [])]
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    if args.child:
        return memory_child(args)

    t_start = time.perf_counter()
    root, seq, description = resolve_sequence(args)
    sequence = open_sequence(root, seq)
    n = n_frames(sequence, args.max_frames)
    config, mask_note = make_config(sequence, args.set, args.max_frames)

    import kiss_icp
    import twistslam

    kiss_version = getattr(kiss_icp, "__version__", "?")
    gt = sequence.gt_poses[:n]
    path_m = float(np.linalg.norm(np.diff(gt[:, :3, 3], axis=0), axis=1).sum())
    print(f"sequence: {description}, {n} frames, {path_m:.0f} m driven")
    print(f"twistslam {twistslam.__version__}: {mask_note}"
          + (f"; --set {' '.join(args.set)}" if args.set else ""))
    print(f"KISS-ICP {kiss_version} (PyPI), default config; small_gicp (PyPI), frame-to-frame "
          "GICP" + ("" if is_simulated(sequence) else "; KITTI scan correction for both"))
    print(f"{os.cpu_count()} cores, load average {'/'.join(f'{x:.2f}' for x in os.getloadavg())} "
          f"(1/5/15 min) at start")

    # LiDAR depth on (the default when the sequence has scans) and off, side by side
    has_scans = (sequence.base / "velodyne" / sequence.seq).is_dir()
    stereo_config, _ = make_config(sequence, [*args.set, "lidar.use_depth=false"], args.max_frames)
    stereo_only = run_ours(sequence, stereo_config, n)
    ours = run_ours(sequence, config, n) if config.lidar.use_depth and has_scans else stereo_only
    peers = [("KISS-ICP (LiDAR)", run_lidar_peer(sequence, n, kiss_poses)),
             ("small_gicp (LiDAR)", run_lidar_peer(sequence, n, gicp_poses))]
    print(f"\ncamera trajectory vs ground truth ({n} frames)")
    own_rows = [("twistslam (stereo)", stereo_only)]
    if ours is not stereo_only:
        own_rows.append(("twistslam (+LiDAR dep)", ours))
    print_table("system", [*own_rows, *peers],
                [("path/gt", 7, lambda r: f"{r['path_ratio']:.4f}")])
    om = ours["metrics"]
    for name, peer in peers:
        pm = peer["metrics"]
        ahead = [k for k, a, b in (("RPE_t", om.rpe_t_mean, pm.rpe_t_mean),
                                    ("RPE_R", om.rpe_r_mean, pm.rpe_r_mean),
                                    ("ATE", om.ate_rmse, pm.ate_rmse)) if a < b]
        print(f"vs {name.split()[0]}: ahead on {', '.join(ahead) if ahead else 'nothing'} "
              f"(ratios ours/peer: RPE_t {om.rpe_t_mean / pm.rpe_t_mean:.2f}, "
              f"RPE_R {om.rpe_r_mean / pm.rpe_r_mean:.2f}, ATE {om.ate_rmse / pm.ate_rmse:.2f})")
    print(f"twistslam: {ours['lost']} lost, {ours['keyframes']} keyframes, "
          f"{ours['map_points']} map points; disparity offset {ours['offset']:+.3f} px "
          f"({ours['offset_source']})")
    if ours is not stereo_only and ours["lidar_ms"] is not None:
        print(f"LiDAR depth stage (projection + association): median {ours['lidar_ms']:.2f} ms "
              f"per frame = {100 * ours['lidar_ms'] / ours['median_ms']:.1f} % of the loop's "
              f"{ours['median_ms']:.1f} ms (stereo only: {stereo_only['median_ms']:.1f} ms)")
    print(f"ms/f: twistslam = loop wall time per frame (reading overlapped); LiDAR peers = "
          f"registration only (KISS-ICP register_frame; small_gicp preprocess + align), reading "
          f"a scan is a median {peers[0][1]['read_ms']:.1f} ms more. CPU ms/f = process CPU "
          f"time (all threads) / frames. load 1m = after the run.")

    if args.sweep:
        print(f"\nsweep: one setting changed from the row above (twistslam, {n} frames)")
        rows = []
        base = config.to_dict()
        for key, values in zip(SWEEP_KEYS, (args.features, args.windows)):
            for value in (int(v) for v in values.split(",")):
                cfg, _ = make_config(sequence, [*args.set, f"{key}={value}"], args.max_frames)
                if cfg.to_dict() == base:
                    rows.append((f"{key}={value} (default)", ours))
                    continue
                rows.append((f"{key}={value}", run_ours(sequence, cfg, n)))
        print_table("setting", rows, [("lost", 4, lambda r: str(r["lost"])),
                                       ("KFs", 4, lambda r: str(r["keyframes"]))])
        print("(default) rows repeat the twistslam row above (same settings, not re-run)")

    if args.memory:
        print(f"\npeak memory, each system alone in a fresh process, {n} frames")
        print(f"{'system':<18}  {'frames':>6}  {'peak RSS (MB)':>13}  {'before run (MB)':>15}  "
              f"{'run peak (MB)':>13}  {'growth (MB)':>11}  {'at end (MB)':>11}  {'wall s':>6}  "
              f"{'load 1m':>7}")
        for name, system in (("twistslam (stereo)", "ours"), ("KISS-ICP (LiDAR)", "kiss")):
            m = measure_memory(root, seq, system, args)
            print(f"{name:<18}  {m['frames']:>6}  {m['peak_mb']:>13.0f}  {m['before_mb']:>15.0f}  "
                  f"{m['run_peak_mb']:>13.0f}  {m['run_peak_mb'] - m['before_mb']:>11.0f}  "
                  f"{m['end_mb']:>11.0f}  {m['wall_s']:>6.1f}  {m['load']:>7.2f}"
                  + (f"   ({m['map_points']} map points, {m['keyframes']} keyframes)"
                     if system == "ours" else ""))
        print("VmHWM / VmRSS of the child (/proc/self/status). peak RSS = whole process; before "
              "run = after importing twistslam + kiss_icp and reading frame 0; run peak = peak "
              "from the start of the run (counter reset); growth = run peak - before run")

    print(f"\ntotal {time.perf_counter() - t_start:.0f} s, load average now "
          f"{'/'.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
