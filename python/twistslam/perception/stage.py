"""The protocol every perception stage follows, and the per-frame timer of a stage.

A stage is any callable from a :class:`~twistslam.datasets.Frame` to documented numpy arrays,
so a user's own function or torch module plugs in where a built-in source would. A flow
stage also receives the previous frame: ``flow(previous, current) -> (H, W, 2) float32``
(u, v) in pixels, such that the pixel (x, y) of ``previous`` moves to (x + u, y + v) in
``current``. NaN marks a pixel without a flow value (files only cover valid pixels).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from twistslam.datasets import Frame


@runtime_checkable
class FlowStage(Protocol):
    """Optical flow from the left image of ``previous`` to the one of ``current``.

    A source whose class sets ``accepts_instances = True`` is also given
    ``instances=(previous_ids, current_ids)``, both frames' instance images (either may be
    ``None``), by a run: DIS uses them to compute only around the objects.

    Returns
    -------
    (H, W, 2) float32 array of (u, v) in pixels, NaN where the source has no value.
    """

    def __call__(self, previous: Frame, current: Frame) -> np.ndarray: ...


def check_flow(flow: np.ndarray, shape: tuple[int, int], source: str) -> np.ndarray:
    """``flow`` as (H, W, 2) float32 of the image ``shape``; ValueError naming ``source`` if
    a stage (a user's function, say) returned something else."""
    flow = np.asarray(flow)
    if flow.shape != (*shape, 2):
        raise ValueError(f"{source}: flow must be {(*shape, 2)} (H, W, 2), got {flow.shape}")
    if flow.dtype.kind != "f":
        raise ValueError(f"{source}: flow must be floating point (u, v) pixels, got {flow.dtype}")
    return flow.astype(np.float32, copy=False)


@dataclass
class TimedStage:
    """Wraps a stage and records its wall time per call in milliseconds, so a run reports
    each perception stage's time apart from the core's.

    Attributes
    ----------
    stage : the wrapped callable.
    name : the stage's name in timings (``flow``, ``segmentation``).
    ms : one entry per call, in call order.
    """

    stage: Callable[..., np.ndarray]
    name: str
    ms: list[float] = field(default_factory=list)

    def __call__(self, *frames: Frame) -> np.ndarray:
        start = time.perf_counter()
        out = self.stage(*frames)
        self.ms.append((time.perf_counter() - start) * 1e3)
        return out

    def last_ms(self) -> dict[str, float]:
        """``{name: ms}`` of the latest call, the shape of a frame's stage record in
        :class:`twistslam.timings.Timings`; empty before the first call."""
        return {self.name: self.ms[-1]} if self.ms else {}
