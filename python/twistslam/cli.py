"""Command line: ``twistslam <command> ...``.

Each command is a ``_add_<name>(subparsers)`` that registers its arguments and a handler
``args -> exit code``; :func:`main` dispatches. Errors a user can fix (missing or malformed
files, bad options) are printed as one ``twistslam <command>: error: ...`` line with exit
code 2, not as a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

from .detect_cli import add_detect
from .eval_detections_cli import add_eval_detections
from .train_detector_cli import add_train_detector


def _iou(text: str) -> float:
    value = float(text)
    if not 0.0 < value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be in (0, 1], got {text}")
    return value


def _run_eval(args: argparse.Namespace) -> int:
    # imported here, not at the top: keeps `twistslam --help` fast (no scipy, matplotlib)
    from .eval.report import load_paper_tables, render_markdown, render_text
    from .eval.sequence import evaluate_sequence
    from .input_checks import check_output_dir, check_output_file

    # outputs checked first: an unwritable --json must not cost a whole evaluation
    for option in ("json", "markdown"):
        if getattr(args, option):
            check_output_file(getattr(args, option), f"--{option}")
    if args.plots:
        check_output_dir(args.plots, "--plots")
    metrics = evaluate_sequence(
        args.root, args.results, args.seq,
        iou_threshold=args.iou, difficulty=args.difficulty, cls=args.cls,
        object_alignment="se3" if args.align_objects else "none", split=args.split,
        protocol=args.protocol,
    )
    paper = load_paper_tables(args.paper) if args.paper else None
    print(render_text(metrics, paper), end="")
    if args.json:
        path = Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(metrics.to_dict(), indent=2) + "\n", encoding="utf-8")
        print(f"wrote {path}")
    if args.markdown:
        path = Path(args.markdown)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(render_markdown(metrics, paper), encoding="utf-8")
        print(f"wrote {path}")
    if args.plots:
        from .eval.plots import plot_trajectories

        for p in plot_trajectories(metrics, args.plots):
            print(f"wrote {p}")
    return 0


def _add_eval(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "eval",
        help="evaluate results against KITTI tracking ground truth",
        description="Camera RPE / ATE, per-object ATE / RPE, TP and MOTP (2D, bird view, 3D), "
        "CLEAR MOT, sAMOTA / AMOTA / AMOTP and HOTA of one sequence, printed as the paper's "
        "tables; every MOT number names the protocol that produced it.",
    )
    p.add_argument("root", help="KITTI tracking root (holding training/calib, label_02, ...)")
    p.add_argument("results", help="results directory: camera_poses.txt and/or tracking/XXXX.txt")
    p.add_argument("--seq", required=True, help="sequence number, e.g. 0001")
    p.add_argument("--split", default="training", help="dataset split folder (default: training)")
    p.add_argument("--json", metavar="FILE", help="write the metrics as JSON")
    p.add_argument("--markdown", metavar="FILE", help="write the tables as Markdown")
    p.add_argument("--plots", metavar="DIR", help="write bird-view trajectory PNGs")
    p.add_argument("--iou", type=_iou, default=0.25, help="IoU threshold of a true positive")
    p.add_argument("--protocol", default="clear", choices=["clear", "kitti"],
                   help="clear: CLEAR MOT definitions, the paper's object tables (default); "
                   "kitti: the KITTI tracking devkit as AB3DMOT's evaluate.py runs it")
    p.add_argument("--difficulty", default=None, choices=["easy", "moderate", "hard"],
                   help="default: the protocol's (clear: easy, kitti: hard)")
    p.add_argument("--cls", default="car", help="evaluated class (car, pedestrian, ...)")
    p.add_argument("--align-objects", action="store_true",
                   help="report object ATE after SE(3) alignment (systems without canonical pose)")
    p.add_argument("--paper", metavar="TABLES_JSON",
                   help="the paper's tables.json: print its rows beside ours")
    p.set_defaults(handler=_run_eval)


def _check_out(out: str, overwrite: bool) -> None:
    """``--out`` is writable, and holds no earlier results unless ``--overwrite``: checked
    before tracking, so a run never ends in an error that loses its results."""
    from .input_checks import check_output_dir
    from .result import FILES

    names = (*FILES.values(), "tracking")  # the camera's files, the objects' tracking/
    existing = [name for name in names if (Path(out) / name).exists()]
    if existing and not overwrite:
        raise ValueError(f"--out {out} already holds results ({', '.join(existing)}); pass "
                         "--overwrite to replace them, or choose another folder")
    check_output_dir(out, "--out")


def _load_config(path: str | None):
    from .config import Config

    if path is None:
        return Config()
    if Path(path).is_dir():
        raise ValueError(f"--config {path}: is a folder, expected a YAML file")
    return Config.from_yaml(path)


def _run_run(args: argparse.Namespace) -> int:
    from .datasets import MissingDataWarning, open_sequence

    config = _load_config(args.config)
    config.override(args.set)
    _check_out(args.out, args.overwrite)
    with warnings.catch_warnings():
        if args.no_images:  # images, scans are not read: do not warn that they are missing
            warnings.simplefilter("ignore", MissingDataWarning)
        sequence = open_sequence(args.root, args.seq, split=args.split)
    if args.no_images and not args.detections:
        raise ValueError("--no-images needs --detections (objects from detections alone)")
    if args.no_images:
        return _run_objects(args, config, sequence)
    from .pipeline import run

    result = run(sequence, config, progress=not args.no_progress,
                 segmentation=args.segmentation, flow=args.flow, viz=args.viz,
                 viz_save=args.viz_save, segmentation_weights=_segmentation_weights(args),
                 detections=args.detections, detector=args.detector,
                 detector_weights=args.weights)
    paths = result.save(args.out)
    t = result.timings.summary()
    print(f"{result.seq or args.root}: {len(result)} frames, {t['hz']:.1f} Hz "
          f"(median {t['per_frame_ms']['median']:.1f} ms/frame), {result.num_lost} lost, "
          f"{int(result.is_keyframe.sum())} keyframes")
    for name, ms in t["after_loop_ms"].items():
        print(f"after the last frame: {name} {ms:.0f} ms")
    print(f"wrote {', '.join(p.name for p in paths.values())} in {args.out}")
    return 0


def _segmentation_weights(args: argparse.Namespace) -> dict | None:
    """``--maskrcnn-weights`` / ``--semantic-weights`` as run()'s segmentation_weights."""
    files = {"maskrcnn": args.maskrcnn_weights, "semantic": args.semantic_weights}
    files = {k: v for k, v in files.items() if v is not None}
    if files and args.segmentation != "torch":
        raise ValueError("--maskrcnn-weights / --semantic-weights need --segmentation torch")
    return files or None


