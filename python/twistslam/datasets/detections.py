"""Precomputed 3D detections in the PointRCNN / AB3DMOT text format.

One detection per line, comma separated:
``frame, type, x1, y1, x2, y2, score, h, w, l, x, y, z, rotation_y, alpha`` with
type 1 = Pedestrian, 2 = Car, 3 = Cyclist, and the KITTI label conventions for the box
(bottom centre ``x y z`` in the rectified camera frame; stored here as geometric centre).
Scores are the detector's raw confidences (not probabilities; PointRCNN's exceed 1).
"""

from __future__ import annotations

import numpy as np

from ._parsing import INT32_MIN, MAX_FRAME, PathLike, iter_lines, parse_error, to_floats, to_int
from .labels import read_labels
from .objects import ObjectTable

#: integer class codes of the AB3DMOT detection files
DETECTION_CLASSES: dict[int, str] = {1: "Pedestrian", 2: "Car", 3: "Cyclist"}
N_COLUMNS = 15


def read_detections(path: PathLike) -> ObjectTable:
    """Read a comma-separated detection file into an :class:`ObjectTable`.

    ``track_id`` is -1 (detections are not tracked); truncation and occlusion are unknown
    (-1). Rows keep the file order.

    Raises
    ------
    ValueError
        ``"<file>:<line>: expected 15 columns, got n"``, an unknown class code or a bad number.
    """
    frame, cls, numbers = [], [], []
    for line_no, tokens in iter_lines(path, sep=","):
        if len(tokens) != N_COLUMNS:
            raise parse_error(path, line_no, f"expected {N_COLUMNS} columns, got {len(tokens)}")
        # below 0: refused by the tracker's loader, which names the sequence's frame range
        frame.append(to_int(tokens[0], path, line_no, "frame", INT32_MIN, MAX_FRAME))
        code = to_int(tokens[1], path, line_no, "type")
        if code not in DETECTION_CLASSES:
            known = ", ".join(f"{k}={v}" for k, v in DETECTION_CLASSES.items())
            raise parse_error(path, line_no, f"type: unknown class code {code} ({known})")
        cls.append(DETECTION_CLASSES[code])
        numbers.append(to_floats(tokens[2:], path, line_no, "detection"))
    if not frame:
        return ObjectTable.empty(source=str(path))
    v = np.stack(numbers)  # x1 y1 x2 y2 score h w l x y z ry alpha
    h, w, length = v[:, 5], v[:, 6], v[:, 7]
    box_3d = np.stack([v[:, 8], v[:, 9] - h / 2.0, v[:, 10], length, w, h, v[:, 11]], axis=1)
    n = len(frame)
    return ObjectTable(
        frame=frame, track_id=np.full(n, -1), cls=cls, truncation=np.full(n, -1.0),
        occlusion=np.full(n, -1), alpha=v[:, 12], box_2d=v[:, 0:4], box_3d=box_3d,
        score=v[:, 4], source=str(path),
    )


def is_pointrcnn_file(path: PathLike) -> bool:
    """Whether the file's first non-blank line has a comma: the PointRCNN comma format above
    (an empty file is not)."""
    with open(path, encoding="utf-8") as f:
        first = next((line for line in f if line.strip()), "")
    return "," in first


def read_detection_file(path: PathLike) -> ObjectTable:
    """One detection file of a whole sequence: the PointRCNN comma format above when its first
    non-blank line has a comma, else KITTI tracking results (space separated, track ids
    ignored by the callers). An empty file gives an empty table."""
    return read_detections(path) if is_pointrcnn_file(path) else read_labels(path)
