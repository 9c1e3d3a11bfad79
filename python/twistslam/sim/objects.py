"""The moving objects of one frame, ray cast without a per-frame BVH.

Each object's mesh has its own ray-casting scene in its object frame, built once per sequence
(a RaycastingScene cannot move geometry: a scene of the frame's placed meshes cost ~35 ms of
BVH build per frame, more than all the casts into it). A ray that may hit an object is moved
into the object frame and cast there; which rays may hit which object is known from the
object's box for each kind of ray bundle, without testing every ray against every box:

- rays of an image (one origin, a pixel grid): the rectangle around the projected box,
- LiDAR rays (one origin, an elevation x azimuth grid): the box's angular window,
- shadow rays (one direction): the box's outline seen along the sun, found through a grid.
"""

from __future__ import annotations

import numpy as np

from .mesh import rotate
from .raycast import tensor_rays

#: the 12 edges of a box whose corner k has the coordinates (bit 0: x, bit 1: y, bit 2: z)
EDGES = np.array([(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1])
NEAR = 1e-3  # m; rays start at their origin, so box parts nearer than this are never hit


class MovingObjects:
    """Agents ``agents`` at poses ``T_m_o`` (K, 4, 4) with object-frame scenes ``scenes`` and
    object-frame boxes ``bounds`` (K, 2, 3) (min, max corners)."""

    def __init__(self, agents: np.ndarray, T_m_o: np.ndarray, scenes: list, bounds: np.ndarray) -> None:
        self.agents = np.asarray(agents, dtype=np.int32)
        self.T_m_o = T_m_o
        self.scenes = scenes
        k = np.arange(8)
        local = np.stack([bounds[:, (k >> b) & 1, b] for b in range(3)], -1)  # (K, 8, 3)
        self.corners = np.einsum("kij,kcj->kci", T_m_o[:, :3, :3], local) + T_m_o[:, None, :3, 3]

    def __len__(self) -> int:
        return len(self.agents)

    def _local_rays(self, k: int, origins: np.ndarray, dirs: np.ndarray, idx: np.ndarray, scale=None):
        """Rays ``idx`` moved into object k's frame (lengths kept, so hit distances agree)."""
        R, t = self.T_m_o[k, :3, :3], self.T_m_o[k, :3, 3]
        d = dirs[idx] if scale is None else dirs[idx] * scale[:, None]
        if origins.strides[0] == 0:  # one shared origin: move it once
            o = (origins[0] - t) @ R
        else:
            o = rotate(origins[idx] - t, R.T)
        return tensor_rays(o, rotate(d, R.T.astype(np.float32)))

    def first_hits(self, origins, dirs, candidates, t, group, agent, prim, uv, normal, code: int) -> None:
        """Replace the hits (arrays of all rays, changed in place) by nearer object hits among
        ray indices ``candidates[k]`` of each object k."""
        for k, idx in enumerate(candidates):
            if len(idx) == 0:
                continue
            r = self.scenes[k].cast_rays(self._local_rays(k, origins, dirs, idx))
            tk = r["t_hit"].numpy()
            closer = np.flatnonzero(tk < t[idx])
            j = idx[closer]
            t[j] = tk[closer]
            group[j] = code
            agent[j] = self.agents[k]
            prim[j] = r["primitive_ids"].numpy()[closer]
            uv[j] = r["primitive_uvs"].numpy()[closer]
            normal[j] = rotate(r["primitive_normals"].numpy()[closer], self.T_m_o[k, :3, :3].astype(np.float32))

    def occluded(self, origins, dirs, tfar, candidates) -> np.ndarray:
        """Whether rays (``tfar``: one limit or one per ray) hit an object before ``tfar``."""
        out = np.zeros(len(dirs), bool)
        per_ray = np.ndim(tfar) > 0
        for k, idx in enumerate(candidates):
            if len(idx) == 0:
                continue
            # per-ray limits: scale the directions so that t = 1 is the limit
            rays = self._local_rays(k, origins, dirs, idx, np.asarray(tfar)[idx] if per_ray else None)
            out[idx] |= self.scenes[k].test_occlusions(rays, tfar=1.0 if per_ray else float(tfar)).numpy()
        return out

    # ------------------------------------------------------------------ candidate rays
    def image_bounds(self, P: np.ndarray, T_m_c: np.ndarray) -> np.ndarray:
        """(K, 4) ``u_min, v_min, u_max, v_max`` of each box projected by the 3x4 ``P`` (of
        camera-frame points) from camera pose ``T_m_c``, cut at the near plane; NaN when the box
        is entirely behind the camera."""
        A = P[:, :3] @ T_m_c[:3, :3].T
        x = self.corners @ A.T + (P[:, 3] - A @ T_m_c[:3, 3])  # (K, 8, 3) homogeneous pixels
        a, b = x[:, EDGES[:, 0]], x[:, EDGES[:, 1]]
        wa, wb = a[..., 2:], b[..., 2:]
        with np.errstate(divide="ignore", invalid="ignore"):
            cut = a + (NEAR - wa) / (wb - wa) * (b - a)  # where the edges cross the near plane
            pts = np.concatenate([x, cut], 1)
            ok = np.concatenate([x[..., 2] >= NEAR, (wa[..., 0] - NEAR) * (wb[..., 0] - NEAR) < 0], 1)
            uv = pts[..., :2] / np.maximum(pts[..., 2:], NEAR)
        lo = np.where(ok[..., None], uv, np.inf).min(1)
        hi = np.where(ok[..., None], uv, -np.inf).max(1)
        out = np.concatenate([lo, hi], 1)
        out[~ok.any(1)] = np.nan
        return out

    def pixel_candidates(self, P: np.ndarray, T_m_c: np.ndarray, width: int, height: int) -> list[np.ndarray]:
        """Pixel-centre rays (row-major indices) of an image that may hit each object."""
        out = []
        for u0, v0, u1, v1 in self.image_bounds(P, T_m_c):
            if not np.isfinite(u0):
                out.append(np.zeros(0, np.int64))
                continue
            # one pixel of margin for rounding; the clip keeps rows and columns in the image
            c0, c1 = int(np.clip(np.floor(u0) - 1, 0, width)), int(np.clip(np.ceil(u1) + 1, -1, width - 1))
            r0, r1 = int(np.clip(np.floor(v0) - 1, 0, height)), int(np.clip(np.ceil(v1) + 1, -1, height - 1))
            out.append((np.arange(r0, r1 + 1)[:, None] * width + np.arange(c0, c1 + 1)).ravel())
        return out

    def point_candidates(self, P: np.ndarray, T_m_c: np.ndarray, uv: np.ndarray) -> list[np.ndarray]:
        """Rays from the camera to points projected at ``uv`` that may hit each object."""
        out = []
        for u0, v0, u1, v1 in self.image_bounds(P, T_m_c):
            ok = (uv[:, 0] >= u0 - 1) & (uv[:, 0] <= u1 + 1) & (uv[:, 1] >= v0 - 1) & (uv[:, 1] <= v1 + 1)
            out.append(np.flatnonzero(ok))  # false for NaN bounds
        return out

    def grid_candidates(self, T_m_s: np.ndarray, elevation: np.ndarray, azimuth_step: float, n_az: int
                        ) -> list[np.ndarray]:
        """Rays of a sensor at pose ``T_m_s`` with beams at ``elevation`` (rad) and ``n_az``
        azimuths ``0, step, ...`` (rad; row-major (beam, azimuth) indices) that may hit each
        object. Bounds are conservative: the box's horizontal extent is a disc around its centre."""
        X = (self.corners - T_m_s[:3, 3]) @ T_m_s[:3, :3]  # (K, 8, 3) sensor frame
        c = X[..., :2].mean(1)
        d = np.linalg.norm(c, axis=1)
        r = np.linalg.norm(X[..., :2] - c[:, None], axis=2).max(1) + 1e-3
        z0, z1 = X[..., 2].min(1), X[..., 2].max(1)
        near, far = np.maximum(d - r, 0.0), d + r
        el_hi = np.arctan2(z1, np.where(z1 > 0, near, far)) + 1e-4
        el_lo = np.arctan2(z0, np.where(z0 > 0, far, near)) - 1e-4
        out = []
        for k in range(len(self)):
            rows = np.flatnonzero((elevation >= el_lo[k]) & (elevation <= el_hi[k]))
            half = np.arcsin(r[k] / d[k]) if d[k] > r[k] else np.pi  # inside the disc: all azimuths
            first = int(np.floor((np.arctan2(c[k, 1], c[k, 0]) - half) / azimuth_step)) - 1
            count = int(np.ceil(2 * half / azimuth_step)) + 3
            # (the steps need not divide the turn: the wrap then lands on a smaller azimuth, so
            # the window stays conservative)
            cols = np.arange(n_az) if count >= n_az else np.arange(first, first + count) % n_az
            out.append((rows[:, None] * n_az + cols).ravel())
        return out

    def shadow_candidates(self, points: np.ndarray, sun: np.ndarray, cell: float = 1.0) -> list[np.ndarray]:
        """Rays from ``points`` towards the unit vector ``sun`` that may hit each object: the
        point lies inside the box's outline seen along the sun, and below its top. A grid of
        the outlines picks the few candidate points first, then each box takes the candidates
        of its slice of them sorted along one outline axis (testing every point against every
        box cost more than the rays)."""
        if len(self) == 0:
            return []
        e1 = np.cross(sun, [0.0, 0.0, 1.0] if abs(sun[2]) < 0.9 else [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        B = np.stack([e1, np.cross(sun, e1), sun])  # rows: outline coordinates, height
        C = self.corners @ B.T  # (K, 8, 3)
        lo, hi = C.min(1), C.max(1)
        g0 = lo[:, :2].min(0)
        shape = np.ceil((hi[:, :2].max(0) - g0) / cell).astype(int) + 1
        grid = np.zeros(shape + 2, bool)  # with an empty border for the points outside
        for (a0, b0), (a1, b1) in zip(((lo[:, :2] - g0) // cell).astype(int), ((hi[:, :2] - g0) // cell).astype(int)):
            grid[a0 + 1 : a1 + 2, b0 + 1 : b1 + 2] = True
        a = np.einsum("ij,j->i", points, B[0])
        b = np.einsum("ij,j->i", points, B[1])
        # cells by truncation after clipping into the border: a point up to a cell before the
        # grid may count as inside (a superset of the candidates is harmless)
        ia = np.clip((a - g0[0]) / cell, -1, shape[0]).astype(np.int64) + 1
        ib = np.clip((b - g0[1]) / cell, -1, shape[1]).astype(np.int64) + 1
        cand = np.flatnonzero(grid[ia, ib])
        order = np.argsort(a[cand])
        cand = cand[order]
        ac, bc, hc = a[cand], b[cand], np.einsum("ij,j->i", points[cand], B[2])
        start, end = np.searchsorted(ac, lo[:, 0], "left"), np.searchsorted(ac, hi[:, 0], "right")
        out = []
        for k in range(len(self)):
            s = slice(start[k], end[k])
            out.append(cand[s][(bc[s] >= lo[k, 1]) & (bc[s] <= hi[k, 1]) & (hc[s] < hi[k, 2])])
        return out