def _run_objects(args: argparse.Namespace, config, sequence) -> int:
    """``run --detections DIR --no-images``: 3D multi-object tracking from detections."""
    from .objects import track_detections

    result = track_detections(sequence, args.detections, config)
    paths = result.save(args.out)
    n_tracks = sum(o.reported.any() for o in result.objects)
    print(f"{result.seq}: {result.num_frames} frames, {n_tracks} tracks, "
          f"{len(result.thresholded())} boxes, {result.frames_per_second:.0f} frames/s "
          f"(tracking in the {result.frame} frame)")
    print(f"wrote {', '.join(str(p.relative_to(args.out)) for p in paths.values())} in {args.out}")
    return 0


def _add_run(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "run",
        help="track the camera through a stereo sequence and write the results",
        description="Stereo SLAM on one KITTI-tracking-layout sequence (real or simulated). "
        "Writes OUT/camera_poses.txt (what `twistslam eval` reads), OUT/timings.json, "
        "OUT/config.yaml (the resolved settings) and OUT/status.txt (per-frame status).",
    )
    p.add_argument("root", help="dataset root (holding training/calib, image_02, image_03, ...), "
                   "or a path into one sequence when --seq is not given")
    p.add_argument("--seq", help="sequence number, e.g. 0000")
    p.add_argument("--out", required=True, help="results directory")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the results an earlier run wrote into --out")
    p.add_argument("--split", default="training", help="dataset split folder (default: training)")
    p.add_argument("--config", metavar="FILE", help="YAML file of settings (partial is fine)")
    p.add_argument("--set", metavar="SECTION.KEY=VALUE", action="extend", nargs="+", default=[],
                   help="override a setting after --config, e.g. --set tracking.min_inliers=40 "
                   "run.max_frames=20 (repeatable)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--detections", metavar="DIR",
                   help="3D detections: DIR/SEQ.txt (PointRCNN comma format or KITTI tracking "
                   "results) or DIR/SEQ/NNNNNN.txt (KITTI object results), for the masks "
                   "from boxes and the LiDAR fusion (default: the sequence's detections/*/); "
                   "with --no-images, writes OUT/tracking/SEQ.txt (objects tracked from the "
                   "detections alone)")
    p.add_argument("--detector", default="auto",
                   choices=["auto", "files", "classical", "3dssd", "none"],
                   help="3D detections of the LiDAR fusion of object tracking (canonical pose, "
                   "size, e_det, e_reg): files (--detections or the sequence's), classical "
                   "(the LiDAR detector of the core, no weights), 3dssd (needs --weights), "
                   "none (the camera alone); auto: files when there are any, else classical "
                   "when the sequence has scans (default: auto)")
    p.add_argument("--weights", metavar="FILE", type=Path, default=None,
                   help="--detector 3dssd: the checkpoint (twistslam train-detector)")
    p.add_argument("--no-images", action="store_true",
                   help="do not run the stereo SLAM (objects from --detections only)")
    p.add_argument("--segmentation", default="auto",
                   choices=["auto", "files", "boxes", "torch", "none"],
                   help="panoptic segmentation source: files (the sequence's panoptic PNGs), "
                   "boxes (masks from the 3D boxes of --detector, or of the detection files "
                   "with --detector none), torch (Mask R-CNN + semantic network, needs "
                   "--maskrcnn-weights), none; auto: files when the sequence has them, else "
                   "boxes when it has LiDAR scans (default: auto)")
    p.add_argument("--maskrcnn-weights", metavar="FILE", type=Path, default=None,
                   help="--segmentation torch: state dict of a torchvision-layout "
                   "maskrcnn_resnet50_fpn (COCO classes); nothing is downloaded")
    p.add_argument("--semantic-weights", metavar="FILE", type=Path, default=None,
                   help="--segmentation torch: state dict of a torchvision-layout "
                   "deeplabv3_resnet50 or fcn_resnet50 (VOC classes) for the stuff; "
                   "optional (without it, pixels outside the things are unknown)")
    p.add_argument("--flow", default="auto", choices=["auto", "files", "dis", "raft", "none"],
                   help="optical flow source: files (the sequence's flow files), dis (OpenCV "
                   "DIS), raft (torchvision RAFT, needs weights), none; auto: files when the "
                   "sequence has them, else dis (default: auto)")
    p.add_argument("--viz", action="store_true",
                   help="live view: spawn a rerun viewer (needs pip install 'twistslam[viz]')")
    p.add_argument("--viz-save", metavar="FILE.rrd", type=Path, default=None,
                   help="write the rerun recording to FILE.rrd, no viewer needed "
                   "(needs pip install 'twistslam[viz]')")
    p.set_defaults(handler=_run_run)


