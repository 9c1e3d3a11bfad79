"""Albedo (linear RGB) and LiDAR reflectivity of the static surfaces at hit points.

Each function takes the hits of one material group and returns ``(albedo (N, 3) float32,
reflectivity (N,) float32)``. Patterns are computed from the surface's own coordinates
(street ``s, lat``; facade ``u, v``; map ``x, y, z`` for things that never move), and thin
features (lane lines, window frames) are anti-aliased by their coverage of the pixel
footprint ``fp`` (metres on the surface).
"""

from __future__ import annotations

import numpy as np

from .road import StreetNetwork
from .textures import TextureBank


def hash01(*keys: np.ndarray) -> np.ndarray:
    """Deterministic pseudo-random numbers in [0, 1) from integer keys (vectorised)."""
    h = np.zeros(np.broadcast(*keys).shape, dtype=np.uint64)
    for k, prime in zip(keys, (73856093, 19349663, 83492791, 2654435761)):
        h ^= np.asarray(k).astype(np.int64).astype(np.uint64) * np.uint64(prime)
        h = (h ^ (h >> np.uint64(13))) * np.uint64(0x5BD1E995)
    return ((h >> np.uint64(11)) % np.uint64(1 << 20)).astype(np.float64) / float(1 << 20)


def coverage(distance: np.ndarray, half_width: float, fp: np.ndarray) -> np.ndarray:
    """Fraction of a pixel covered by a line of ``half_width`` at ``distance`` from its axis."""
    return np.clip((half_width - distance) / np.maximum(fp, 1e-6) + 0.5, 0.0, 1.0).astype(np.float32)


