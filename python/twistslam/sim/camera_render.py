"""Stereo camera images by ray casting: a ray per pixel centre (or an s x s grid per pixel
with supersampling), Lambertian shading under a sun and sky, cast shadows, a cloudy sky,
then exposure, gamma and sensor noise into 8-bit RGB."""

from __future__ import annotations

import numpy as np

from .mesh import rotate
from .objects import MovingObjects
from .raycast import cast, occluded
from .shading import surface
from .world import World

SHADOW_BIAS = 0.03  # m; shadow rays start this far off the surface (no self-shadowing acne)
SKY_HORIZON = np.array([0.62, 0.68, 0.74], np.float32)
SKY_ZENITH = np.array([0.22, 0.36, 0.66], np.float32)


class Camera:
    """One rectified camera of the rig: projection ``P`` (3x4) of reference-frame points."""

    def __init__(self, P: np.ndarray, width: int, height: int) -> None:
        self.P = P
        self.K_inv = np.linalg.inv(P[:, :3])
        self.centre = -self.K_inv @ P[:, 3]  # camera centre in the reference frame c
        self.f = float(P[0, 0])
        self.width, self.height = width, height
        self._centre_dirs: np.ndarray | None = None
        self._centre_dirs32: np.ndarray | None = None
        self._centres: np.ndarray | None = None
        self._projected: dict[bytes, np.ndarray] = {}

    def directions(self, offset: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
        """Unit ray directions (H*W, 3) in frame c through pixel centres + ``offset`` (px)."""
        if offset == (0.0, 0.0):
            if self._centre_dirs is None:
                self._centre_dirs = self._directions(offset)
            return self._centre_dirs
        return self._directions(offset)

    def map_rays(self, T_m_c: np.ndarray, offset: tuple[float, float] = (0.0, 0.0)
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Origin (3,) and unit directions (H*W, 3) float32 of the pixel rays in the map frame
        for camera pose ``T_m_c``. The ray caster takes float32: rotating in float64 only to
        round afterwards cost twice as much (0.01 s per image)."""
        if offset == (0.0, 0.0):
            if self._centre_dirs32 is None:
                self._centre_dirs32 = self.directions().astype(np.float32)
            d = self._centre_dirs32
        else:
            d = self._directions(offset).astype(np.float32)
        R = T_m_c[:3, :3]
        return R @ self.centre + T_m_c[:3, 3], rotate(d, R.astype(np.float32))

    def _directions(self, offset: tuple[float, float]) -> np.ndarray:
        v, u = np.mgrid[0 : self.height, 0 : self.width].astype(np.float64)
        pix = np.stack([u.ravel() + offset[0], v.ravel() + offset[1], np.ones(u.size)], -1)
        d = rotate(pix, self.K_inv)
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    def projected_directions(self, P: np.ndarray) -> np.ndarray:
        """(H*W, 3) ``P[:, :3] d`` of the unit pixel-centre rays ``d`` (computed once per ``P``)."""
        key = P.tobytes()
        if key not in self._projected:
            self._projected[key] = rotate(self.directions(), P[:, :3])
        return self._projected[key]

    def pixel_centres(self) -> np.ndarray:
        """(H*W, 2) float64 ``u, v`` of every pixel centre, row by row (computed once)."""
        if self._centres is None:
            v, u = np.divmod(np.arange(self.height * self.width), self.width)
            self._centres = np.stack([u, v], -1).astype(np.float64)
        return self._centres

    def project_map(self, X_m: np.ndarray, T_m_c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`project` of map-frame points seen from camera pose ``T_m_c``, with the frame
        change folded into the projection (one pass over the points instead of two)."""
        A = self.P[:, :3] @ T_m_c[:3, :3].T
        x = rotate(X_m, A) + (self.P[:, 3] - A @ T_m_c[:3, 3])
        return x[:, :2] / x[:, 2:3], x[:, 2]

    def project(self, X_c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (N, 2) and depth along the optical axis (N,) of points in c."""
        x = rotate(X_c, self.P[:, :3]) + self.P[:, 3]
        return x[:, :2] / x[:, 2:3], x[:, 2]


def sky(world: World, dirs: np.ndarray) -> np.ndarray:
    """Sky radiance (N, 3) for map-frame directions: gradient plus clouds on a far plane."""
    up = dirs[:, 2]
    w = np.clip(up * 2.5, 0, 1) ** 0.7
    colour = SKY_HORIZON * (1 - w[:, None]) + SKY_ZENITH * w[:, None]
    h = np.maximum(up, 0.03)
    u, v = dirs[:, 0] / h * 800.0, dirs[:, 1] / h * 800.0
    fp = 800.0 / h / world.calib.P2[0, 0] / h
    c = np.clip(world.textures.clouds.sample(u, v, fp), 0, 1)[:, None]
    return (colour * (1 - c) + 0.9 * c).astype(np.float32)


def radiance(world: World, objects: MovingObjects, n: int, origins: np.ndarray, dirs: np.ndarray, f: float,
             candidates: list[np.ndarray]):
    """Linear radiance (N, 3) of rays, and their hits (``candidates``: see :func:`cast`)."""
    hits = cast(world.static_scene, objects, origins, dirs, candidates)
    hit = np.isfinite(hits.t)
    # nearly every ray hits something: shade all of them (misses have no material group and
    # get a zero albedo) rather than copying the hits' fields into a subset first
    cos = np.abs(np.einsum("ij,ij->i", hits.normal, dirs))
    with np.errstate(invalid="ignore"):  # misses: inf / cos
        fp = hits.t / f / np.maximum(cos, 0.08)  # isotropic mip: blur along the foreshortened axis
    albedo, _ = surface(world, hits, n, fp)
    light = world.cfg.light
    ambient = light.ambient * (0.7 + 0.3 * hits.normal[:, 2])
    ndotl = np.maximum(np.einsum("ij,j->i", hits.normal, world.sun.astype(np.float32)), np.float32(0.0))
    ndotl[~hit] = 0.0
    lit = np.flatnonzero(ndotl > 0)
    if light.shadows and len(lit):
        start = hits.point[lit] + SHADOW_BIAS * hits.normal[lit]
        shadow = occluded(world.static_scene, objects, start, np.broadcast_to(world.sun, (len(lit), 3)), 400.0,
                          objects.shadow_candidates(start, world.sun))
        ndotl[lit[shadow]] = 0.0
    out = albedo * (ambient + np.float32(light.sun_intensity) * ndotl)[:, None]
    miss = np.flatnonzero(~hit)
    out[miss] = sky(world, dirs[miss])
    return out, hits


def render(world: World, camera: Camera, objects: MovingObjects, n: int, rng: np.random.Generator):
    """8-bit RGB image (H, W, 3) and the hits of the pixel-centre rays."""
    cfg = world.cfg.camera
    ss = max(1, int(cfg.supersample))
    origin, centre_dirs = camera.map_rays(world.T_m_c[n])
    origins = np.broadcast_to(origin, centre_dirs.shape)
    # the pixels whose rays may hit each moving object (with a pixel of margin: sub-pixel
    # offsets of supersampling stay inside)
    candidates = objects.pixel_candidates(camera.P, world.T_m_c[n], camera.width, camera.height)
    if ss == 1:
        L, hits = radiance(world, objects, n, origins, centre_dirs, camera.f, candidates)
    else:
        hits = cast(world.static_scene, objects, origins, centre_dirs, candidates)
        L = np.zeros((len(centre_dirs), 3), np.float32)
        for k in range(ss * ss):
            off = ((k % ss + 0.5) / ss - 0.5, (k // ss + 0.5) / ss - 0.5)
            d = camera.map_rays(world.T_m_c[n], off)[1]
            L += radiance(world, objects, n, origins, d, camera.f, candidates)[0]
        L /= ss * ss
    value = np.power(np.clip(L * np.float32(cfg.exposure), 0, 1), np.float32(1.0 / cfg.gamma)) * np.float32(255.0)
    value += rng.standard_normal(value.shape, dtype=np.float32) * np.float32(cfg.noise_std)
    image = np.clip(np.rint(value), 0, 255).astype(np.uint8)
    return image.reshape(camera.height, camera.width, 3), hits
