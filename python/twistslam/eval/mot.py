"""Multi-object tracking metrics of one mode under one protocol, per sequence and pooled.

:func:`evaluate_mot` is the entry point for benchmarks: a results directory against KITTI
tracking labels over a list of sequences, every number of 3D MOT papers (CLEAR MOT under
the ``kitti`` or ``clear`` protocol, sAMOTA / AMOTA / AMOTP, HOTA / DetA / AssA), per
sequence and over all of them, optionally at a score threshold.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass
from pathlib import Path

from .amota import ScoreSweep, score_sweep
from .clear_mot import MotMetrics, pool_mot
from .difficulty import Difficulty, get_difficulty
from .hota import HotaResult, hota, hota_frames, pool_hota
from .matching import MODES, SequenceOverlaps, iou_function, sequence_overlaps
from .metrics import json_value
from .protocol import Protocol, get_protocol
from .results import load_results, seq_name


def with_scores(counts: MotMetrics, sweep: ScoreSweep | None, hota_result: HotaResult | None
                ) -> MotMetrics:
    """``counts`` with the sweep's sAMOTA / AMOTA / AMOTP and HOTA / DetA / AssA filled in."""
    extra = {}
    if sweep is not None:
        extra |= {"samota": sweep.samota, "amota": sweep.amota, "amotp": sweep.amotp}
    if hota_result is not None:
        extra |= {"hota": hota_result.hota, "deta": hota_result.deta, "assa": hota_result.assa}
    return dataclasses.replace(counts, **extra)


def keep_by_score(overlaps: SequenceOverlaps, min_score: float | None):
    """Tracker rows whose track's mean score is at least ``min_score`` (None: all)."""
    return None if min_score is None else overlaps.est_track_score >= min_score


def sequence_mot(
    overlaps: SequenceOverlaps, protocol: str | Protocol, *, min_score: float | None = None,
    score_metrics: bool = True,
) -> tuple[MotMetrics, HotaResult]:
    """Every MOT metric of one sequence in one mode.

    CLEAR MOT and HOTA are computed on the tracks whose mean score is at least
    ``min_score`` (all tracks when None); sAMOTA / AMOTA / AMOTP sweep their own thresholds
    over all tracks (skipped, left NaN, when ``score_metrics`` is False).

    Returns
    -------
    (metrics, hota_result) : the HOTA counts are returned for pooling (:func:`pool_hota`).
    """
    protocol = get_protocol(protocol)
    m = overlaps.match(keep_by_score(overlaps, min_score))
    hota_result = hota(hota_frames(m))
    sweep = score_sweep(overlaps, protocol) if score_metrics else None
    return with_scores(protocol.count(m), sweep, hota_result), hota_result


@dataclass
class MotEvaluation:
    """Result of :func:`evaluate_mot`: per-sequence and overall :class:`MotMetrics`."""

    protocol: str
    mode: str
    iou_threshold: float
    difficulty: str
    cls: str
    min_score: float | None
    sequences: dict[str, MotMetrics]
    overall: MotMetrics

    def to_dict(self) -> dict:
        """JSON-ready: the settings, then ``sequences`` and ``overall`` (``MotMetrics``
        entries as in ``metrics.json``)."""
        entry = lambda m: {k: json_value(v) for k, v in m.to_dict().items()}  # noqa: E731
        return {
            "protocol": self.protocol, "mode": self.mode, "iou_threshold": self.iou_threshold,
            "difficulty": self.difficulty, "class": self.cls, "min_score": self.min_score,
            "sequences": {seq: entry(m) for seq, m in self.sequences.items()},
            "overall": entry(self.overall),
        }


def evaluate_mot(
    root: str | Path,
    results: str | Path,
    seqs: list[int | str],
    *,
    protocol: str | Protocol = "kitti",
    min_score: float | None = None,
    iou_threshold: float = 0.25,
    mode: str = "3d",
    difficulty: str | Difficulty | None = None,
    cls: str = "car",
    split: str = "training",
) -> MotEvaluation:
    """MOT metrics of ``results/tracking/SEQ.txt`` against KITTI tracking labels.

    Parameters
    ----------
    root : KITTI tracking root (``root/<split>/label_02``, ``calib``).
    results : directory holding ``tracking/SEQ.txt`` (KITTI tracking format with scores).
    seqs : sequences, e.g. ``["0001", "0006"]``.
    protocol : ``"kitti"`` (the devkit as 3D MOT papers run it) or ``"clear"``.
    min_score : evaluate CLEAR MOT and HOTA on the tracks whose mean score is at least this
        (AB3DMOT's thresholding); None keeps every track. sAMOTA, AMOTA and AMOTP always
        sweep all tracks.
    iou_threshold : minimum IoU of a match; mode : ``"3d"``, ``"bv"`` or ``"2d"``.
    difficulty : defaults to the protocol's (``kitti``: hard, ``clear``: easy).
    cls : evaluated class.

    Returns
    -------
    MotEvaluation
        ``sequences[seq]`` per sequence; ``overall`` with the counts summed over the
        sequences, the score sweep over all of them together and HOTA pooled as TrackEval
        pools sequences.
    """
    from .sequence import fill_missing_box_2d, ground_truth, open_dataset

    protocol = get_protocol(protocol)
    if not seqs:
        raise ValueError("evaluate_mot: no sequences given")
    if mode not in MODES:
        raise ValueError(f"unknown overlap mode {mode!r}; choose one of {MODES}")
    level = get_difficulty(difficulty or protocol.default_difficulty)
    per_seq, overlaps, hotas = {}, [], []
    for seq in seqs:
        name = seq_name(seq)
        dataset = open_dataset(root, name, split)
        tracking = load_results(results, name).tracking
        if tracking is None:
            raise FileNotFoundError(f"{Path(results) / 'tracking' / f'{name}.txt'} not found")
        gt = ground_truth(dataset, name)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # image size lookups of a labels-only root
            est = fill_missing_box_2d(tracking, dataset)
        o = sequence_overlaps(
            gt, est, iou_function(mode), cls=cls, difficulty=level, threshold=iou_threshold,
            mode=mode, gt_min_height=protocol.gt_min_height,
        )
        per_seq[name], h = sequence_mot(o, protocol, min_score=min_score)
        overlaps.append(o)
        hotas.append(h)
    overall = with_scores(
        pool_mot(list(per_seq.values())), score_sweep(overlaps, protocol), pool_hota(hotas)
    )
    return MotEvaluation(protocol.name, mode, iou_threshold, level.name, cls.lower(),
                         min_score, per_seq, overall)
