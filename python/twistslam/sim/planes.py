"""A small analytic stereo scene: textured fronto-parallel rectangles.

Each pixel's ray is cast against the rectangles (the nearest hit wins), so every pixel's plane
and 3D point are known exactly. It tests and times the feature front end (ORB, stereo
matching) in a fraction of a second, without the full simulator:

>>> from twistslam import geometry                                   # doctest: +SKIP
>>> cam = geometry.StereoCamera.from_kitti(KITTI_P2, KITTI_P3, *KITTI_SIZE)   # doctest: +SKIP
>>> scene = PlaneScene.default()                                     # doctest: +SKIP
>>> left, ids = scene.render(cam, right=False, noise_seed=100)       # doctest: +SKIP
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import gaussian_filter, map_coordinates

# P2 / P3 of KITTI tracking sequence 0000 (training/calib/0000.txt) and its image size.
KITTI_P2 = np.array([[721.5377, 0, 609.5593, 44.85728], [0, 721.5377, 172.854, 0.2163791],
                     [0, 0, 1, 0.002745884]])
KITTI_P3 = np.array([[721.5377, 0, 609.5593, -339.5242], [0, 721.5377, 172.854, 2.199936],
                     [0, 0, 1, 0.002729905]])
KITTI_SIZE = (1242, 375)  # width, height


def texture(shape: tuple[int, int], seed: int) -> np.ndarray:
    """Float texture of mean 128 and std 40: blurred noise at three scales (corners at every
    scale of the ORB pyramid, no repetition that would fool stereo matching)."""
    rng = np.random.default_rng(seed)
    acc = np.zeros(shape)
    for sigma, weight in ((0.8, 0.6), (2.0, 0.8), (5.0, 1.0)):
        n = gaussian_filter(rng.normal(size=shape), sigma)
        acc += weight * n / n.std()
    return (acc - acc.mean()) * (40.0 / acc.std()) + 128.0


@dataclass
class Plane:
    """Textured rectangle x in [x0, x1], y in [y0, y1] at depth z of camera frame c (metres),
    ~1.3 image pixels per texel at focal length fx."""

    z: float
    x0: float
    y0: float
    x1: float
    y1: float
    seed: int
    fx: float = 721.5377
    texel: float = field(init=False)
    texture: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.texel = 1.3 * self.z / self.fx
        shape = (int(np.ceil((self.y1 - self.y0) / self.texel)) + 3,
                 int(np.ceil((self.x1 - self.x0) / self.texel)) + 3)
        self.texture = texture(shape, self.seed)


class PlaneScene:
    """Rectangles seen by a rectified stereo camera (``geometry.StereoCamera``)."""

    def __init__(self, planes: list[Plane]) -> None:
        self.planes = planes

    @classmethod
    def default(cls, fx: float = 721.5377) -> "PlaneScene":
        """A wall at 40 m filling the view, a panel at 15 m and one at 7 m in front of it
        (disparities ~10, ~26 and ~55 px on KITTI's rig, with occlusion edges)."""
        return cls([Plane(40.0, -40, -12, 40, 12, 1, fx), Plane(15.0, -1.0, -3.0, 6.0, 1.5, 2, fx),
                    Plane(7.0, -5.0, -2.0, -0.5, 1.2, 3, fx)])

    def cast(self, cam, offset, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nearest hit of the rays of pixels (u, v) of the image whose centre sits at
        ``-offset`` in frame c (``cam.t_left`` / ``cam.t_right``): plane index (-1: none) and
        the point X_c (..., 3)."""
        o = -np.asarray(offset, dtype=np.float64)
        d = np.stack([(u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, np.ones_like(u)], -1)
        best = np.full(u.shape, np.inf)
        ids = np.full(u.shape, -1)
        X = np.zeros(u.shape + (3,))
        for k, p in enumerate(self.planes):
            s = p.z - o[2]
            P = o + s * d
            inside = (P[..., 0] >= p.x0) & (P[..., 0] <= p.x1) & (P[..., 1] >= p.y0) & (P[..., 1] <= p.y1)
            take = inside & (s < best)
            best[take], ids[take], X[take] = s, k, P[take]
        return ids, X

    def render(self, cam, right: bool, noise_seed: int, size: tuple[int, int] = KITTI_SIZE
               ) -> tuple[np.ndarray, np.ndarray]:
        """``(H, W)`` uint8 image of the left or right camera with Gaussian noise of std 1 grey
        level, and the plane index of every pixel."""
        width, height = size
        v, u = np.mgrid[0:height, 0:width].astype(float)
        ids, X = self.cast(cam, cam.t_right if right else cam.t_left, u, v)
        img = np.zeros((height, width))
        for k, p in enumerate(self.planes):
            m = ids == k
            tx = 1.0 + (X[m, 0] - p.x0) / p.texel
            ty = 1.0 + (X[m, 1] - p.y0) / p.texel
            img[m] = map_coordinates(p.texture, [ty, tx], order=1)
        img += np.random.default_rng(noise_seed).normal(0, 1.0, img.shape)
        return np.clip(np.rint(img), 0, 255).astype(np.uint8), ids
