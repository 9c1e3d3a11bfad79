"""Per-frame timings of a run and their ``timings.json`` summary."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Timings:
    """Wall-clock milliseconds per frame.

    Attributes
    ----------
    frame_ms : (N,) wall time of the loop per frame, from the end of frame i-1 to the end
        of frame i: waiting for frame i to be read (read ahead while frame i-1 was tracked)
        plus the core's ``track`` call.
    stages : name -> (N,) ms. ``load`` (reading images and labels, in a background thread),
        ``track`` (the whole core call) and the core's own stages (``features``, ``stereo``, ``track_motion``,
        ``track_local_map``, ``keyframe``, ``local_ba``); NaN where a stage did not run
        on that frame (local BA runs on keyframes only; with ``local_ba.asynchronous`` it is
        solved beside the next frame's front end and reported by that frame, with
        ``local_ba_wait``, the time tracking waited for it).
    after_loop_ms : name -> ms of the steps run once after the last frame, outside the
        per-frame loop and its ``hz`` (``object_smoothing``: the final smoothing of the object
        tracks, ``visual_objects.final_smoothing``; ``object_verdicts`` without it: the
        end-of-run LiDAR verdicts on the object rows alone).
    """

    frame_ms: np.ndarray = field(default_factory=lambda: np.zeros(0))
    stages: dict[str, np.ndarray] = field(default_factory=dict)
    after_loop_ms: dict[str, float] = field(default_factory=dict)

    @classmethod
    def from_frames(cls, per_frame: list[dict[str, float]], frame_ms: list[float]) -> "Timings":
        """From one ``{stage: ms}`` dict and one wall time per frame."""
        if len(per_frame) != len(frame_ms):
            raise ValueError(f"{len(per_frame)} stage records for {len(frame_ms)} frame times")
        names = list(dict.fromkeys(name for stages in per_frame for name in stages))
        stages = {name: np.array([s.get(name, np.nan) for s in per_frame], dtype=np.float64)
                  for name in names}
        return cls(frame_ms=np.asarray(frame_ms, dtype=np.float64), stages=stages)

    @property
    def hz(self) -> float:
        """Frames per second of the whole loop (waiting for frames included)."""
        total = float(self.frame_ms.sum())
        return len(self.frame_ms) / (total / 1e3) if total > 0 else float("nan")

    def summary(self) -> dict:
        """The ``timings.json`` layout: ``{"frames", "hz", "per_frame_ms": {"median", "p90",
        "max"}, "stages": {name: median ms over the frames where it ran}, "after_loop_ms":
        {name: ms}}``."""
        def stat(fn, values):
            return round(float(fn(values)), 3) if len(values) else None

        ms = self.frame_ms
        stages = {}
        for name, values in self.stages.items():
            ran = values[np.isfinite(values)]
            stages[name] = stat(np.median, ran)
        return {
            "frames": int(len(ms)),
            "hz": round(self.hz, 3) if len(ms) else None,
            "per_frame_ms": {
                "median": stat(np.median, ms),
                "p90": stat(lambda v: np.percentile(v, 90), ms),
                "max": stat(np.max, ms),
            },
            "stages": stages,
            "after_loop_ms": {name: round(float(ms), 3) for name, ms in self.after_loop_ms.items()},
        }
