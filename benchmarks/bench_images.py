"""Camera image decoding: the core's PNG reader against Pillow, on the same files in one run.

    .venv/bin/python benchmarks/bench_images.py [--repeats 20] [--images 20] [--sim ROOT]

For each set (the real KITTI tracking 0001 left images in ``$TWISTSLAM_DATA``; with ``--sim``,
a simulated sequence's, e.g. ``.cache/sim/urban-seed0-n100``) prints, per image and then as
the median over the set, the median wall time (ms) of
- ``core``: ``twistslam.datasets.read_image`` (the C++ core: libdeflate for plain RGB PNGs,
  cpp/io/png_decoder.hpp),
- ``Pillow``: ``PIL.Image.open(...).convert("RGB")`` (libpng + zlib), the peer,
- ``zlib``: ``zlib.decompress`` of the file's joined IDAT stream alone, what any zlib-based
  decoder spends before unfiltering (for scale, not a decoder),
the ratio Pillow / core, and whether the two decoders gave the same pixels on every image.
"""

from __future__ import annotations

import argparse
import struct
import time
import zlib
from pathlib import Path

import numpy as np
from PIL import Image

from twistslam.datasets import data_root, read_image


def median_ms(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(times))


def idat_stream(path: Path) -> bytes:
    """The PNG file's IDAT payloads joined (its zlib stream)."""
    data, at, parts = path.read_bytes(), 8, []
    while at + 8 <= len(data):
        (length,) = struct.unpack(">I", data[at:at + 4])
        if data[at + 4:at + 8] == b"IDAT":
            parts.append(data[at + 8:at + 8 + length])
        at += 12 + length
    return b"".join(parts)


def pillow_rgb(path: Path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"))


def bench_set(name: str, images: list[Path], repeats: int) -> None:
    if not images:
        print(f"{name}: no images")
        return
    rows, same = [], True
    for path in images:
        same &= bool(np.array_equal(read_image(path), pillow_rgb(path)))
        stream = idat_stream(path)
        rows.append((median_ms(lambda: read_image(path), repeats),
                     median_ms(lambda: pillow_rgb(path), repeats),
                     median_ms(lambda: zlib.decompress(stream), repeats)))
    core, pil, inflate = (float(np.median(c)) for c in zip(*rows))
    size = pillow_rgb(images[0]).shape
    print(f"{name}: {len(images)} images of {size[1]} x {size[0]}, {repeats} repeats each")
    print(f"  {'core':>8} {'Pillow':>8} {'zlib':>8} {'Pillow/core':>12}  same pixels")
    print(f"  {core:8.2f} {pil:8.2f} {inflate:8.2f} {pil / core:12.2f}  {'yes' if same else 'NO'}"
          "   (median ms per image)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--images", type=int, default=20, help="images per set (the first ones)")
    parser.add_argument("--sim", type=Path, metavar="ROOT", help="a simulated sequence's root")
    args = parser.parse_args(argv)
    real = data_root() / "kitti_tracking_lidar" / "training" / "image_02" / "0001"
    bench_set(f"real KITTI 0001 ({real})", sorted(real.glob("*.png"))[:args.images], args.repeats)
    if args.sim is not None:
        sim = sorted((args.sim / "training" / "image_02").glob("*/*.png"))[:args.images]
        bench_set(f"simulated ({args.sim})", sim, args.repeats)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
