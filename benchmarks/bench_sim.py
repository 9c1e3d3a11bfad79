"""Simulator speed at full KITTI resolution, and preview images of one sequence.

    .venv/bin/python benchmarks/bench_sim.py                       # 30 urban frames, 1242 x 375
    .venv/bin/python benchmarks/bench_sim.py --frames 100 --previews docs/images/sim

Reports the one-off world build (streets, meshes, traffic simulation, textures) and the
per-frame rate of everything written per frame: two colour images, a LiDAR scan with
labels, panoptic ids, disparity, two flow maps, labels and oracle detections. With
``--previews DIR`` it also writes a left/right image pair, a LiDAR bird view with the
labelled boxes and a colour-coded panoptic mask of the middle frame.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _timed_generate(out: Path, args) -> tuple[float, float, float]:
    """(world build seconds, rendering seconds, rendering CPU seconds) of one run."""
    import twistslam.sim.generate  # noqa: F401  (the module, not the function re-exported by the package)

    gen = sys.modules["twistslam.sim.generate"]
    world_cls = gen.World
    times = {}

    class TimedWorld(world_cls):
        def __init__(self, cfg):
            t = time.perf_counter()
            super().__init__(cfg)
            times["world"] = time.perf_counter() - t
            times["start"] = time.perf_counter()
            times["cpu"] = time.process_time()

    gen.World = TimedWorld
    try:
        gen.generate(out, args.scenario, frames=args.frames, seed=args.seed, width=args.width, height=args.height,
                     progress=False, overwrite=True)
    finally:
        gen.World = world_cls
    return times["world"], time.perf_counter() - times["start"], time.process_time() - times["cpu"]


def previews(out: Path, dest: Path, frame: int) -> list[Path]:
    """Left/right pair, LiDAR bird view and panoptic mask of ``frame`` as PNGs in ``dest``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    from twistslam.datasets import KittiTracking
    from twistslam.geometry import box_corners
    from twistslam.datasets.png16 import read_png16

    dest.mkdir(parents=True, exist_ok=True)
    seq = KittiTracking(out, "0000")
    f = seq[frame]
    paths = [dest / "sim_urban_stereo.png", dest / "sim_urban_lidar_bev.png", dest / "sim_urban_panoptic.png"]
    # previews are quantised to 256 colours: small enough to keep in the repository
    Image.fromarray(np.vstack([f.image_left, f.image_right])).quantize(256).save(paths[0], optimize=True)

    fig, ax = plt.subplots(figsize=(8, 8), dpi=100)
    p = f.points_c
    keep = (np.abs(p[:, 0]) < 40) & (p[:, 2] > -20) & (p[:, 2] < 60)
    ax.scatter(p[keep, 0], p[keep, 2], s=0.2, c=-p[keep, 1], cmap="viridis", vmin=-1.8, vmax=2.0)
    for box, cls in zip(f.objects_gt.box_3d, f.objects_gt.cls):
        c = box_corners(box[None])[0][[0, 1, 2, 3, 0]]
        ax.plot(c[:, 0], c[:, 2], color="red" if cls == "Car" else "orange", lw=1)
    ax.plot([0], [0], "k^", ms=8)
    ax.set(xlim=(-40, 40), ylim=(-20, 60), xlabel="x (m, camera right)", ylabel="z (m, camera forward)",
           title=f"LiDAR bird view, frame {frame}: height colour, labelled boxes")
    ax.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(paths[1])
    plt.close(fig)

    pan = read_png16(out / "training" / "panoptic" / "0000" / f"{frame:06d}.png").astype(np.int64)
    palette = {7: (128, 64, 128), 8: (244, 35, 232), 11: (70, 70, 70), 14: (180, 165, 180), 17: (153, 153, 153),
               20: (220, 220, 0), 21: (107, 142, 35), 22: (152, 251, 152), 23: (70, 130, 180)}
    rgb = np.zeros(pan.shape + (3,), np.uint8)
    cls = np.where(pan >= 1000, pan // 1000, pan)
    for k, colour in palette.items():
        rgb[cls == k] = colour
    inst = np.where(pan >= 1000, pan % 1000, 0)
    rng = np.random.default_rng(0)
    colours = rng.integers(60, 255, size=(1000, 3), dtype=np.uint8)
    things = inst > 0
    rgb[things] = colours[inst[things]]
    rgb[things & (cls == 26)] = (0.5 * rgb[things & (cls == 26)] + [0, 0, 70]).astype(np.uint8)
    Image.fromarray(np.vstack([f.image_left, rgb])).quantize(256).save(paths[2], optimize=True)
    return paths


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--scenario", default="urban")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--width", type=int, default=1242)
    parser.add_argument("--height", type=int, default=375)
    parser.add_argument("--out", default=None, help="keep the sequence here (default: a temporary folder)")
    parser.add_argument("--previews", default=None, metavar="DIR", help="write preview PNGs of the middle frame")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.out) if args.out else Path(tmp) / "sim"
        # other jobs on the machine slow the wall clock (not the CPU time): report the load
        load_before = os.getloadavg()
        world_s, render_s, cpu_s = _timed_generate(out, args)
        fps = args.frames / render_s
        print(f"scenario {args.scenario}, {args.width}x{args.height}, {args.frames} frames, seed {args.seed}")
        print(f"world build        {world_s:7.2f} s (once per sequence)")
        print(f"render + write     {render_s:7.2f} s = {render_s / args.frames:.3f} s/frame -> {fps:.2f} frames/s")
        print(f"CPU time           {cpu_s / args.frames:7.3f} CPU-s/frame (all threads; {os.cpu_count()} cores give at"
              f" most {os.cpu_count()} CPU-s per s)")
        print("load average       before " + " ".join(f"{v:.2f}" for v in load_before)
              + ", after " + " ".join(f"{v:.2f}" for v in os.getloadavg()) + " (1, 5, 15 min; includes this run)")
        total = world_s + render_s * 100 / args.frames
        print(f"a 100-frame sequence: ~{total:.0f} s")
        if args.previews:
            for path in previews(out, Path(args.previews), args.frames // 2):
                print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
