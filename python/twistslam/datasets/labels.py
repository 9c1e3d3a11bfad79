"""KITTI tracking labels (``label_02/XXXX.txt``) and tracking result files.

One object per line: ``frame track_id type truncated occluded alpha x1 y1 x2 y2 h w l x y z
rotation_y [score]``. Labels have 17 columns, result files add an 18th, the score. KITTI's
``x y z`` is the *bottom* centre of the box; :class:`ObjectTable` stores the geometric centre
(``cy = y - h / 2``), and the writer converts back.

DontCare regions carry placeholders (``h w l = -1000``, ``x y z = -10 -1 -1``...). Rows whose
height is negative are placeholders, not boxes: their ``y`` is stored unchanged (no half
height shift), so they survive a read -> write -> read round trip exactly.
"""

from __future__ import annotations

import numpy as np

from ._parsing import (
    INT32_MAX, MAX_FRAME, PathLike, ensure_parent, iter_lines, parse_error, to_floats, to_int,
)
from .objects import ObjectTable


def _bottom_to_centre_y(y: np.ndarray, h: np.ndarray) -> np.ndarray:
    return np.where(h >= 0, y - h / 2.0, y)


def _centre_to_bottom_y(cy: np.ndarray, h: np.ndarray) -> np.ndarray:
    return np.where(h >= 0, cy + h / 2.0, cy)


def _format_truncation(value: float) -> str:
    # tracking labels use integer levels 0/1/2 (and -1): keep them integers in the output
    return str(int(value)) if value == int(value) else f"{value:.6f}"


def read_labels(path: PathLike) -> ObjectTable:
    """Read a KITTI tracking label or result file into an :class:`ObjectTable`.

    Rows without a score (ground truth) get score 1. Rows keep the file order.

    Raises
    ------
    ValueError
        ``"<file>:<line>: expected 17 or 18 columns, got n"``, a bad number / integer, a
        NaN / inf value, or a frame outside ``[0, MAX_FRAME]``.
    """
    frame, track, cls, trunc, occ, numbers = [], [], [], [], [], []
    for line_no, tokens in iter_lines(path):
        if len(tokens) not in (17, 18):
            raise parse_error(path, line_no, f"expected 17 or 18 columns, got {len(tokens)}")
        frame.append(to_int(tokens[0], path, line_no, "frame", 0, MAX_FRAME))
        track.append(to_int(tokens[1], path, line_no, "track_id", -1, INT32_MAX))
        cls.append(tokens[2])
        # tracking labels use an integer truncation level, object labels a fraction: keep float
        trunc.append(to_floats(tokens[3:4], path, line_no, "truncated")[0])
        occ.append(to_int(tokens[4], path, line_no, "occluded"))
        values = to_floats(tokens[5:], path, line_no, "box")
        numbers.append(values if len(values) == 13 else np.append(values, 1.0))
    return label_table(frame, track, cls, trunc, occ, numbers, path)


def label_table(frame, track, cls, trunc, occ, numbers: list[np.ndarray],
                path: PathLike) -> ObjectTable:
    """An :class:`ObjectTable` from the parsed label columns; ``numbers`` rows hold
    ``alpha x1 y1 x2 y2 h w l x y z ry score`` with KITTI's bottom-centre ``y`` (shared by the
    tracking and the object label readers)."""
    if not len(numbers):
        return ObjectTable.empty(source=str(path))
    v = np.stack(numbers)
    h, w, length = v[:, 5], v[:, 6], v[:, 7]
    x, y, z, ry = v[:, 8], v[:, 9], v[:, 10], v[:, 11]
    box_3d = np.stack([x, _bottom_to_centre_y(y, h), z, length, w, h, ry], axis=1)
    return ObjectTable(
        frame=frame, track_id=track, cls=cls, truncation=trunc, occlusion=occ, alpha=v[:, 0],
        box_2d=v[:, 1:5], box_3d=box_3d, score=v[:, 12], source=str(path),
    )


#: result files are read exactly like labels (the 18th column is the score)
read_tracking_results = read_labels


def format_label_lines(table: ObjectTable, with_score: bool = True) -> list[str]:
    """KITTI text lines for ``table`` (17 columns, plus the score if ``with_score``)."""
    lines = []
    b = table.box_3d
    y = _centre_to_bottom_y(b[:, 1], b[:, 5])
    for i in range(len(table)):
        cx, _, cz, length, w, h, ry = b[i]
        fields = [
            str(table.frame[i]), str(table.track_id[i]), str(table.cls[i]),
            _format_truncation(table.truncation[i]), str(table.occlusion[i]),
            f"{table.alpha[i]:.6f}",
            *(f"{v:.6f}" for v in table.box_2d[i]),
            *(f"{v:.6f}" for v in (h, w, length, cx, y[i], cz, ry)),
        ]
        if with_score:
            fields.append(f"{table.score[i]:.6f}")
        lines.append(" ".join(fields))
    return lines


def write_tracking_results(path: PathLike, table: ObjectTable) -> None:
    """Write ``table`` in the KITTI tracking result format (17 label columns + score).

    Rows are written in (frame, track_id) order, the order the KITTI devkit expects; numbers
    with 6 decimals, as KITTI's own files (1 µm / 1e-6 rad resolution).
    """
    path = ensure_parent(path)
    with open(path, "w", encoding="utf-8") as f:
        for line in format_label_lines(table.sorted(), with_score=True):
            f.write(line + "\n")


def write_labels(path: PathLike, table: ObjectTable) -> None:
    """Write ``table`` as a ground-truth label file (17 columns, no score), sorted."""
    path = ensure_parent(path)
    with open(path, "w", encoding="utf-8") as f:
        for line in format_label_lines(table.sorted(), with_score=False):
            f.write(line + "\n")
