"""Stereo camera images by ray casting: a ray per pixel centre (or an s x s grid per pixel
with supersampling), Lambertian shading under a sun and sky, cast shadows, a cloudy sky,
then exposure, gamma and sensor noise into 8-bit RGB."""

from __future__ import annotations

import numpy as np

from .mesh import rotate
from .raycast import ObjectScene, cast, occluded
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

    def directions(self, offset: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
        """Unit ray directions (H*W, 3) in frame c through pixel centres + ``offset`` (px)."""
        if offset == (0.0, 0.0):
            if self._centre_dirs is None:
                self._centre_dirs = self._directions(offset)
            return self._centre_dirs
        return self._directions(offset)

    def _directions(self, offset: tuple[float, float]) -> np.ndarray:
        v, u = np.mgrid[0 : self.height, 0 : self.width].astype(np.float64)
        pix = np.stack([u.ravel() + offset[0], v.ravel() + offset[1], np.ones(u.size)], -1)
        d = rotate(pix, self.K_inv)
        return d / np.linalg.norm(d, axis=1, keepdims=True)

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


def radiance(world: World, objects: list[ObjectScene], n: int, origins: np.ndarray, dirs: np.ndarray, f: float):
    """Linear radiance (N, 3) of rays, and their hits."""
    hits = cast(world.static_scene, objects, origins, dirs)
    hit = np.isfinite(hits.t)
    out = np.empty((len(dirs), 3), np.float32)
    out[~hit] = sky(world, dirs[~hit])
    sub = hits.select(hit)
    cos = np.abs(np.einsum("ij,ij->i", sub.normal, dirs[hit]))
    fp = sub.t / f / np.maximum(cos, 0.08)  # isotropic mip: blur along the foreshortened axis
    albedo, _ = surface(world, sub, n, fp)
    light = world.cfg.light
    ambient = light.ambient * (0.7 + 0.3 * sub.normal[:, 2])
    ndotl = np.maximum(np.einsum("ij,j->i", sub.normal, world.sun), 0.0)
    lit = ndotl > 0
    if light.shadows and lit.any():
        shadow = occluded(world.static_scene, objects, sub.point[lit] + SHADOW_BIAS * sub.normal[lit],
                          np.broadcast_to(world.sun, (int(lit.sum()), 3)).copy(), 400.0)
        ndotl[np.flatnonzero(lit)[shadow]] = 0.0
    out[hit] = albedo * (ambient + light.sun_intensity * ndotl).astype(np.float32)[:, None]
    return out, hits


def render(world: World, camera: Camera, objects: list[ObjectScene], n: int, rng: np.random.Generator):
    """8-bit RGB image (H, W, 3) and the hits of the pixel-centre rays."""
    cfg = world.cfg.camera
    T = world.T_m_c[n]
    origin = T[:3, :3] @ camera.centre + T[:3, 3]
    ss = max(1, int(cfg.supersample))
    centre_dirs = rotate(camera.directions(), T[:3, :3])
    origins = np.broadcast_to(origin, centre_dirs.shape)
    if ss == 1:
        L, hits = radiance(world, objects, n, origins, centre_dirs, camera.f)
    else:
        hits = cast(world.static_scene, objects, origins, centre_dirs)
        L = np.zeros((len(centre_dirs), 3), np.float32)
        for k in range(ss * ss):
            off = ((k % ss + 0.5) / ss - 0.5, (k // ss + 0.5) / ss - 0.5)
            d = rotate(camera.directions(off), T[:3, :3])
            L += radiance(world, objects, n, origins, d, camera.f)[0]
        L /= ss * ss
    value = np.power(np.clip(L * np.float32(cfg.exposure), 0, 1), np.float32(1.0 / cfg.gamma)) * np.float32(255.0)
    value += rng.standard_normal(value.shape, dtype=np.float32) * np.float32(cfg.noise_std)
    image = np.clip(np.rint(value), 0, 255).astype(np.uint8)
    return image.reshape(camera.height, camera.width, 3), hits
