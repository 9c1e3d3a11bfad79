"""``twistslam sim OUT ...``: the simulator's command line, for the main CLI to register.

    from twistslam.sim.cli import add_sim_parser, run_sim
    add_sim_parser(subparsers)        # registers "sim" with handler run_sim
"""

from __future__ import annotations

import argparse

from .config import MAX_FRAMES, MAX_IMAGE_SIDE
from .scenario import SCENARIOS


def _positive(text: str) -> int:
    value = int(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text}")
    return value


def _image_side(text: str) -> int:
    value = _positive(text)
    if value > MAX_IMAGE_SIDE:
        raise argparse.ArgumentTypeError(f"must be at most {MAX_IMAGE_SIDE} px, got {text}")
    return value


def _frames(text: str) -> int:
    value = _positive(text)
    if value > MAX_FRAMES:
        raise argparse.ArgumentTypeError(f"must be at most {MAX_FRAMES}, got {text}")
    return value


def _scenario(text: str) -> str:
    if text not in SCENARIOS:
        raise argparse.ArgumentTypeError(f"unknown scenario {text!r}; valid scenarios: {', '.join(SCENARIOS)}")
    return text


def _setting(text: str) -> tuple[str, str]:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected SECTION.FIELD=VALUE, got {text!r}")
    key, value = text.split("=", 1)
    return key.strip(), value.strip()


def add_sim_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``sim`` on ``subparsers``; the parsed args carry ``handler=run_sim``."""
    scenarios = "; ".join(f"{k}: {v[0]}" for k, v in SCENARIOS.items())
    p = subparsers.add_parser(
        "sim", help="generate a synthetic KITTI-tracking-format sequence with exact ground truth",
        description=f"Render a synthetic driving sequence into OUT/training (KITTI tracking layout). "
                    f"Scenarios: {scenarios}.",
    )
    p.add_argument("out", help="output root (must be empty unless --overwrite)")
    p.add_argument("--scenario", type=_scenario, default="urban",
                   help="urban | highway | intersection | static | crowded")
    p.add_argument("--frames", type=_frames, default=100,
                   help=f"number of frames (10 Hz, at most {MAX_FRAMES})")
    p.add_argument("--seed", type=int, default=0, help="random seed (same seed -> identical files)")
    p.add_argument("--seq", default="0000", help="sequence number, e.g. 0000")
    p.add_argument("--calib", default=None, help="KITTI calibration file (default: tracking 0000)")
    p.add_argument("--width", type=_image_side, default=None,
                   help=f"image width, px (default 1242, at most {MAX_IMAGE_SIDE})")
    p.add_argument("--height", type=_image_side, default=None,
                   help=f"image height, px (default 375, at most {MAX_IMAGE_SIDE})")
    p.add_argument("--overwrite", action="store_true", help="replace this sequence in a non-empty OUT")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--set", dest="settings", type=_setting, action="append", default=[], metavar="SECTION.FIELD=VALUE",
                   help="override a SimConfig setting, e.g. --set lidar.range_noise=0.05 (repeatable)")
    p.set_defaults(handler=run_sim)
    return p


def _value(text: str):
    if "," in text:
        return [v.strip() for v in text.split(",")]
    return text


def run_sim(args: argparse.Namespace) -> int:
    """Handler of ``twistslam sim``; returns the exit code. User errors (unknown scenario or
    setting, non-empty OUT without --overwrite, bad calibration) raise ValueError or
    FileNotFoundError for the main CLI to print as one line."""
    from ..input_checks import check_output_dir
    from .generate import generate

    check_output_dir(args.out, "OUT")  # a file or a read-only folder: said before rendering
    overrides = {key: _value(value) for key, value in args.settings}
    try:
        out = generate(args.out, scenario=args.scenario, frames=args.frames, seed=args.seed, seq=args.seq,
                       calib_path=args.calib, overwrite=args.overwrite, width=args.width, height=args.height,
                       progress=not args.no_progress, **overrides)
    except FileExistsError as exc:  # the main CLI reports ValueError / FileNotFoundError as usage errors
        raise ValueError(str(exc)) from exc
    print(f"wrote {out}/training (sequence {args.seq}, {args.frames} frames, scenario {args.scenario})")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Stand-alone entry point: ``python -m twistslam.sim.cli OUT ...``."""
    import sys

    parser = argparse.ArgumentParser(prog="twistslam")
    add_sim_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["sim", *(sys.argv[1:] if argv is None else argv)])
    try:
        return args.handler(args)
    except (OSError, ValueError) as exc:
        print(f"twistslam sim: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
