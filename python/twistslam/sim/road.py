"""Street network: a gently curving main street, an optional perpendicular cross street, their
lanes, and the meshes of road surfaces, raised sidewalks with curbs and the ground around.

Street coordinates: ``s`` is the arc length along a street's centre line, ``lat`` the signed
lateral offset (positive to the left of the driving direction of increasing ``s``). Traffic
keeps right: lanes of the ``+s`` direction lie at negative ``lat``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .config import StreetConfig
from .mesh import Mesh, ring_loft
from .path import Path2D, from_curvature
from .terrain import Terrain

ROAD_STEP = 2.0  # m between road mesh rows; the height field is smooth at this scale
TERRAIN_CELL = 2.5  # m, ground grid cell
TERRAIN_REACH = 75.0  # m from a centre line up to which ground is built (hidden beyond)
STRAIGHT_NEAR_INTERSECTION = 70.0  # m of straight main street each side of the crossing


@dataclass
class Street:
    """One street: centre line, cross-section and where another street crosses it."""

    index: int
    centre: Path2D
    lanes: int
    lane_width: float
    parking: float
    median: float
    sidewalk: float
    curb: float
    s_cross: float | None = None  # arc length of the intersection centre on this street
    cross_half: float = 0.0  # half road width of the crossing street
    cross_outer: float = 0.0  # half road width + sidewalk of the crossing street

    @property
    def half_width(self) -> float:
        """Curb-to-centre distance (m)."""
        return self.median / 2 + self.lanes * self.lane_width + self.parking

    def lane_offset(self, k: int) -> float:
        """|lat| of lane ``k`` (0 = next to the centre line)."""
        return self.median / 2 + (k + 0.5) * self.lane_width

    def lane(self, direction: int, k: int) -> Path2D:
        """Centre line of lane ``k`` in driving direction ``+1`` (increasing s) or ``-1``."""
        path = self.centre.offset(-direction * self.lane_offset(k))
        return path if direction > 0 else path.reversed()

    def curb_path(self, side: int, inset: float) -> Path2D:
        """Path ``inset`` metres from the curb on ``side`` (+1 left, -1 right), direction +s;
        a positive inset lies on the road (parking), a negative one on the sidewalk."""
        return self.centre.offset(side * (self.half_width - inset))

    def gaps(self, outer: bool) -> list[tuple[float, float]]:
        """Pieces of s where this street's road (``outer=False``) or its sidewalks and
        facades (``outer=True``) are interrupted by the crossing street."""
        if self.s_cross is None:
            return []
        half = self.cross_outer if outer else self.cross_half
        return [(self.s_cross - half, self.s_cross + half)]


def intervals(length: float, gaps: list[tuple[float, float]]) -> list[tuple[float, float]]:
    pieces, start = [], 0.0
    for g0, g1 in sorted(gaps):
        if g0 > start:
            pieces.append((start, g0))
        start = max(start, g1)
    if start < length:
        pieces.append((start, length))
    return pieces


def _samples(s0: float, s1: float, step: float) -> np.ndarray:
    n = max(1, int(np.ceil((s1 - s0) / step)))
    return np.linspace(s0, s1, n + 1)


class StreetNetwork:
    """Main street 0 (starting ``cfg.behind`` metres behind the ego start, which is the map
    origin, heading +x) and, when enabled, cross street 1."""

    def __init__(self, cfg: StreetConfig, rng: np.random.Generator, length_ahead: float,
                 median: float = 0.0) -> None:
        self.cfg = cfg
        self.ego_s0 = cfg.behind
        total = cfg.behind + length_ahead
        s_int = None
        if cfg.intersection:
            s_int = cfg.behind + rng.uniform(*cfg.intersection_ahead)
        kappa = self._curvature_profile(rng, total, s_int)
        ds = 0.5
        k_ahead = kappa[int(round(cfg.behind / ds)):]
        k_behind = kappa[: int(round(cfg.behind / ds)) + 1][::-1]
        ahead = from_curvature(k_ahead, ds, np.zeros(2), 0.0)
        behind = from_curvature(-k_behind, ds, np.zeros(2), np.pi)
        centre = Path2D(np.concatenate([behind.points[::-1], ahead.points[1:]]))
        common = dict(lane_width=cfg.lane_width, parking=cfg.parking_width, median=median,
                      sidewalk=cfg.sidewalk_width, curb=cfg.curb_height)
        main = Street(0, centre, cfg.lanes_per_direction, **common)
        self.streets = [main]
        if s_int is not None:
            p, h = centre.pose(s_int)
            d = np.array([-np.sin(h[0]), np.cos(h[0])])  # cross street runs to the main's left
            half = length_ahead
            cross = Street(1, Path2D(p[0] + np.linspace(-half, half, int(2 * half / 0.5) + 1)[:, None] * d),
                           cfg.cross_lanes_per_direction, **common)
            main.s_cross, cross.s_cross = s_int, half
            main.cross_half, cross.cross_half = cross.half_width, main.half_width
            main.cross_outer = cross.half_width + cross.sidewalk
            cross.cross_outer = main.half_width + main.sidewalk
            self.streets.append(cross)

    def _curvature_profile(self, rng: np.random.Generator, total: float, s_int: float | None) -> np.ndarray:
        """Piecewise-constant curvature, smoothed into clothoid-like transitions, zero near
        the ego start (frame 0 looks down a straight street) and near the intersection."""
        cfg = self.cfg
        ds = 0.5
        s = np.arange(0.0, total + ds / 2, ds)
        kappa = np.zeros_like(s)
        pos = 0.0
        while pos < total:
            length = rng.uniform(*cfg.curve_length)
            value = rng.uniform(-cfg.max_curvature, cfg.max_curvature) * (rng.uniform() < 0.7)
            kappa[(s >= pos) & (s < pos + length)] = value
            pos += length
        kappa[np.abs(s - cfg.behind) < 25.0] = 0.0
        if s_int is not None:
            kappa[np.abs(s - s_int) < STRAIGHT_NEAR_INTERSECTION] = 0.0
        width = int(30.0 / ds)
        return np.convolve(np.pad(kappa, width // 2, mode="edge"), np.ones(width) / width, "valid")[: len(s)]

    # ------------------------------------------------------------------------------ meshes
    def road_mesh(self, terrain: Terrain) -> Mesh:
        """Asphalt of all streets; attributes ``(s, lat, street, 0)``."""
        meshes = []
        for st in self.streets:
            W = st.half_width
            lat = np.linspace(-W, W, max(3, int(np.ceil(2 * W / 1.75)) + 1))
            for s0, s1 in intervals(st.centre.length, st.gaps(outer=False)):
                meshes.append(self._grid(st, terrain, _samples(s0, s1, ROAD_STEP), lat, 0.0))
        return Mesh.concat(meshes)

    def _grid(self, st: Street, terrain: Terrain, s: np.ndarray, lat: np.ndarray, dz: float) -> Mesh:
        p, h = st.centre.pose(s)
        normal = np.stack([-np.sin(h), np.cos(h)], -1)
        xy = p[:, None] + lat[None, :, None] * normal[:, None]
        vertices = terrain.lift(xy.reshape(-1, 2), dz)
        S, L = len(s), len(lat)
        i = np.arange(S - 1)[:, None] * L + np.arange(L - 1)[None]
        faces = np.concatenate([np.stack([i, i + 1, i + L + 1], -1).reshape(-1, 3),
                                np.stack([i, i + L + 1, i + L], -1).reshape(-1, 3)])
        attrs = np.stack([np.repeat(s, L), np.tile(lat, S), np.full(S * L, st.index), np.zeros(S * L)], -1)
        return Mesh(vertices, faces, attrs)

    def sidewalk_mesh(self, terrain: Terrain) -> Mesh:
        """Closed raised slabs along both curbs; attributes ``(s, lat, street, dz)`` where dz
        is the height above the road (curb faces have dz < curb height)."""
        meshes = []
        for st in self.streets:
            W, sw, c = st.half_width, st.sidewalk, st.curb
            section = np.array([[W, -0.05], [W, c], [W + sw, c], [W + sw, -0.05]])
            for side in (-1, 1):
                sec = section if side > 0 else section[::-1] * [-1, 1]
                for s0, s1 in intervals(st.centre.length, st.gaps(outer=True)):
                    s = _samples(s0, s1, ROAD_STEP)
                    p, h = st.centre.pose(s)
                    normal = np.stack([-np.sin(h), np.cos(h)], -1)
                    xy = p[:, None] + sec[None, :, 0, None] * normal[:, None]
                    z = terrain.height(xy.reshape(-1, 2)).reshape(len(s), 4) + sec[None, :, 1]
                    rings = np.concatenate([xy, z[..., None]], -1)
                    mesh = ring_loft(rings)
                    ring_attrs = np.stack(np.broadcast_arrays(s[:, None], sec[None, :, 0], float(st.index),
                                                              sec[None, :, 1]), -1).reshape(-1, 4)
                    caps = [[s[0], side * (W + sw / 2), st.index, c / 2], [s[-1], side * (W + sw / 2), st.index, c / 2]]
                    mesh.attrs = np.concatenate([ring_attrs, caps]).astype(np.float32)
                    meshes.append(mesh)
        return Mesh.concat(meshes)

    def ground_mesh(self, terrain: Terrain) -> Mesh:
        """Height-field grid just below the road level, within reach of a street (grass, dirt)."""
        centres = np.concatenate([st.centre.points for st in self.streets])
        lo, hi = centres.min(0) - TERRAIN_REACH, centres.max(0) + TERRAIN_REACH
        xs = np.arange(lo[0], hi[0] + TERRAIN_CELL, TERRAIN_CELL)
        ys = np.arange(lo[1], hi[1] + TERRAIN_CELL, TERRAIN_CELL)
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        xy = np.stack([X.ravel(), Y.ravel()], -1)
        vertices = terrain.lift(xy, -0.04)
        nx, ny = len(xs), len(ys)
        i = (np.arange(nx - 1)[:, None] * ny + np.arange(ny - 1)[None]).ravel()
        cell_centre = xy[i] + TERRAIN_CELL / 2
        dist, _ = cKDTree(centres).query(cell_centre)
        i = i[dist < TERRAIN_REACH]
        faces = np.concatenate([np.stack([i, i + ny, i + ny + 1], -1), np.stack([i, i + ny + 1, i + 1], -1)])
        return Mesh(vertices, faces)
