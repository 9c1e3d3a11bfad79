"""Sanity checks of what a user hands the system, run before any work is done.

A sequence can be readable and still silently wrong: right images that are copies of the
left ones, the two cameras swapped, or images resized without their calibration. The
tracker then reports most frames "ok" with a trajectory metres off (measured: 8 m ATE on
27 frames of real KITTI with the left images as right ones, 10 m with half-size images).
:func:`check_first_frames` looks at the first frames for each of these; the output checks
make a run fail at once, not after an hour of tracking, when its results cannot be written.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

#: principal point farther from the image centre than this fraction of the image size: the
#: images do not have the calibration's size. KITTI's sit at 0.6-2 % (x) and 1-4 % (y) of
#: the size off centre; images at half or double the calibrated size put them 48 % / 25 % off
PRINCIPAL_POINT_OFF_CENTRE = 0.2
#: px at half resolution, largest |disparity| searched: 64 covers depths down to 3 m with
#: KITTI's rig (721 px focal length, 0.54 m baseline)
MAX_HALF_DISPARITY = 64
#: px, half size of the SAD window at half resolution (7 x 7)
PATCH_RADIUS = 3
#: at most this many textured pixels are matched, one per grid cell (~0.1 s on KITTI)
MAX_PROBES = 600
GRID_CELL = 12  # px at half resolution, one probe per cell: probes spread over the image
#: grey levels of |I(x+1) - I(x-1)| a probe needs: flat cells (sky, blank frames) give none
#: (real KITTI 0001 frame 0: a quarter of the cells are below, the median cell has 48)
MIN_GRADIENT = 8.0
#: a probe counts when its best SAD beats the best one at least 2 px away by this factor
UNIQUENESS = 0.8
#: fewer confident probes than this: a blank or textureless frame, no verdict from it
MIN_CONFIDENT = 40
#: fraction of confident probes with negative disparity above which the cameras are
#: swapped (measured on frames 0, 10, 20 of real KITTI 0001 and of the simulator: 0-2 %,
#: 98-100 % with the two images swapped)
MAX_NEGATIVE_FRACTION = 0.5
#: fraction with zero disparity above which the right image is (nearly) the left one
#: (measured: 0 % on the frames above, 100 % for the left image plus +-2 grey levels of
#: noise; a zero disparity at half resolution is a point beyond 400 m on KITTI)
MAX_ZERO_FRACTION = 0.6
#: frames looked at before giving up on a verdict (a sequence may start on a blank frame)
FRAMES_CHECKED = 3


def check_image_size(width: int, height: int, calib, where: str) -> None:
    """Refuse images whose size does not fit the calibration's principal point (cx ~ W/2,
    cy ~ H/2): resized images would track "ok" with every depth wrong."""
    cx, cy = calib.P2[0, 2], calib.P2[1, 2]
    if (abs(cx - width / 2) > PRINCIPAL_POINT_OFF_CENTRE * width
            or abs(cy - height / 2) > PRINCIPAL_POINT_OFF_CENTRE * height):
        source = getattr(calib, "source", "") or "the calibration"
        raise ValueError(
            f"{where}: images of {width}x{height} px do not fit {source}: its principal point "
            f"({cx:.1f}, {cy:.1f}) is far from the image centre ({width / 2:.1f}, "
            f"{height / 2:.1f}); were the images resized, or is the calibration of another "
            "camera?")


def _grey_half(image: np.ndarray) -> np.ndarray:
    """Grey float32 at half resolution (2 x 2 means)."""
    grey = image.astype(np.float32)
    if grey.ndim == 3:
        grey = grey.mean(axis=2)
    h, w = (grey.shape[0] // 2) * 2, (grey.shape[1] // 2) * 2
    g = grey[:h, :w]
    return 0.25 * (g[0::2, 0::2] + g[1::2, 0::2] + g[0::2, 1::2] + g[1::2, 1::2])


def _probes(left: np.ndarray, margin_x: int, margin_y: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the most textured pixel (horizontal gradient) of each grid cell."""
    gx = np.zeros_like(left)
    gx[:, 1:-1] = np.abs(left[:, 2:] - left[:, :-2])
    h, w = left.shape
    inner = gx[margin_y:h - margin_y, margin_x:w - margin_x]
    ch, cw = inner.shape[0] // GRID_CELL, inner.shape[1] // GRID_CELL
    if ch == 0 or cw == 0:
        return np.zeros(0, int), np.zeros(0, int)
    cells = inner[:ch * GRID_CELL, :cw * GRID_CELL].reshape(ch, GRID_CELL, cw, GRID_CELL)
    cells = cells.transpose(0, 2, 1, 3).reshape(ch * cw, -1)
    best = cells.argmax(axis=1)
    strength = cells[np.arange(len(cells)), best]
    keep = np.argsort(-strength)[:MAX_PROBES]
    keep = keep[strength[keep] > MIN_GRADIENT]
    rows = (keep // cw) * GRID_CELL + best[keep] // GRID_CELL + margin_y
    cols = (keep % cw) * GRID_CELL + best[keep] % GRID_CELL + margin_x
    return rows, cols


def disparity_signs(left: np.ndarray, right: np.ndarray) -> tuple[int, int, int]:
    """``(positive, zero, negative)`` counts of confident block-matching disparities
    ``x_left - x_right`` of textured pixels, searched in both directions."""
    L, R = _grey_half(left), _grey_half(right)
    r = PATCH_RADIUS
    D = min(MAX_HALF_DISPARITY, (L.shape[1] - 2 * r - 2) // 4)  # small images: the middle half
    if D < 2:
        return 0, 0, 0
    rows, cols = _probes(L, D + r + 1, r + 1)
    if len(rows) == 0:
        return 0, 0, 0
    dy, dx = np.mgrid[-r:r + 1, -r:r + 1].reshape(2, -1)
    shifts = np.arange(-D, D + 1)
    patch_l = L[rows[:, None] + dy, cols[:, None] + dx]  # (N, P)
    patch_r = R[rows[:, None, None] + dy, cols[:, None, None] + dx - shifts[:, None]]  # (N, S, P)
    sad = np.abs(patch_r - patch_l[:, None, :]).sum(axis=2)  # (N, S)
    best = sad.argmin(axis=1)
    best_cost = sad[np.arange(len(sad)), best]
    far = np.abs(np.arange(len(shifts))[None, :] - best[:, None]) >= 2
    second = np.where(far, sad, np.inf).min(axis=1)
    confident = best_cost < UNIQUENESS * second
    d = shifts[best[confident]]
    return int((d > 0).sum()), int((d == 0).sum()), int((d < 0).sum())


def check_stereo_pair(left: np.ndarray, right: np.ndarray, where: str) -> bool:
    """Refuse a right image equal to the left one or cameras swapped; returns whether the
    pair gave a verdict (False: too little texture to tell; two blank frames are equal too,
    and are no error)."""
    if left.shape != right.shape:
        return False  # refused, naming the frame, by the tracker
    pos, zero, neg = disparity_signs(left, right)
    total = pos + zero + neg
    if total < MIN_CONFIDENT:
        return False
    if np.array_equal(left, right):
        raise ValueError(f"{where}: the right image is identical to the left one; stereo needs "
                         "the two cameras' images (image_02 left, image_03 right)")
    if zero > MAX_ZERO_FRACTION * total:
        raise ValueError(f"{where}: the right image is nearly identical to the left one "
                         f"({zero} of {total} matched pixels have zero disparity); stereo needs "
                         "the two cameras' images (image_02 left, image_03 right)")
    if neg > MAX_NEGATIVE_FRACTION * total:
        raise ValueError(f"{where}: {neg} of {total} matched pixels have a negative disparity: "
                         "cameras swapped? image_02 must hold the left camera, image_03 the "
                         "right one")
    return True


def check_first_frames(sequence, indices) -> None:
    """Image size against the calibration, identical or swapped images, on the first frames
    of a run (up to :data:`FRAMES_CHECKED` until one has enough texture to tell)."""
    from .inputs import _frame_file, load_frame

    for index in list(indices)[:FRAMES_CHECKED]:
        frame = load_frame(sequence, index)
        path = _frame_file(sequence, "image_02", index)
        where = f"frame {index}" + (f" ({path.parent.parent.name}/{path.parent.name})"
                                    if path is not None else "")
        height, width = frame.image_left.shape[:2]
        check_image_size(width, height, sequence.calib, where)
        if check_stereo_pair(frame.image_left, frame.image_right, where):
            return


# ------------------------------------------------------------------------ output folders
def check_output_dir(path: str | os.PathLike, option: str) -> Path:
    """Make sure folder ``path`` can be created (if missing) and written into, before any
    work: a run must not track for an hour and then fail to save. Nothing is created; errors
    name ``option`` (``--out``, ``--plots``)."""
    return _writable_dir(Path(path), option, Path(path))


def check_output_file(path: str | os.PathLike, option: str) -> Path:
    """The folder of file ``path`` can be written into and ``path`` is no folder."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{option} {path}: is a folder, expected a file name")
    _writable_dir(path.parent, option, path)
    return path


def _writable_dir(folder: Path, option: str, shown: Path) -> Path:
    """Probe the nearest existing folder of ``folder`` with a nameless temporary file."""
    existing = next(p for p in (folder.absolute(), *folder.absolute().parents) if p.exists())
    if not existing.is_dir():
        raise ValueError(f"{option} {shown}: {existing} is a file, not a folder")
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as exc:
        reason = exc.strerror or str(exc)
        raise ValueError(f"{option} {shown}: cannot write into {existing} ({reason})") from None
    return folder
