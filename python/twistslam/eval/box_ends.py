"""Where a detector's boxes end: near- and far-end offsets along each matched label's length,
by view angle and range (``twistslam eval-detections ... --box-ends``).

A LiDAR sees a car's end nearer the sensor squarely; the far end of its side comes in at a
grazing angle when the car is seen nearly end-on, and a box drawn around the returns can fall
short there. The AP hides where a box's length error sits; this table shows it. Every
detection of the class is matched one to one to the nearest label of the same frame by
bird's-eye centre distance (closest pairs first, within ``max_centre_distance_m``). For each
pair, along the label's heading axis:

* ``view``: the angle between that axis and the line of sight to the label's centre, folded
  into 0-90 deg (0: seen end-on, from behind or ahead; 90: broadside);
* ``near`` / ``far``: how far the detection's end nearer / farther from the sensor lies
  beyond the label's (m, positive outwards: the box is longer there);
* ``centre``: the detection centre's shift along the axis towards the far end (m);
* ``dl``: detection length minus label length (m).

A detection whose heading differs from the label's is measured by its extent along the
label's axis (``|cos| l / 2 + |sin| w / 2`` on each side of its centre). Medians per bin.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..datasets.objects import ObjectTable
from .detection_ap import Tables, _by_frame

#: view-angle bin edges (deg between the label's axis and the line of sight)
VIEW_BINS_DEG = (0.0, 10.0, 20.0, 30.0, 50.0, 90.0)
#: range bin edges (m, bird's-eye distance from the camera to the label's centre)
RANGE_BINS_M = (0.0, 15.0, 30.0, 80.0)
#: a detection farther than this from every free label of its frame is not matched: a car's
#: half width, so that a box never pairs with the car beside its own
MAX_CENTRE_DISTANCE_M = 1.5
#: columns of :func:`box_end_offsets`' array
COLUMNS = ("frame", "range_m", "view_deg", "dl_m", "near_m", "far_m", "centre_m")


@dataclass(frozen=True)
class BoxEndsRow:
    """Medians of the matched pairs in one (view angle, range) bin."""

    view_deg: tuple[float, float]
    range_m: tuple[float, float]
    n: int
    dl_m: float
    near_m: float
    far_m: float
    centre_m: float


@dataclass(frozen=True)
class BoxEndsResult:
    """Per-bin medians of one class's matched detections (bins without a pair left out)."""

    cls: str
    rows: tuple[BoxEndsRow, ...]
    n_matched: int
    n_detections: int
    offsets: np.ndarray  # (n_matched, len(COLUMNS)) every pair, columns as COLUMNS

    def table(self) -> str:
        """The bins as text, one line each."""
        lines = [f"{self.cls} box ends along the label's axis: {self.n_matched} of "
                 f"{self.n_detections} detections matched (median m; near / far: the end "
                 "nearer / farther from the sensor, + beyond the label's; centre: + towards "
                 "the far end)",
                 f"{'view deg':>10}{'range m':>10}{'n':>6}{'dl':>8}{'near':>8}{'far':>8}"
                 f"{'centre':>8}"]
        for r in self.rows:
            lines.append(f"{r.view_deg[0]:>4.0f}-{r.view_deg[1]:<5.0f}"
                         f"{r.range_m[0]:>4.0f}-{r.range_m[1]:<5.0f}{r.n:>6}{r.dl_m:>+8.2f}"
                         f"{r.near_m:>+8.2f}{r.far_m:>+8.2f}{r.centre_m:>+8.2f}")
        return "\n".join(lines) + "\n"

    def to_dict(self) -> dict:
        """JSON-ready dict of the bins."""
        return {"class": self.cls, "n_matched": self.n_matched,
                "n_detections": self.n_detections,
                "bins": [{"view_deg": list(r.view_deg), "range_m": list(r.range_m), "n": r.n,
                          "dl_m": r.dl_m, "near_m": r.near_m, "far_m": r.far_m,
                          "centre_m": r.centre_m} for r in self.rows]}


def _match_frame(gt_xz: np.ndarray, det_xz: np.ndarray,
                 max_distance: float) -> list[tuple[int, int]]:
    """One-to-one (label, detection) pairs, closest first, within ``max_distance``."""
    if len(gt_xz) == 0 or len(det_xz) == 0:
        return []
    d = np.linalg.norm(gt_xz[:, None, :] - det_xz[None, :, :], axis=2)
    pairs, used_g, used_d = [], set(), set()
    for flat in np.argsort(d, axis=None, kind="stable"):
        g, k = np.unravel_index(flat, d.shape)
        if d[g, k] > max_distance:
            break
        if g in used_g or k in used_d:
            continue
        used_g.add(g), used_d.add(k)
        pairs.append((int(g), int(k)))
    return pairs