def soft(signed_distance: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """Pixel coverage of the region where ``signed_distance`` (m) > 0: a box-filtered edge,
    so procedural edges land at sub-pixel positions consistently in both stereo views."""
    return np.clip(signed_distance / np.maximum(fp, 1e-6) + 0.5, 0.0, 1.0).astype(np.float32)


def rect(du: np.ndarray, dv: np.ndarray, half_u, half_v, fp: np.ndarray) -> np.ndarray:
    """Coverage of an axis-aligned rectangle of half sizes ``half_u, half_v`` at offsets du, dv."""
    return soft(half_u - np.abs(du), fp) * soft(half_v - np.abs(dv), fp)


def stripes(x: np.ndarray, period: float, duty: float, fp: np.ndarray) -> np.ndarray:
    """Coverage of periodic stripes (``duty`` of each ``period`` metres), fading to their
    mean once the footprint approaches the period (no moire)."""
    d = np.abs((x / period) % 1.0 - duty / 2) * period
    value = soft(duty * period / 2 - d, fp)
    fade = np.clip(fp / period * 2 - 0.5, 0, 1).astype(np.float32)
    return value * (1 - fade) + duty * fade


def _mix(a: np.ndarray, b, w: np.ndarray) -> np.ndarray:
    return a * (1 - w[:, None]) + b * w[:, None]


def road(tex: TextureBank, net: StreetNetwork, attrs: np.ndarray, fp: np.ndarray, colour: bool = True):
    s, lat, sid = attrs[:, 0].astype(np.float64), attrs[:, 1].astype(np.float64), np.rint(attrs[:, 2])
    paint = np.zeros(len(s), dtype=np.float32)
    for st in net.streets:
        m = sid == st.index
        if not m.any():
            continue
        ss, aa, f = s[m], np.abs(lat[m]), fp[m]
        p = np.zeros(len(ss), dtype=np.float32)
        dashed = stripes(ss, 9.0, 1.0 / 3.0, f)
        if st.median > 0:
            p = np.maximum(p, coverage(np.abs(aa - st.median / 2 - 0.2), 0.08, f))
        elif st.lanes == 1:
            p = np.maximum(p, coverage(aa, 0.06, f) * dashed)
        else:
            p = np.maximum(p, coverage(np.abs(aa - 0.12), 0.06, f))
        for k in range(1, st.lanes):
            p = np.maximum(p, coverage(np.abs(aa - st.median / 2 - k * st.lane_width), 0.07, f) * dashed)
        edge = st.median / 2 + st.lanes * st.lane_width
        p = np.maximum(p, coverage(np.abs(aa - edge), 0.08 if st.parking == 0 else 0.06, f))
        if st.s_cross is not None:
            d = np.abs(ss - st.s_cross)
            p = p * soft(d - st.cross_half, f)  # no lines inside the intersection
            zebra = soft(1.5 - np.abs(d - st.cross_half - 2.5), f) * soft(edge - aa, f)
            p = p * (1 - zebra) + stripes(lat[m], 1.0, 0.5, f) * zebra
        paint[m] = p
    reflect = (0.15 + 0.55 * paint).astype(np.float32)
    if not colour:
        return None, reflect
    grain = tex.asphalt.sample(s, lat, fp) * tex.stain.sample(s, lat, fp)
    out = (0.085 * grain)[:, None] * np.array([1.0, 1.0, 1.05], dtype=np.float32)
    k = np.flatnonzero(paint > 0)  # worn white paint, only where there are lines
    wear = np.clip(tex.stain.sample(s[k] * 3.1, lat[k] * 3.1, fp[k]), 0.7, 1.1)
    out[k] = _mix(out[k], (0.62 * wear)[:, None] * np.ones(3, dtype=np.float32), 0.95 * paint[k])
    return out.astype(np.float32), reflect


def sidewalk(tex: TextureBank, attrs: np.ndarray, fp: np.ndarray, curb: float):
    s, lat, dz = attrs[:, 0].astype(np.float64), attrs[:, 1].astype(np.float64), attrs[:, 3]
    top = (tex.paving.sample(s, lat, fp) * 0.3)[:, None] * np.array([1.0, 0.97, 0.92], dtype=np.float32)
    face = (tex.grain.sample(s, dz * 4.0, fp) * 0.42)[:, None] * np.ones(3, dtype=np.float32)
    is_face = dz < curb - 0.01
    return np.where(is_face[:, None], face, top).astype(np.float32), np.full(len(s), 0.25, np.float32)


def terrain(tex: TextureBank, P: np.ndarray, fp: np.ndarray):
    g = tex.grass.sample(P[:, 0], P[:, 1], fp)
    dirt = np.clip((tex.stain.sample(P[:, 0] * 0.7, P[:, 1] * 0.7, fp) - 1.0) * 8 + 0.5, 0, 1)
    colour = _mix(np.array([0.06, 0.11, 0.03], np.float32)[None] * g[:, None],
                  np.array([0.13, 0.1, 0.07], np.float32)[None] * g[:, None], dirt)
    return colour.astype(np.float32), np.full(len(g), 0.35, np.float32)


SIGN_PALETTE = np.array([[0.6, 0.05, 0.04], [0.05, 0.15, 0.5], [0.7, 0.55, 0.05], [0.05, 0.35, 0.12],
                         [0.65, 0.65, 0.65], [0.45, 0.05, 0.35]], np.float32)


def roof(tex: TextureBank, attrs: np.ndarray, fp: np.ndarray):
    g = tex.grain.sample(attrs[:, 0], attrs[:, 1], fp) * tex.stain.sample(attrs[:, 0], attrs[:, 1], fp)
    return (0.14 * g)[:, None] * np.array([1.0, 0.97, 0.95], np.float32), np.full(len(g), 0.2, np.float32)


def trunk(tex: TextureBank, P: np.ndarray, fp: np.ndarray):
    g = tex.grain.sample((P[:, 0] + P[:, 1]) * 3.0, P[:, 2] * 0.5, fp)
    return (g[:, None] * np.array([0.12, 0.08, 0.05], np.float32)), np.full(len(g), 0.3, np.float32)


def canopy(tex: TextureBank, P: np.ndarray, fp: np.ndarray):
    u = 0.8 * P[:, 0] + 0.6 * P[:, 1]
    v = P[:, 2] + 0.3 * (0.8 * P[:, 1] - 0.6 * P[:, 0])
    g = tex.leaves.sample(u, v, fp)
    hue = tex.stain.sample(P[:, 0] * 5, P[:, 1] * 5, fp)
    colour = g[:, None] * np.array([0.05, 0.11, 0.03], np.float32) * np.stack([hue, np.ones_like(hue), 2 - hue], -1)
    return colour.astype(np.float32), np.full(len(g), 0.45, np.float32)


def metal(tex: TextureBank, P: np.ndarray, fp: np.ndarray, grey: float):
    g = tex.grain.sample(P[:, 0] + P[:, 1], P[:, 2], fp)
    return (grey * g)[:, None] * np.ones(3, np.float32), np.full(len(g), 0.5, np.float32)


def sign(tex: TextureBank, attrs: np.ndarray, fp: np.ndarray):
    u, v, k = attrs[:, 0], attrs[:, 1], np.rint(attrs[:, 2]).astype(np.int64)
    colour = SIGN_PALETTE[(hash01(k, 7) * len(SIGN_PALETTE)).astype(int)]
    inner = rect(u - 0.35, v - 0.35, 0.29, 0.29, fp)
    symbol = np.clip((tex.letters.sample(u * 0.6 + k, v * 0.6, fp) - 0.5) * 4 + 0.5, 0, 1)
    colour = _mix(colour, np.float32(0.8), np.maximum(1 - inner, symbol))
    return colour.astype(np.float32), np.full(len(u), 0.9, np.float32)  # retro-reflective
