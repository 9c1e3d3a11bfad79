"""One-to-one, per-frame association of estimated tracks with ground-truth objects.

The rule of the CLEAR MOT metrics (Bernardin and Stiefelhagen 2008), which KITTI's tracking
devkit follows: in each frame an estimated track stands for at most one object and an
object is stood for by at most one track. A pair is a candidate when the track's position
lies inside the object's box grown by a margin (:func:`.object_tracks.inside_box`'s gate);
a pair matched in the previous frame is kept while it stays a candidate (no identity switch
for a closer newcomer), the rest are matched by the Hungarian algorithm on the distance to
the box centre in units of the grown half extents (a box is longer than wide: a metre along
a car is less than a metre across it).

Without it one track between two queued cars, inside both grown boxes, would cover both:
a car the tracker lost would count as tracked by its neighbour's track, and be compared with
it (seen on crowded seed 16 in the twenty-sixth session: a queued car at 0.60 of its frames
matched to the track of the car ahead).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from .trajectory import invert

#: cost of a pair outside the gate (never chosen: the Hungarian step drops such pairs)
_NO_PAIR = 1e6


def _box_coordinates(points_w: np.ndarray, T_w_o: np.ndarray) -> np.ndarray:
    """(E, G, 3) the E world points in each of the G box frames."""
    T_o_w = invert(T_w_o)
    return np.einsum("gij,ej->egi", T_o_w[:, :3, :3], points_w) + T_o_w[None, :, :3, 3]


def assign_tracks(gt_boxes: dict[int, list[tuple[int, np.ndarray, np.ndarray]]],
                  est_positions: dict[int, list[tuple[int, np.ndarray]]],
                  margin_m: float) -> dict[int, dict[int, int]]:
    """Per frame, estimated track id -> ground-truth track id, one-to-one.

    Parameters
    ----------
    gt_boxes : frame -> [(gt id, ``T_w_o`` (4, 4), half extents (3,))], every object of the
        frame (any class, hidden or not: a track on a hidden object stands for it).
    est_positions : frame -> [(estimated track id, position (3,))] in the same world.
    margin_m : the gate: the box grown by this much on every side (m).

    Returns
    -------
    frame -> {estimated id: ground-truth id} for the frames with at least one pair.
    """
    assignment: dict[int, dict[int, int]] = {}
    previous: dict[int, int] = {}
    for frame in sorted(est_positions):
        boxes, tracks = gt_boxes.get(frame, []), est_positions[frame]
        if not boxes or not tracks:
            previous = {}
            continue
        gt_ids = [b[0] for b in boxes]
        est_ids = [t[0] for t in tracks]
        half = np.stack([b[2] for b in boxes]) + margin_m                 # (G, 3)
        local = _box_coordinates(np.stack([t[1] for t in tracks]), np.stack([b[1] for b in boxes]))
        gate = (np.abs(local) <= half[None]).all(axis=-1)                  # (E, G)
        cost = np.where(gate, np.linalg.norm(local / half[None], axis=-1), _NO_PAIR)
        matched: dict[int, int] = {}
        column = {g: j for j, g in enumerate(gt_ids)}
        for i, est_id in enumerate(est_ids):  # CLEAR MOT: keep last frame's pairs while valid
            g = previous.get(est_id)
            if g is not None and g in column and gate[i, column[g]] and g not in matched.values():
                matched[est_id] = g
        free_rows = [i for i, e in enumerate(est_ids) if e not in matched]
        taken = set(matched.values())
        free_cols = [j for j, g in enumerate(gt_ids) if g not in taken]
        if free_rows and free_cols:
            sub = cost[np.ix_(free_rows, free_cols)]
            for r, c in zip(*linear_sum_assignment(sub)):
                if sub[r, c] < _NO_PAIR:
                    matched[est_ids[free_rows[r]]] = gt_ids[free_cols[c]]
        if matched:
            assignment[frame] = matched
        previous = matched
    return assignment