def _pair_offsets(g: np.ndarray, b: np.ndarray) -> tuple[float, ...]:
    """(range, view, dl, near, far, centre) of detection box ``b`` against label box ``g``
    (both ``[cx, cy, cz, l, w, h, ry]``)."""
    centre_g, centre_b = g[[0, 2]], b[[0, 2]]
    axis = np.array([np.cos(g[6]), -np.sin(g[6])])  # the length axis in (x, z): ry = 0 is +x
    distance = float(np.linalg.norm(centre_g))
    ray = centre_g / max(distance, 1e-9)
    view = float(np.degrees(np.arccos(min(1.0, abs(float(ray @ axis))))))
    towards_near = -axis if centre_g @ axis > 0 else axis
    heading_b = np.array([np.cos(b[6]), -np.sin(b[6])])
    cross = abs(heading_b[0] * axis[1] - heading_b[1] * axis[0])
    half_b = abs(float(heading_b @ axis)) * b[3] / 2 + cross * b[4] / 2
    along_g, along_b = float(centre_g @ towards_near), float(centre_b @ towards_near)
    near = (along_b + half_b) - (along_g + g[3] / 2)
    far = (half_b - along_b) - (g[3] / 2 - along_g)
    return distance, view, float(b[3] - g[3]), float(near), float(far), along_g - along_b


def box_end_offsets(gt: Tables, dets: Tables, cls: str = "Car",
                    max_centre_distance_m: float = MAX_CENTRE_DISTANCE_M,
                    frames=None) -> tuple[np.ndarray, int]:
    """Every matched pair's offsets (columns :data:`COLUMNS`) and the number of detections
    of ``cls`` in the evaluated frames.

    ``gt`` and ``dets``: an ObjectTable or ``{frame: ObjectTable}`` (as
    :func:`~twistslam.eval.detection_ap.evaluate_detections`); ``frames``: the frames to use
    (default: every frame of either side). Classes compare case-insensitively.
    """
    if not max_centre_distance_m > 0:
        raise ValueError(f"max_centre_distance_m must be > 0, got {max_centre_distance_m}")
    gt_frames, det_frames = _by_frame(gt, "gt"), _by_frame(dets, "dets")
    frame_ids = sorted(set(gt_frames) | set(det_frames) if frames is None else set(frames))
    rows, n_det = [], 0
    for f in frame_ids:
        g = gt_frames.get(f)
        d = det_frames.get(f)
        if d is None:
            continue
        d = d.select(np.char.lower(d.cls.astype(str)) == cls.lower())
        n_det += len(d)
        if g is None or len(d) == 0:
            continue
        g = g.select(np.char.lower(g.cls.astype(str)) == cls.lower())
        for i, k in _match_frame(g.box_3d[:, [0, 2]], d.box_3d[:, [0, 2]], max_centre_distance_m):
            rows.append((f, *_pair_offsets(g.box_3d[i], d.box_3d[k])))
    offsets = np.array(rows, dtype=np.float64).reshape(-1, len(COLUMNS))
    if not np.isfinite(offsets).all():
        raise ValueError("box_end_offsets: a matched box has a non-finite centre, size or yaw")
    return offsets, n_det


def evaluate_box_ends(gt: Tables, dets: Tables, cls: str = "Car",
                      view_bins_deg=VIEW_BINS_DEG, range_bins_m=RANGE_BINS_M,
                      max_centre_distance_m: float = MAX_CENTRE_DISTANCE_M,
                      frames=None) -> BoxEndsResult:
    """Medians of the end offsets (see the module docstring) per view-angle and range bin."""
    for name, edges in (("view_bins_deg", view_bins_deg), ("range_bins_m", range_bins_m)):
        e = np.asarray(edges, dtype=np.float64)
        if e.ndim != 1 or len(e) < 2 or not np.all(np.diff(e) > 0):
            raise ValueError(f"{name} must be at least two increasing edges, got {edges}")
    offsets, n_det = box_end_offsets(gt, dets, cls, max_centre_distance_m, frames)
    rows = []
    for v0, v1 in zip(view_bins_deg[:-1], view_bins_deg[1:]):
        # the last view bin includes 90 deg itself
        in_view = (offsets[:, 2] >= v0) & ((offsets[:, 2] < v1) | (v1 == view_bins_deg[-1])
                                           & (offsets[:, 2] <= v1))
        for r0, r1 in zip(range_bins_m[:-1], range_bins_m[1:]):
            s = in_view & (offsets[:, 1] >= r0) & (offsets[:, 1] < r1)
            if not s.any():
                continue
            med = np.median(offsets[s][:, 3:], axis=0)
            rows.append(BoxEndsRow((float(v0), float(v1)), (float(r0), float(r1)), int(s.sum()),
                                   *(float(x) for x in med)))
    return BoxEndsResult(cls=cls, rows=tuple(rows), n_matched=len(offsets), n_detections=n_det,
                         offsets=offsets)
