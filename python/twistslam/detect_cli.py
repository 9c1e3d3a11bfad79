"""``twistslam detect ROOT --out DIR``: run a 3D detector over KITTI data and write results.

* KITTI object layout (``ROOT/<split>/calib/NNNNNN.txt``, ``velodyne/NNNNNN.bin``): one
  ``DIR/NNNNNN.txt`` per frame in the object label format with a score (16 columns), the files
  the KITTI object devkit and ``twistslam eval-detections`` read.
* KITTI tracking layout with ``--seq NNNN``: ``DIR/NNNN.txt`` in the tracking result format
  (18 columns, track id -1), every frame in one file.

Image boxes are the 3D boxes projected by P2 and clipped to the image; ``alpha`` is
``yaw - atan2(x, z)``. The lead registers :func:`add_detect` in ``twistslam.cli``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path


def _setting(text: str) -> tuple[str, object]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    for convert in (int, float):
        try:
            return key, convert(value)
        except ValueError:
            pass
    if value.lower() in ("true", "false"):
        return key, value.lower() == "true"
    raise argparse.ArgumentTypeError(f"{key}: expected a number or true/false, got {value!r}")


def _image_size(frame) -> tuple[int, int] | None:
    if frame.image_left is None:
        return None
    height, width = frame.image_left.shape[:2]
    return width, height


def _object_lines(table) -> list[str]:
    # the object format is the tracking one without its frame and track id columns
    from twistslam.datasets.labels import format_label_lines

    return [line.split(" ", 2)[2] for line in format_label_lines(table, with_score=True)]


def run_detect(args: argparse.Namespace) -> int:
    """Handler of ``twistslam detect``; returns the exit code."""
    from twistslam.datasets import KittiObject, KittiTracking, ObjectTable, write_tracking_results
    from twistslam.input_checks import check_output_dir
    from twistslam.perception.detection import detection_source

    out = check_output_dir(args.out, "--out")
    options = dict(args.settings or [])
    if options and args.detector != "classical":
        raise ValueError("--set applies to the classical detector only")
    detect = detection_source(args.detector, path=args.input, weights=args.weights,
                              options=options or None)
    if args.seq is not None:
        dataset = KittiTracking(args.root, args.seq, split=args.split)
        frames = (dataset[i] for i in range(len(dataset)))
    else:
        dataset = KittiObject(args.root, split=args.split)
        frames = iter(dataset)
    out.mkdir(parents=True, exist_ok=True)
    tables, seconds, count = [], [], 0
    for frame in frames:
        start = time.perf_counter()
        dets = detect(frame)
        seconds.append(time.perf_counter() - start)
        table = dets.to_table(frame.index, frame.calib, _image_size(frame))
        count += len(table)
        if args.seq is None:
            text = "".join(line + "\n" for line in _object_lines(table))
            (out / f"{frame.index:06d}.txt").write_text(text, encoding="utf-8")
        else:
            tables.append(table)
    if args.seq is not None:
        path = out / f"{int(args.seq):04d}.txt"
        write_tracking_results(path, ObjectTable.concat(tables))
        print(f"wrote {path}")
    else:
        print(f"wrote {len(seconds)} files to {out}")
    if seconds:
        ms = sorted(1000.0 * s for s in seconds)
        print(f"{len(seconds)} frames, {count} detections, median {ms[len(ms) // 2]:.1f} ms "
              f"per frame ({args.detector})")
    return 0


def add_detect(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``twistslam detect`` on the ``twistslam`` sub-command parsers."""
    p = sub.add_parser(
        "detect",
        help="3D object detection over KITTI object frames or a tracking sequence",
        description="Run a 3D detector (the classical LiDAR detector by default, 3DSSD with "
        "--weights, or precomputed files) over a KITTI object folder (training/velodyne, "
        "calib) or, with --seq, a tracking sequence, and write KITTI result files.",
    )
    p.add_argument("root", help="KITTI object root (<split>/calib, velodyne) or tracking root")
    p.add_argument("--out", required=True, help="output folder (NNNNNN.txt per frame, or SEQ.txt)")
    p.add_argument("--detector", default="classical", choices=("classical", "3dssd", "files"),
                   help="detection source (default: classical)")
    p.add_argument("--weights", help="3DSSD checkpoint (--detector 3dssd)")
    p.add_argument("--input", help="detection file or folder (--detector files)")
    p.add_argument("--seq", help="tracking sequence number, e.g. 0001 (tracking layout)")
    p.add_argument("--split", default="training", help="dataset split folder (default: training)")
    p.add_argument("--set", dest="settings", action="append", type=_setting, metavar="KEY=VALUE",
                   help="classical detector option (repeatable), e.g. --set max_range_m=50")
    p.set_defaults(handler=run_detect)
    return p