def _add_sim(sub: argparse._SubParsersAction) -> None:
    """``twistslam sim``, registered by the simulator itself when it is installed."""
    try:
        from .sim.cli import add_sim_parser, run_sim
    except ModuleNotFoundError as exc:
        if exc.name in ("twistslam.sim", "twistslam.sim.cli"):
            return  # a build without the simulator: the other commands still work
        raise
    parser = add_sim_parser(sub)
    if parser is not None and parser.get_default("handler") is None:
        parser.set_defaults(handler=run_sim)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="twistslam", description="TwistSLAM++ dynamic SLAM")
    sub = parser.add_subparsers(dest="command", required=True, metavar="command")
    _add_run(sub)
    _add_eval(sub)
    _add_sim(sub)
    add_detect(sub)
    add_eval_detections(sub)
    add_train_detector(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``twistslam`` script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    # warnings are for the user here, not for a developer: one line, no source location
    previous_format = warnings.formatwarning
    warnings.formatwarning = lambda message, category, *_: (
        f"twistslam {args.command}: warning: {message}\n"
    )
    try:
        return args.handler(args)
    except (OSError, ValueError) as exc:  # missing / unreadable / unwritable files, bad values
        print(f"twistslam {args.command}: error: {exc}", file=sys.stderr)
        return 2
    finally:
        warnings.formatwarning = previous_format


if __name__ == "__main__":
    sys.exit(main())
