"""Small helpers shared by the text readers: line iteration and uniform error messages.

Every reader reports malformed input as ``ValueError("<file>:<line>: <what>")`` so a user can
jump straight to the offending line; these helpers keep that format in one place.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np

PathLike = str | os.PathLike

INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1
#: largest frame number a reader accepts. KITTI's longest drive has about 5,200 frames
#: (raw 2011_09_30_drive_0028); 1e5 leaves 20x room while an array indexed by frame number
#: (poses, 128 bytes a frame) stays at 13 MB instead of an allocation a typo could blow up.
MAX_FRAME = 100_000


def parse_error(path: PathLike, line_no: int | None, message: str) -> ValueError:
    """A ``ValueError`` whose message starts with ``file:line:`` (or ``file:`` alone)."""
    where = f"{path}:{line_no}" if line_no is not None else f"{path}"
    return ValueError(f"{where}: {message}")


def iter_lines(path: PathLike, sep: str | None = None) -> Iterator[tuple[int, list[str]]]:
    """Yield ``(line_number, tokens)`` for every non-blank line; line numbers start at 1.

    ``sep=None`` splits on any whitespace; ``sep=","`` splits on commas and strips each token.
    """
    with open(path, encoding="utf-8") as f:
        for line_no, line in enumerate(f, start=1):
            text = line.strip()
            if not text:
                continue  # trailing newlines and blank separators are common in KITTI files
            if sep is None:
                yield line_no, text.split()
            else:
                yield line_no, [t.strip() for t in text.split(sep)]


def to_floats(tokens: list[str], path: PathLike, line_no: int, what: str = "value",
              finite: bool = True) -> np.ndarray:
    """Parse tokens as float64, naming file, line and the bad token on failure.

    ``finite`` (default): ``nan``, ``inf`` and numbers beyond float64 (``1e400``) are errors
    too -- Python parses them without complaint, and one of them in a box or a matrix only
    shows up much later as "SVD did not converge" or as every LiDAR point turned NaN.
    """
    try:
        values = np.array([float(t) for t in tokens], dtype=np.float64)
    except ValueError:
        bad = next(t for t in tokens if not _is_float(t))
        raise parse_error(path, line_no, f"{what}: cannot parse {bad!r} as a number") from None
    if finite and not np.isfinite(values).all():
        bad = tokens[int(np.flatnonzero(~np.isfinite(values))[0])]
        raise parse_error(path, line_no, f"{what}: {bad!r} is not finite (NaN or Inf)")
    return values


def to_int(token: str, path: PathLike, line_no: int, what: str,
           lo: int = INT32_MIN, hi: int = INT32_MAX) -> int:
    """Parse an integer column (also accepts ``"3.0"``, as some writers emit floats) that must
    lie in ``[lo, hi]`` (default: the int32 range the C++ core stores ids in)."""
    try:
        value = float(token)
    except ValueError:
        raise parse_error(path, line_no, f"{what}: cannot parse {token!r} as an integer") from None
    if not math.isfinite(value) or value != int(value):
        raise parse_error(path, line_no, f"{what}: expected an integer, got {token!r}")
    if not lo <= value <= hi:
        raise parse_error(path, line_no, f"{what}: {token} is outside [{lo}, {hi}]")
    return int(value)


def _is_float(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def ensure_parent(path: PathLike) -> Path:
    """Create the parent directory of a file about to be written; return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def format_float(value: float) -> str:
    """Shortest scientific notation that reads back to the same float64 (``7.215377e+02``).

    Writers use it where a round trip must be exact (calibration, poses, oxts): synthetic
    sequences are judged against their ground truth to 1e-6 m and better.
    """
    return np.format_float_scientific(float(value), unique=True, trim="0", exp_digits=2)
