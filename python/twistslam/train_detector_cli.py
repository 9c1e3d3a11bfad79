"""``twistslam train-detector``: train 3DSSD on KITTI-layout tracking sequences and write its
checkpoint (the file ``--detector 3dssd --weights FILE`` reads).

    twistslam train-detector ROOT [ROOT ...] --seqs 0000 [0001 ...] --out 3dssd.pt [--epochs N] [--tiny]

Optionally evaluates the result (car bird's-eye-view AP, KITTI rules) on held-out sequences:
``--val-root ROOT --val-seqs 0000``.
"""

from __future__ import annotations

import argparse
import json
import logging


def _positive(text: str) -> int:
    value = int(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text}")
    return value


def add_train_detector(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``train-detector`` on ``sub``; the parsed args carry ``handler=run_train_detector``."""
    p = sub.add_parser(
        "train-detector", help="train the 3DSSD LiDAR detector on KITTI-layout sequences",
        description="Train 3DSSD (plain torch, CPU) on the labelled frames of KITTI tracking-layout "
                    "sequences (real KITTI or `twistslam sim` output) and write a checkpoint for "
                    "`--detector 3dssd --weights FILE`.")
    p.add_argument("roots", nargs="+", metavar="ROOT", help="dataset root(s) holding training/velodyne, label_02, calib")
    p.add_argument("--seqs", nargs="+", required=True, help="sequence numbers under every root, e.g. 0000")
    p.add_argument("--out", required=True, metavar="FILE", help="checkpoint to write (rewritten after every epoch)")
    p.add_argument("--epochs", type=_positive, default=40, help="passes over the training frames (default 40)")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--tiny", action="store_const", dest="preset", const="tiny",
                      help="a few-thousand-parameter model (tests, smoke runs)")
    size.add_argument("--size", dest="preset", choices=["tiny", "small", "full"],
                      help="network size: small (default, CPU-sized) or full (the paper's)")
    p.add_argument("--batch-size", type=_positive, default=2, help="frames per step (default 2)")
    p.add_argument("--max-frames", type=_positive, default=None, help="use at most this many frames per sequence")
    p.add_argument("--threads", type=_positive, default=None, help="torch CPU threads (default: torch's)")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    p.add_argument("--val-root", metavar="ROOT", help="evaluate the result on this root's --val-seqs")
    p.add_argument("--val-seqs", nargs="+", default=[], help="held-out sequences under --val-root")
    p.add_argument("--json", metavar="FILE", help="write the validation figures as JSON")
    p.set_defaults(handler=run_train_detector, preset="small")
    return p


def run_train_detector(args: argparse.Namespace) -> int:
    """Handler of ``train-detector``: returns the exit code."""
    from .perception.train_3dssd import train

    if args.val_root and not args.val_seqs:
        raise ValueError("--val-root needs --val-seqs")
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    out = train(args.roots, args.seqs, args.out, epochs=args.epochs, preset=args.preset,
                batch_size=args.batch_size, seed=args.seed, max_frames=args.max_frames, threads=args.threads)
    print(f"wrote {out}")
    if args.val_root:
        from .perception.torch_models.ssd3d_evaluation import evaluate_checkpoint

        result = evaluate_checkpoint(out, args.val_root, args.val_seqs)
        print(result.table())
        if args.json:
            with open(args.json, "w") as f:
                json.dump(result.to_dict(), f, indent=1)
    return 0
