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
        n: np.ndarray, fp: np.ndarray):
    p = table[agent]
    L, W, H, zb, x_ws, x_rw, x_rr, x_rf, r, ar, af, clear = (p[:, k] for k in range(12))
    paint = p[:, 12:15].astype(np.float32)
    x, y, z = X[:, 0], X[:, 1], X[:, 2]
    ay, ax = np.abs(n[:, 1]), n[:, 0]
    g = np.where(ay > 0.6, tex.grain.sample(x * 2, z * 2, fp),
                 np.where(np.abs(ax) > 0.6, tex.grain.sample(y * 2, z * 2, fp), tex.grain.sample(x * 2, y * 2, fp)))
    dirt = 0.65 + 0.35 * np.clip((z - clear) / 0.35, 0, 1)
    colour = paint * (g * dirt)[:, None]
    reflect = np.full(len(x), 0.35, np.float32)
    # wheels: black tyre, silver rim with five spokes on the outer face
    wheel = prim >= p[:, 15]
    xa = np.where(np.abs(x - af) < np.abs(x - ar), af, ar)
    d = np.hypot(x - xa, z - r)
    phi = np.arctan2(z - r, x - xa)
    rim = wheel * (ay > 0.5) * soft(0.62 * r - d, fp)
    spokes = np.maximum(soft((np.cos(5 * phi) - 0.2) * d * 0.3, fp), soft(0.18 * r - d, fp))
    colour = np.where(wheel[:, None], 0.035 * g[:, None], colour)
    colour = _mix(colour, (0.08 + 0.37 * spokes)[:, None] * g[:, None], rim)
    reflect = np.where(wheel, 0.1, reflect)
    body = (~wheel).astype(np.float32)
    # windows
    b_pillar = 0.5 * (x_rr + x_rf)
    glass = body * soft(z - zb - 0.04, fp) * soft(H - 0.05 - z, fp)
    glass *= soft(x - x_rw - 0.05, fp) * soft(x_ws - 0.05 - x, fp)
    glass *= 1 - (ay > 0.5) * soft(0.06 - np.abs(x - b_pillar), fp)
    sky_glint = 0.04 + 0.05 * np.clip(n[:, 2], 0, 1)
    colour = _mix(colour, (sky_glint * g)[:, None] * np.array([0.9, 1.0, 1.1], np.float32), glass)
    reflect = reflect * (1 - glass) + 0.03 * glass
    front = body * ((x > L / 2 - 0.15) & (ax > 0.5))
    rear = body * ((x < -L / 2 + 0.15) & (ax < -0.5))
    ends = front + rear
    # lights, plates, grille, bumpers
    band = rect(z - zb + 0.155, np.abs(y) - 0.74 * W / 2, 0.085, 0.19 * W / 2, fp)
    colour = _mix(colour, np.array([0.8, 0.78, 0.7], np.float32), front * band)
    colour = _mix(colour, np.array([0.55, 0.03, 0.02], np.float32), rear * band)
    plate = ends * rect(y, z - 0.36, 0.26, 0.06, fp)
    chars = np.clip((tex.letters.sample(y * 0.8 + hash01(agent) * 50, z * 0.8, fp) - 0.5) * 4 + 0.5, 0, 1)
    colour = _mix(colour, (0.8 - 0.75 * chars)[:, None] * np.ones(3, np.float32), plate)
    reflect = reflect * (1 - plate) + 0.95 * plate
    reflect = reflect * (1 - ends * band) + 0.8 * ends * band
    grille = front * rect(y, z - (clear + zb - 0.01) / 2, 0.45 * W / 2, (zb - clear - 0.51) / 2, fp)
    slats = stripes(z, 1 / 30, 0.45, fp)
    colour = _mix(colour, (0.03 + 0.09 * slats)[:, None] * np.ones(3, np.float32), grille)
    bumper = body * (1 - plate) * soft(clear + 0.2 - z, fp) * ((ay > 0.5) | (np.abs(ax) > 0.5))
    colour = colour * (1 - 0.65 * bumper)[:, None]
    # door seams and handles on the sides
    side = body * (ay > 0.6) * soft(z - clear - 0.08, fp) * soft(zb - z, fp)
    seam = np.zeros(len(x), np.float32)
    for xs in (x_ws - 0.03, b_pillar, x_rw + 0.12):
        seam = np.maximum(seam, coverage(np.abs(x - xs), 0.008, fp))
    handle = side * soft(0.025 - np.abs(z - zb + 0.1), fp) * np.maximum(
        soft(0.1 - np.abs(x - b_pillar + 0.3), fp), soft(0.1 - np.abs(x - x_rw - 0.45), fp))
    colour = colour * (1 - 0.8 * seam * side - 0.6 * handle)[:, None]
    return colour.astype(np.float32), reflect.astype(np.float32)


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
