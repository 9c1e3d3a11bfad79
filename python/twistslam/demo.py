"""``make demo``: the main job end to end on a synthetic sequence with exact ground truth.

1. Generate the simulator's default ``urban`` sequence (100 frames, seed 0) once into a cache
   (``.cache/sim/urban-seed0-n100``; reused when complete and made by the same simulator --
   same configuration, same code -- so later demos start at once and a changed simulator
   regenerates it).
2. Run stereo SLAM on it (:func:`twistslam.run`).
3. Evaluate the camera trajectory against the exact ground truth and print the summary table.

Writes ``OUT/results/`` (camera_poses.txt, timings.json, config.yaml, status.txt),
``OUT/metrics.json``, ``OUT/report.md`` and ``OUT/plots/*.png``.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import os
import shutil
import sys
from pathlib import Path

from .config import Config
from .pipeline import run
from .result import Result

SCENARIO, FRAMES, SEED, SEQ = "urban", 100, 0, "0000"
#: written last into a cached sequence: its presence means the sequence is complete
MARKER = "demo_sequence.json"
#: Cityscapes ids of movable things (person, rider, car, truck, bus, caravan, trailer, train,
#: motorcycle, bicycle): the paper tracks the camera on a-priori static clusters only (eq. 3);
#: the simulator's panoptic images stand in for the segmentation network
MOVABLE_CLASSES = [24, 25, 26, 27, 28, 29, 30, 31, 32, 33]


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:16]


def sim_code_version(folder: Path | None = None) -> str:
    """Short hash of the simulator's source files (``twistslam/sim/*.py``, names and
    contents): any edit of the simulator's code changes it."""
    folder = Path(folder) if folder is not None else Path(__file__).resolve().parent / "sim"
    h = hashlib.sha256()
    for path in sorted(folder.glob("*.py")):
        h.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:16]


def sim_config_digest(scenario: str, frames: int, seed: int, seq: str) -> str:
    """Short hash of the full :class:`~twistslam.sim.SimConfig` that ``generate`` builds for
    these arguments (the scenario's settings and every default)."""
    from .sim import scenario_config

    cfg = scenario_config(scenario)
    cfg.frames, cfg.seed, cfg.seq = int(frames), int(seed), seq
    text = json.dumps(dataclasses.asdict(cfg), sort_keys=True, default=list)
    return _digest(text.encode())


def sequence_key(scenario: str = SCENARIO, frames: int = FRAMES, seed: int = SEED,
                 seq: str = SEQ) -> dict:
    """What a cached sequence must have been made with to be reused: the arguments, the
    simulator's configuration and its code version (written into the sequence's marker)."""
    return {"scenario": scenario, "frames": frames, "seed": seed, "seq": seq,
            "sim_config": sim_config_digest(scenario, frames, seed, seq),
            "sim_code": sim_code_version()}


def _process_alive(pid: str) -> bool:
    """Whether the process of a partial folder's suffix still runs (no suffix: no)."""
    if not pid.isdigit():
        return False
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def cached_sequence(cache: Path, scenario: str = SCENARIO, frames: int = FRAMES,
                    seed: int = SEED, seq: str = SEQ, progress: bool = True) -> Path:
    """Root of the simulated sequence, generated on first use.

    The sequence is reused only when its marker holds the same :func:`sequence_key`: a
    change of the simulator's configuration or code regenerates it. It is written to a
    ``.partial`` folder and renamed when complete, so an interrupted generation is never
    mistaken for a finished one.
    """
    from .sim import generate  # the simulator only when a sequence must be made

    key = sequence_key(scenario, frames, seed, seq)
    root = cache / f"{scenario}-seed{seed}-n{frames}"
    marker = root / MARKER
    stale = False
    if marker.is_file():
        if json.loads(marker.read_text(encoding="utf-8")) == key:
            print(f"demo: using the cached sequence {root}")
            return root
        stale = True
    # one partial folder per process: two runs that regenerate at once must not share one;
    # those left by interrupted generations (their process is gone) are removed
    for old in cache.glob(f"{root.name}.partial*"):
        if not _process_alive(old.name.rpartition("-")[2]):
            shutil.rmtree(old, ignore_errors=True)
    partial = root.with_name(f"{root.name}.partial-{os.getpid()}")
    why = " (the cached one was made by another simulator configuration or code)" if stale else " (once)"
    print(f"demo: generating the {scenario} sequence ({frames} frames, seed {seed}) "
          f"into {root}{why}")
    generate(partial, scenario=scenario, frames=frames, seed=seed, seq=seq, progress=progress)
    (partial / MARKER).write_text(json.dumps(key) + "\n", encoding="utf-8")
    if marker.is_file() and json.loads(marker.read_text(encoding="utf-8")) == key:
        shutil.rmtree(partial, ignore_errors=True)  # another process finished first
        return root
    if root.is_symlink():  # a link the user put there: replaced, what it points to left alone
        root.unlink()
    else:
        shutil.rmtree(root, ignore_errors=True)
    partial.rename(root)
    return root


