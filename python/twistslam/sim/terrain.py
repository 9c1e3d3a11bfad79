"""Smooth height field ``z = h(x, y)`` of the map: the reason the road is not one plane.

Map frame ``m``: x, y horizontal, z up, metres. Everything (road, sidewalks, buildings,
cars) stands on this surface, so cars drive up and down small slopes and the camera's
road plane changes along the sequence.
"""

from __future__ import annotations

import numpy as np


class Terrain:
    """Sum of three long sine waves; grades stay below ``2 pi A / wavelength`` (~2 %)."""

    def __init__(self, rng: np.random.Generator, amplitude: float, wavelength: float) -> None:
        self.amplitude = amplitude
        angles = rng.uniform(0, np.pi, 3)
        scales = np.array([1.0, 0.7, 1.6])  # wavelengths relative to the nominal one
        self.k = (2 * np.pi / (wavelength * scales))[:, None] * np.stack([np.cos(angles), np.sin(angles)], -1)
        self.phase = rng.uniform(0, 2 * np.pi, 3)
        self.weight = amplitude * np.array([0.6, 0.25, 0.15])
        # so that the map origin (the ego start) is at height 0
        self.offset = 0.0
        self.offset = float(self.height(np.zeros((1, 2)))[0])

    def height(self, xy: np.ndarray) -> np.ndarray:
        """Heights (N,) at map points (N, 2)."""
        arg = np.asarray(xy, dtype=np.float64) @ self.k.T + self.phase
        return np.sin(arg) @ self.weight - self.offset

    def gradient(self, xy: np.ndarray) -> np.ndarray:
        """(dh/dx, dh/dy) (N, 2)."""
        arg = np.asarray(xy, dtype=np.float64) @ self.k.T + self.phase
        return (np.cos(arg) * self.weight) @ self.k

    def normal(self, xy: np.ndarray) -> np.ndarray:
        """Unit up-normals (N, 3)."""
        g = self.gradient(xy)
        n = np.concatenate([-g, np.ones((len(g), 1))], axis=1)
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def lift(self, xy: np.ndarray, dz: float | np.ndarray = 0.0) -> np.ndarray:
        """3D points (N, 3) on the surface (plus ``dz``) above map points (N, 2)."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        return np.concatenate([xy, (self.height(xy) + dz)[:, None]], axis=1)
