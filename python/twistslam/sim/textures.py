"""Procedural texture images (tileable, generated from the seed) sampled with mip-mapping.

Every texture is a grey "detail" image around 1.0 that modulates a material's colour. It is
sampled in metres of the surface's own coordinates (street coordinates, facade coordinates,
object-frame coordinates), so a texture stays glued to its surface and moves with its object.
Mip levels are chosen from the pixel footprint on the surface: distant asphalt is averaged,
not aliased into flickering noise that would fool flow and stereo.
"""

from __future__ import annotations

import numpy as np


def fractal_noise(rng: np.random.Generator, size: int, beta: float) -> np.ndarray:
    """Periodic noise with power spectrum ~ 1/f^beta, zero mean, unit std, (size, size) float32."""
    white = rng.standard_normal((size, size))
    f = np.fft.fftfreq(size)
    r = np.hypot(f[:, None], f[None, :])
    r[0, 0] = 1.0
    spectrum = np.fft.fft2(white) / r ** (beta / 2)
    spectrum[0, 0] = 0.0
    img = np.real(np.fft.ifft2(spectrum))
    return (img / img.std()).astype(np.float32)


class MipTexture:
    """A tileable square grey image (power-of-two side) of ``texel`` metres per pixel, with its
    mip pyramid stored in one flat array so that a batch of samples at mixed levels is one
    vectorised gather (a loop over levels with masks cost several passes over the batch)."""

    def __init__(self, image: np.ndarray, texel: float) -> None:
        self.texel = texel
        self.levels = [np.ascontiguousarray(image, dtype=np.float32)]
        side = self.levels[0].shape[0]
        if self.levels[0].shape != (side, side) or side & (side - 1):
            raise ValueError(f"MipTexture: expected a square power-of-two image, got {image.shape}")
        while min(self.levels[-1].shape) > 2:
            a = self.levels[-1]
            self.levels.append(0.25 * (a[0::2, 0::2] + a[1::2, 0::2] + a[0::2, 1::2] + a[1::2, 1::2]))
        self._flat = np.concatenate([a.ravel() for a in self.levels])
        # int32 index arithmetic: half the memory traffic of int64, and the pyramid is small
        self._offset = np.cumsum([0] + [a.size for a in self.levels[:-1]]).astype(np.int32)
        self._side = np.array([a.shape[0] for a in self.levels], dtype=np.int32)
        # texel size of each level, computed as texel * 2**level like a per-level division would
        self._scale = np.array([texel * 2.0**k for k in range(len(self.levels))])

    def sample(self, u: np.ndarray, v: np.ndarray, footprint: np.ndarray) -> np.ndarray:
        """Values at surface coordinates ``u, v`` (m) for pixel footprints (m), bilinear
        within the mip level whose texel size is nearest to the footprint (in log scale).
        Coordinates must stay within +-2**31 texels (street coordinates are ~1e5)."""
        lod = np.log2(np.maximum(footprint, 1e-9) / self.texel).astype(np.float32)
        lod = np.clip(np.floor(lod + np.float32(0.5)), 0, len(self.levels) - 1).astype(np.intp)
        scale = self._scale[lod]
        x = u / scale - 0.5  # float64: coordinates reach 1e5 texels
        y = v / scale - 0.5
        x0 = np.floor(x)
        y0 = np.floor(y)
        fx = (x - x0).astype(np.float32)
        fy = (y - y0).astype(np.float32)
        side = self._side[lod]
        wrap = side - 1  # sides are powers of two: & wraps like a floor modulo, negatives too
        ix0 = x0.astype(np.int32) & wrap
        ix1 = (ix0 + 1) & wrap
        iy0 = y0.astype(np.int32) & wrap
        offset = self._offset[lod]
        row0 = offset + iy0 * side
        row1 = offset + ((iy0 + 1) & wrap) * side
        flat = self._flat
        top = flat[row0 + ix0] * (1 - fx) + flat[row0 + ix1] * fx
        bottom = flat[row1 + ix0] * (1 - fx) + flat[row1 + ix1] * fx
        return top * (1 - fy) + bottom * fy


def _cells(rng: np.random.Generator, size: int, cell_w: int, cell_h: int, mortar: int, stagger: bool,
           spread: float) -> np.ndarray:
    """Tiles (bricks, paving slabs): per-tile brightness, darker/lighter joints."""
    y, x = np.mgrid[0:size, 0:size]
    row = y // cell_h
    shift = (row % 2) * (cell_w // 2) if stagger else 0
    col = ((x + shift) % size) // cell_w
    n_cols = size // cell_w
    tint = 1.0 + spread * rng.standard_normal((size // cell_h + 1, n_cols + 1))
    img = tint[row, col]
    joint = ((y % cell_h) < mortar) | (((x + shift) % cell_w) < mortar)
    return np.where(joint, 0.0, img).astype(np.float32), joint


class TextureBank:
    """All textures of one sequence (built once from the seed: ~0.3 s)."""

    def __init__(self, rng: np.random.Generator) -> None:
        fine = fractal_noise(rng, 512, 0.6)
        medium = fractal_noise(rng, 512, 2.0)
        specks = (rng.uniform(size=(512, 512)) > 0.985).astype(np.float32)
        self.asphalt = MipTexture(1.0 + 0.16 * fine + 0.1 * medium + 0.5 * specks, 0.02)
        self.stain = MipTexture(1.0 + 0.13 * fractal_noise(rng, 256, 2.6), 0.4)
        slabs, joint = _cells(rng, 512, 32, 32, 1, False, 0.06)
        self.paving = MipTexture(np.where(joint, 0.55, slabs * (1 + 0.08 * fractal_noise(rng, 512, 1.0))), 0.01)
        bricks, joint = _cells(rng, 512, 32, 8, 1, True, 0.12)  # 32 cm x 8 cm bricks tile 512 px
        self.brick = MipTexture(np.where(joint, 1.45, bricks * (1 + 0.07 * fractal_noise(rng, 512, 0.8))), 0.01)
        self.plaster = MipTexture(1.0 + 0.07 * fractal_noise(rng, 256, 1.4) + 0.04 * fractal_noise(rng, 256, 0.5), 0.02)
        leaves = fractal_noise(rng, 512, 1.2)
        self.leaves = MipTexture(np.clip(1.0 + 0.45 * leaves, 0.2, 2.0), 0.015)
        self.grass = MipTexture(np.clip(1.0 + 0.3 * fractal_noise(rng, 512, 1.1), 0.3, 1.8), 0.02)
        self.grain = MipTexture(1.0 + 0.12 * fractal_noise(rng, 256, 1.0) + 0.08 * fractal_noise(rng, 256, 2.2), 0.01)
        clouds = fractal_noise(rng, 512, 3.0)
        self.clouds = MipTexture(np.clip(clouds - 0.3, 0, None) / 2.0, 12.0)
        self.letters = MipTexture((fractal_noise(rng, 256, 0.2) > 0.6).astype(np.float32), 0.03)
