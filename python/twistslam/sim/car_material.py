"""Albedo and reflectivity of cars and pedestrians, from hit points in their vehicle frame
(x forward, y left, z up, ground at z = 0): the paint, windows, lights, plates and seams
are glued to the object and move with it."""

from __future__ import annotations

import numpy as np

from .car_mesh import CarShape
from .materials import _mix, coverage, hash01, rect, soft, stripes
from .person_mesh import HIP, SHOULDER
from .textures import TextureBank

#: columns of the per-agent table used here
CAR_COLUMNS = ("L", "W", "H", "z_belt", "x_ws", "x_rw", "x_rr", "x_rf", "r", "axle_r", "axle_f",
               "clear", "red", "green", "blue", "n_body")


def car_row(shape: CarShape, colour: np.ndarray, n_body: int) -> list[float]:
    xr, xf = shape.x_roof
    return [shape.length, shape.width, shape.height, shape.z_belt, shape.x_windshield, shape.x_rear_window,
            xr, xf, shape.wheel_radius, *shape.axles, shape.clearance, *colour, n_body]


def car(tex: TextureBank, table: np.ndarray, agent: np.ndarray, prim: np.ndarray, X: np.ndarray,
        n: np.ndarray, fp: np.ndarray, colour: bool = True):
    """Albedo (None unless ``colour``) and reflectivity of car hits at vehicle-frame points ``X``
    with normals ``n``. Each detail (windows, lights, plates, seams) is a coverage that is
    exactly zero away from it, so it is evaluated only on the hits near it, in the same order."""
    p = table[agent]
    L, W, H, zb, x_ws, x_rw, x_rr, x_rf, r, ar, af, clear = (p[:, k] for k in range(12))
    x, y, z = X[:, 0], X[:, 1], X[:, 2]
    ay, ax = np.abs(n[:, 1]), n[:, 0]
    margin = np.maximum(fp, 1e-6)  # a coverage is zero beyond half a footprint off its edge
    wheel = prim >= p[:, 15]
    body = ~wheel
    b_pillar = 0.5 * (x_rr + x_rf)
    # windows
    gl = np.flatnonzero(body & (z > zb + 0.04 - margin) & (z < H - 0.05 + margin) & (x > x_rw + 0.05 - margin)
                        & (x < x_ws - 0.05 + margin))
    xg, zg, fg = x[gl], z[gl], fp[gl]
    glass = soft(zg - zb[gl] - 0.04, fg) * soft(H[gl] - 0.05 - zg, fg)
    glass *= soft(xg - x_rw[gl] - 0.05, fg) * soft(x_ws[gl] - 0.05 - xg, fg)
    glass *= 1 - (ay[gl] > 0.5) * soft(0.06 - np.abs(xg - b_pillar[gl]), fg)
    # lights, plates, grille, bumpers on the front and rear faces
    is_front = body & (x > L / 2 - 0.15) & (ax > 0.5)
    e = np.flatnonzero(is_front | (body & (x < -L / 2 + 0.15) & (ax < -0.5)))
    front = is_front[e]
    ye, ze, fe = y[e], z[e], fp[e]
    band = rect(ze - zb[e] + 0.155, np.abs(ye) - 0.74 * W[e] / 2, 0.085, 0.19 * W[e] / 2, fe)
    plate = rect(ye, ze - 0.36, 0.26, 0.06, fe)
    reflect = np.where(wheel, np.float32(0.1), np.float32(0.35))
    reflect[gl] = reflect[gl] * (1 - glass) + 0.03 * glass
    reflect[e] = reflect[e] * (1 - plate) + 0.95 * plate
    reflect[e] = reflect[e] * (1 - band) + 0.8 * band
    if not colour:
        return None, reflect

    g = np.empty(len(x), np.float32)  # grain projected along the dominant axis of the normal
    k = np.flatnonzero(ay > 0.6)
    g[k] = tex.grain.sample(x[k] * 2, z[k] * 2, fp[k])
    k = np.flatnonzero((ay <= 0.6) & (np.abs(ax) > 0.6))
    g[k] = tex.grain.sample(y[k] * 2, z[k] * 2, fp[k])
    k = np.flatnonzero((ay <= 0.6) & (np.abs(ax) <= 0.6))
    g[k] = tex.grain.sample(x[k] * 2, y[k] * 2, fp[k])
    dirt = 0.65 + 0.35 * np.clip((z - clear) / 0.35, 0, 1)
    out = p[:, 12:15].astype(np.float32) * (g * dirt)[:, None]
    # wheels: black tyre, silver rim with five spokes on the outer face
    w = np.flatnonzero(wheel)
    xw, zw, rw = x[w], z[w], r[w]
    xa = np.where(np.abs(xw - af[w]) < np.abs(xw - ar[w]), af[w], ar[w])
    d = np.hypot(xw - xa, zw - rw)
    phi = np.arctan2(zw - rw, xw - xa)
    rim = (ay[w] > 0.5) * soft(0.62 * rw - d, fp[w])
    spokes = np.maximum(soft((np.cos(5 * phi) - 0.2) * d * 0.3, fp[w]), soft(0.18 * rw - d, fp[w]))
    out[w] = _mix(0.035 * g[w, None], (0.08 + 0.37 * spokes)[:, None] * g[w, None], rim)
    sky_glint = 0.04 + 0.05 * np.clip(n[gl, 2], 0, 1)
    out[gl] = _mix(out[gl], (sky_glint * g[gl])[:, None] * np.array([0.9, 1.0, 1.1], np.float32), glass)
    c = out[e]
    c = _mix(c, np.array([0.8, 0.78, 0.7], np.float32), front * band)
    c = _mix(c, np.array([0.55, 0.03, 0.02], np.float32), ~front * band)
    chars = np.clip((tex.letters.sample(ye * 0.8 + hash01(agent[e]) * 50, ze * 0.8, fe) - 0.5) * 4 + 0.5, 0, 1)
    c = _mix(c, (0.8 - 0.75 * chars)[:, None] * np.ones(3, np.float32), plate)
    grille = front * rect(ye, ze - (clear[e] + zb[e] - 0.01) / 2, 0.45 * W[e] / 2, (zb[e] - clear[e] - 0.51) / 2, fe)
    out[e] = _mix(c, (0.03 + 0.09 * stripes(ze, 1 / 30, 0.45, fe))[:, None] * np.ones(3, np.float32), grille)
    k = np.flatnonzero(body & (z < clear + 0.2 + margin) & ((ay > 0.5) | (np.abs(ax) > 0.5)))
    plate_k = np.zeros(len(x), np.float32)
    plate_k[e] = plate
    bumper = (1 - plate_k[k]) * soft(clear[k] + 0.2 - z[k], fp[k])
    out[k] *= (1 - 0.65 * bumper)[:, None]
    # door seams and handles on the sides
    k = np.flatnonzero(body & (ay > 0.6) & (z > clear + 0.08 - margin) & (z < zb + margin))
    xk, zk, fk, bp = x[k], z[k], fp[k], b_pillar[k]
    side = soft(zk - clear[k] - 0.08, fk) * soft(zb[k] - zk, fk)
    seam = np.zeros(len(k), np.float32)
    for xs in (x_ws[k] - 0.03, bp, x_rw[k] + 0.12):
        seam = np.maximum(seam, coverage(np.abs(xk - xs), 0.008, fk))
    handle = side * soft(0.025 - np.abs(zk - zb[k] + 0.1), fk) * np.maximum(
        soft(0.1 - np.abs(xk - bp + 0.3), fk), soft(0.1 - np.abs(xk - x_rw[k] - 0.45), fk))
    out[k] *= (1 - 0.8 * seam * side - 0.6 * handle)[:, None]
    return out.astype(np.float32), reflect


def person(tex: TextureBank, heights: np.ndarray, colours: np.ndarray, agent: np.ndarray, X: np.ndarray,
           fp: np.ndarray):
    h = heights[agent]
    shirt = colours[agent].astype(np.float32)
    trousers = shirt[:, ::-1] * 0.35
    skin = np.array([0.5, 0.34, 0.26], np.float32)
    hair = np.array([0.06, 0.04, 0.03], np.float32)
    z = X[:, 2] / h
    g = tex.grain.sample(X[:, 0] * 2 + X[:, 1] * 2, X[:, 2] * 2, fp)[:, None]
    colour = _mix(shirt, trousers, soft((HIP - z) * h, fp))
    colour = _mix(colour, skin, soft((z - SHOULDER) * h, fp))
    colour = _mix(colour, hair, np.maximum(soft((z - 0.95) * h, fp), soft((z - 0.9) * h, fp) * soft(-X[:, 0], fp)))
    return (colour * g).astype(np.float32), np.full(len(z), 0.3, np.float32)
