"""Planar paths (street centre lines, lanes, routes) as dense polylines with arc length."""

from __future__ import annotations

import numpy as np

SAMPLE_STEP = 0.5  # m between stored samples; interpolation error of a 180 m curve ~0.2 mm


class Path2D:
    """A polyline in the map plane (x, y), parametrised by arc length ``s`` from its start."""

    def __init__(self, points: np.ndarray) -> None:
        points = np.asarray(points, dtype=np.float64)
        step = np.linalg.norm(np.diff(points, axis=0), axis=1)
        keep = np.concatenate([[True], step > 1e-9])  # duplicated joints would break headings
        self.points = points[keep]
        self.s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(self.points, axis=0), axis=1))])
        d = np.gradient(self.points, self.s, axis=0)
        self.heading = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))

    @property
    def length(self) -> float:
        return float(self.s[-1])

    def pose(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Points (N, 2) and headings (N,) at arc lengths ``s`` (clamped to the path)."""
        s = np.atleast_1d(np.asarray(s, dtype=np.float64))
        x = np.interp(s, self.s, self.points[:, 0])
        y = np.interp(s, self.s, self.points[:, 1])
        return np.stack([x, y], -1), np.interp(s, self.s, self.heading)

    def curvature(self, s: np.ndarray | float) -> np.ndarray:
        """Signed curvature (1/m, positive = turning left) at ``s``."""
        kappa = np.gradient(self.heading, self.s)
        return np.interp(np.atleast_1d(s), self.s, kappa)

    def offset(self, lateral: float) -> "Path2D":
        """The parallel path ``lateral`` metres to the left (negative: right)."""
        normal = np.stack([-np.sin(self.heading), np.cos(self.heading)], -1)
        return Path2D(self.points + lateral * normal)

    def reversed(self) -> "Path2D":
        return Path2D(self.points[::-1])

    def sub(self, s0: float, s1: float) -> "Path2D":
        """The piece between arc lengths ``s0 < s1``."""
        inner = (self.s > s0) & (self.s < s1)
        p0, _ = self.pose(s0)
        p1, _ = self.pose(s1)
        return Path2D(np.concatenate([p0, self.points[inner], p1]))

    def project(self, xy: np.ndarray) -> np.ndarray:
        """Arc length of the closest point of the path to each point (N, 2): the nearest
        sample, refined along the local tangent (brute force; small N)."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        k = np.argmin(np.linalg.norm(self.points[None] - xy[:, None], axis=-1), axis=1)
        t = np.stack([np.cos(self.heading[k]), np.sin(self.heading[k])], -1)
        s = self.s[k] + np.einsum("ij,ij->i", xy - self.points[k], t)
        return np.clip(s, 0.0, self.length)


def from_curvature(kappa: np.ndarray, ds: float, start: np.ndarray, heading0: float) -> Path2D:
    """Integrate a curvature profile sampled every ``ds`` metres from a start pose."""
    heading = heading0 + np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * ds)])
    step = np.stack([np.cos(heading), np.sin(heading)], -1)
    mid = 0.5 * (step[1:] + step[:-1]) * ds
    return Path2D(start + np.concatenate([[[0.0, 0.0]], np.cumsum(mid, axis=0)]))


def fillet_route(a: Path2D, b: Path2D, radius: float, near: np.ndarray) -> Path2D:
    """Route along ``a`` then ``b`` joined by a circular arc of ``radius`` tangent to both.

    Both paths must be straight near ``near`` (the intersection centre), where their lines cross.
    """
    pa, ha = a.pose(a.project(np.asarray(near)[None])[0])
    pb, hb = b.pose(b.project(np.asarray(near)[None])[0])
    da = np.array([np.cos(ha[0]), np.sin(ha[0])])
    db = np.array([np.cos(hb[0]), np.sin(hb[0])])
    # pa + t da = pb + u db
    t, _ = np.linalg.solve(np.stack([da, -db], 1), pb[0] - pa[0])
    q = pa[0] + t * da
    turn = np.arctan2(da[0] * db[1] - da[1] * db[0], da @ db)  # signed turn angle
    tangent = radius * np.tan(abs(turn) / 2.0)
    s_in = a.project(q[None])[0] - tangent
    s_out = b.project(q[None])[0] + tangent
    p_in = (q - tangent * da)[None]  # exact tangent points: no kink where arc and lines meet
    left = np.array([-da[1], da[0]]) * np.sign(turn)
    centre = p_in[0] + radius * left
    phi0 = np.arctan2(p_in[0, 1] - centre[1], p_in[0, 0] - centre[0])
    n_arc = max(8, int(radius * abs(turn) / SAMPLE_STEP))
    phi = phi0 + np.sign(turn) * np.linspace(0.0, abs(turn), n_arc)
    arc = centre + radius * np.stack([np.cos(phi), np.sin(phi)], -1)
    first = a.sub(0.0, s_in).points
    last = b.sub(s_out, b.length).points
    return Path2D(np.concatenate([first[:-1], arc, last[1:]]))
