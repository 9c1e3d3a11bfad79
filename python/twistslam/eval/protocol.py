"""Evaluation protocols: which rules turn a matching into CLEAR MOT numbers.

Two protocols share the matching and ignore rules of :mod:`.matching` and differ where the
KITTI tracking devkit's bookkeeping departs from the CLEAR MOT definitions:

``clear`` (default; the paper's object tables, "paper easy")
    CLEAR MOT by the definitions, as motmetrics computes them (:mod:`.clear_mot`); ground
    truth under the difficulty's minimum height is ignored (the KITTI object benchmark's
    easy / moderate / hard). Default difficulty: ``easy``.
``kitti``
    The KITTI tracking devkit exactly as 3D MOT papers run it (AB3DMOT's
    ``scripts/KITTI/evaluate.py``, :mod:`.devkit`): ground truth is never ignored for its
    height, ID switches only between consecutive matched frames, the devkit's
    fragmentations, MOTP over every match. Default difficulty: ``hard`` (occlusion <= 2,
    truncation level 0, tracker boxes of 25 px or less ignored), the devkit's settings.

Every number the evaluator reports names the protocol that produced it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .clear_mot import MotMetrics, clear_mot
from .devkit import devkit_mot
from .matching import Matching


@dataclass(frozen=True)
class Protocol:
    """Rules of one protocol.

    Attributes
    ----------
    name : ``"clear"`` or ``"kitti"``, what reports and ``metrics.json`` print.
    description : one line for report titles.
    default_difficulty : difficulty level used when the caller gives none.
    gt_min_height : ground truth under the minimum height is ignored.
    motp_includes_ignored : MOTP (and sAMOTA's recall axis) takes every match, matches to
        ignored ground truth included, as the devkit's ``tp`` does.
    count : CLEAR MOT of a matching under these rules.
    """

    name: str
    description: str
    default_difficulty: str
    gt_min_height: bool
    motp_includes_ignored: bool
    count: Callable[[Matching], MotMetrics]

    def matched_for_precision(self, m: Matching) -> np.ndarray:
        """(N,) bool: the matches MOTP averages, whose track scores sample the recall axis
        of sAMOTA and whose number (plus FN) is its recall's denominator: counted true
        positives (``clear``) or every match, ignored ground truth included (``kitti``,
        as the devkit's ``tp``)."""
        matched = m.gt_match >= 0
        return matched if self.motp_includes_ignored else matched & ~m.gt_ignored


PROTOCOLS: dict[str, Protocol] = {
    "clear": Protocol(
        "clear", "CLEAR MOT definitions (motmetrics), ground truth under the minimum height "
        "ignored", "easy", gt_min_height=True, motp_includes_ignored=False, count=clear_mot,
    ),
    "kitti": Protocol(
        "kitti", "KITTI tracking devkit as AB3DMOT's evaluate.py runs it", "hard",
        gt_min_height=False, motp_includes_ignored=True, count=devkit_mot,
    ),
}


def get_protocol(name_or_protocol: str | Protocol) -> Protocol:
    """The :class:`Protocol` called ``name`` (``"clear"`` or ``"kitti"``)."""
    if isinstance(name_or_protocol, Protocol):
        return name_or_protocol
    try:
        return PROTOCOLS[name_or_protocol.lower()]
    except KeyError:
        raise ValueError(
            f"unknown protocol {name_or_protocol!r}; choose one of {sorted(PROTOCOLS)}"
        ) from None