def demo_config() -> Config:
    """Defaults, with the simulator's panoptic labels masking movable objects."""
    return Config().override({"tracking.dynamic_class_ids": MOVABLE_CLASSES})


def _run_markdown(result: Result) -> str:
    t = result.timings.summary()
    lines = [
        "", "### Run", "",
        f"{len(result)} frames, {result.num_lost} lost, {int(result.is_keyframe.sum())} "
        f"keyframes; {t['hz']:.1f} Hz, per frame median {t['per_frame_ms']['median']:.1f} ms, "
        f"p90 {t['per_frame_ms']['p90']:.1f} ms, max {t['per_frame_ms']['max']:.1f} ms.", "",
        "| stage | median ms |", "|---|---:|",
        *(f"| {name} | {ms:.2f} |" for name, ms in t["stages"].items() if ms is not None), "",
        *(f"After the last frame: {name} {ms:.0f} ms." for name, ms in t["after_loop_ms"].items()),
    ]
    return "\n".join(lines)


def _object_summary(root: Path, result) -> dict:
    """The object clusters the run tracked, against the simulator's object poses (issue 10's
    metrics: moving cars seen 20+ frames within 50 m, object frame offset aligned)."""
    from .eval.object_tracks import evaluate_object_tracks, load_ground_truth

    evaluation = evaluate_object_tracks(result.objects.reported(), result.camera_poses, load_ground_truth(root, SEQ))
    print(f"\nObject clusters ({len(result.objects)} tracked; segmentation {result.segmentation}, "
          f"flow {result.flow}, 3D detections {result.detector}):")
    print(evaluation.format_table())
    return evaluation.summary()


def run_demo(out: Path, *, cache: Path = Path(".cache/sim"), frames: int = FRAMES,
             progress: bool = True) -> dict:
    """Generate (once), run, evaluate; returns the ``metrics.json`` dictionary."""
    from .eval.plots import plot_trajectories
    from .eval.report import render_markdown, render_text
    from .eval.sequence import evaluate_sequence

    out, cache = Path(out), Path(cache)
    root = cached_sequence(cache, frames=frames, progress=progress)
    result = run((root, SEQ), demo_config(), progress=progress)
    result.save(out / "results")

    metrics = evaluate_sequence(root, out / "results", SEQ)
    summary = metrics.to_dict()
    summary["run"] = {"frames": len(result), "lost": result.num_lost,
                      "keyframes": int(result.is_keyframe.sum()),
                      "timings": result.timings.summary()}
    print(render_text(metrics), end="")
    t = summary["run"]["timings"]
    print(f"{len(result)} frames, {result.num_lost} lost, {t['hz']:.1f} Hz "
          f"(median {t['per_frame_ms']['median']:.1f} ms/frame)")
    if result.objects is not None:
        summary["objects"] = _object_summary(root, result)
    (out / "metrics.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    (out / "report.md").write_text(render_markdown(metrics) + _run_markdown(result),
                                   encoding="utf-8")
    plots = plot_trajectories(metrics, out / "plots")
    print(f"wrote {out / 'metrics.json'}, {out / 'report.md'}, {len(plots)} plot(s) in "
          f"{out / 'plots'}, results in {out / 'results'}")
    return summary


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m twistslam.demo",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="demo_out", help="output directory")
    parser.add_argument("--cache", default=".cache/sim", help="where simulated sequences are kept")
    parser.add_argument("--frames", type=int, default=FRAMES, help="frames of the sequence")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    try:
        run_demo(out, cache=Path(args.cache), frames=args.frames, progress=not args.no_progress)
    except (FileNotFoundError, ValueError) as exc:
        print(f"demo: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
