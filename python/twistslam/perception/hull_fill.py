"""2D convex hull of image points and its filled pixel mask (numpy + PIL, no OpenCV)."""

from __future__ import annotations

import numpy as np


#: Below this many points the hull is computed on all of them (the filter would not pay).
_FILTER_MIN_POINTS = 32


def convex_hull(points: np.ndarray) -> np.ndarray:
    """(K, 2) hull vertices of (N, 2) points, counter-clockwise (Andrew's monotone chain);
    fewer than 3 distinct points are returned as they are. Points strictly inside the
    polygon of the extreme points in eight directions are dropped first (Akl-Toussaint):
    they cannot be hull vertices, so the hull is the same, and the chain's Python loop only
    sees the few that remain (it was a quarter of the masks' time on real KITTI scans)."""
    pts = np.asarray(points, dtype=np.float64)
    return _monotone_chain(np.unique(_drop_interior(pts), axis=0))  # sorted by x, then y


def _drop_interior(pts: np.ndarray) -> np.ndarray:
    """``pts`` without those strictly inside the octagon of its extreme points (by a margin
    far above rounding, so no point near the octagon's edges is dropped)."""
    if len(pts) < _FILTER_MIN_POINTS or not np.isfinite(pts).all():
        return pts
    angles = np.arange(8) * (np.pi / 4)  # increasing angle: the extremes in hull order
    directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    extremes = np.argmax(pts @ directions.T, axis=0)
    order = list(dict.fromkeys(extremes.tolist()))  # consecutive directions may share one
    if len(order) < 3:
        return pts
    a = pts[order]
    b = np.roll(a, -1, axis=0)
    edge = b - a
    scale = float(np.abs(pts - pts.mean(axis=0)).max()) + 1.0
    margin = 1e-9 * scale * scale
    cross = edge[:, 0] * (pts[:, None, 1] - a[:, 1]) - edge[:, 1] * (pts[:, None, 0] - a[:, 0])
    interior = (cross > margin).all(axis=1)
    return pts[~interior]


def _monotone_chain(pts: np.ndarray) -> np.ndarray:
    """Hull of points sorted by x, then y, without duplicates."""
    if len(pts) < 3:
        return pts

    def half(sequence: np.ndarray) -> list[np.ndarray]:
        chain: list[np.ndarray] = []
        for p in sequence:
            # pop while the last turn is not strictly left (collinear points are dropped)
            while len(chain) >= 2:
                a, b = chain[-2], chain[-1]
                if (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0:
                    break
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def clip_polygon(polygon: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """Part of a convex polygon inside the rectangle ``[x0, x1] x [y0, y1]``
    (Sutherland-Hodgman, one rectangle side at a time)."""
    out = [np.asarray(p, float) for p in polygon]
    for axis, bound, keep_above in ((0, x0, True), (0, x1, False), (1, y0, True), (1, y1, False)):
        if not out:
            break
        inside = [(p[axis] >= bound) if keep_above else (p[axis] <= bound) for p in out]
        clipped = []
        for i, p in enumerate(out):
            q, q_in = out[i - 1], inside[i - 1]
            if inside[i] != q_in:  # the edge q -> p crosses the side: keep the crossing
                t = (bound - q[axis]) / (p[axis] - q[axis])
                clipped.append(q + t * (p - q))
            if inside[i]:
                clipped.append(p)
        out = clipped
    return np.array(out).reshape(-1, 2)


def fill_convex_hull(points: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(H, W) bool: pixels whose centre lies in the convex hull of image points ``(N, 2)``,
    and the pixels holding a point (pixel ``(u, v)`` covers ``[u, u+1) x [v, v+1)``).

    The points' own pixels are added because sparse LiDAR puts most of an object's points on
    its hull, and about half of those fall in pixels whose centre is just outside it (75 %
    of one real KITTI car's points were covered by the centre test alone)."""
    H, W = shape
    mask = np.zeros(shape, bool)
    hull = convex_hull(points)
    if len(hull) < 3 or not np.isfinite(hull).all():
        return mask
    # fill only the hull's bounding box, clipped to the image: far boxes are a few pixels
    u0, v0 = np.maximum(np.floor(hull.min(axis=0)).astype(int), 0)
    u1, v1 = np.minimum(np.ceil(hull.max(axis=0)).astype(int) + 1, [W, H])
    if u0 >= u1 or v0 >= v1:
        return mask
    from PIL import Image, ImageDraw

    # the hull can reach far outside the image (a point near the camera plane): cut it to
    # the crop (plus a pixel) so PIL only ever sees small coordinates
    local = clip_polygon(hull - [u0 + 0.5, v0 + 0.5], -1.0, -1.0, u1 - u0 + 1.0, v1 - v0 + 1.0)
    if len(local) < 3:
        return mask
    canvas = Image.new("1", (int(u1 - u0), int(v1 - v0)), 0)
    ImageDraw.Draw(canvas).polygon([tuple(p) for p in local], fill=1, outline=1)
    mask[v0:v1, u0:u1] = np.array(canvas, dtype=bool)
    pix = np.floor(np.asarray(points, dtype=np.float64)).astype(np.int64)
    inside = (pix[:, 0] >= 0) & (pix[:, 0] < W) & (pix[:, 1] >= 0) & (pix[:, 1] < H)
    mask[pix[inside, 1], pix[inside, 0]] = True
    return mask
