"""Small helpers shared by the text readers: line iteration and uniform error messages.

Every reader reports malformed input as ``ValueError("<file>:<line>: <what>")`` so a user can
jump straight to the offending line; these helpers keep that format in one place.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np

PathLike = str | os.PathLike


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


def to_floats(tokens: list[str], path: PathLike, line_no: int, what: str = "value") -> np.ndarray:
    """Parse tokens as float64, naming file, line and the bad token on failure."""
    try:
        return np.array([float(t) for t in tokens], dtype=np.float64)
    except ValueError:
        bad = next(t for t in tokens if not _is_float(t))
        raise parse_error(path, line_no, f"{what}: cannot parse {bad!r} as a number") from None


def to_int(token: str, path: PathLike, line_no: int, what: str) -> int:
    """Parse an integer column (also accepts ``"3.0"``, as some writers emit floats)."""
    try:
        value = float(token)
    except ValueError:
        raise parse_error(path, line_no, f"{what}: cannot parse {token!r} as an integer") from None
    if value != int(value):
        raise parse_error(path, line_no, f"{what}: expected an integer, got {token!r}")
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
