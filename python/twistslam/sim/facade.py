"""Building facades: plaster or brick walls, upper-floor windows (frame, sill, cross bar, glass,
curtains) and ground-floor shop windows with a sign band, or doors.

Every feature is a box-filtered coverage that is exactly zero away from it, so each one is
evaluated only on the hits near it (the window rectangle of their floor and column, the
ground floor of shops...): mixing with a zero weight would leave the colour unchanged, and
evaluating every feature on every wall hit cost most of the shading time.
"""

from __future__ import annotations

import numpy as np

from .materials import SIGN_PALETTE, _mix, hash01, rect, soft
from .textures import TextureBank

WALL_PALETTE = np.array([[0.55, 0.5, 0.4], [0.38, 0.38, 0.37], [0.6, 0.5, 0.3], [0.4, 0.45, 0.5],
                         [0.55, 0.4, 0.36], [0.65, 0.64, 0.6], [0.5, 0.33, 0.22], [0.3, 0.3, 0.34]], np.float32)
BRICK = np.array([0.36, 0.15, 0.09], np.float32)


def _base_colours(params: np.ndarray) -> np.ndarray:
    """(B, 3) float32 wall colour of each building: a palette plaster colour or brick."""
    hue, brick = params[:, 4], params[:, 5] > 0.5
    base = WALL_PALETTE[(hue * len(WALL_PALETTE)).astype(int) % len(WALL_PALETTE)]
    return np.where(brick[:, None], BRICK * (0.8 + 0.4 * hue[:, None]), base).astype(np.float32)


def wall(tex: TextureBank, params: np.ndarray, attrs: np.ndarray, fp: np.ndarray, colour: bool = True):
    """Albedo (N, 3) (None unless ``colour``) and reflectivity (N,) of wall hits with facade
    coordinates ``attrs[:, :2]`` (m) on building ``attrs[:, 2]``."""
    u, v, b = attrs[:, 0].astype(np.float64), attrs[:, 1].astype(np.float64), np.rint(attrs[:, 2]).astype(np.int64)
    fh, pitch, ww, wh, hue, brick, shop, seed = params[b].T
    margin = np.maximum(fp, 1e-6)  # a coverage is zero beyond half a footprint off its edge
    floor = np.floor(v / fh)
    fv = v - floor * fh
    col = np.floor(u / pitch)
    fu = u - (col + 0.5) * pitch
    upper = floor >= 1
    # upper floors: windows with frame, sill and a cross bar, glass of varying darkness
    # (index sets are narrowed step by step: each test then runs on fewer hits)
    w = np.flatnonzero(upper)
    w = w[np.abs(fu[w]) < ww[w] / 2 + 0.08 + margin[w]]
    w = w[(fv[w] > 0.8 - margin[w]) & (fv[w] < 0.9 + wh[w] + margin[w])]
    fu_w, fv_w, wh_w, ww_w, f_w = fu[w], fv[w], wh[w], ww[w], fp[w]
    centre_v = fv_w - 0.9 - wh_w / 2
    win = rect(fu_w, centre_v, ww_w / 2, wh_w / 2, f_w)
    pane = win * rect(fu_w, centre_v, ww_w / 2 - 0.07, wh_w / 2 - 0.07, f_w)
    pane *= soft(np.abs(fu_w) - 0.025, f_w) * soft(np.abs(fv_w - 0.9 - 0.65 * wh_w) - 0.03, f_w)
    # ground floor of shops: shop window, then a sign band with letters above it
    ground = np.flatnonzero(~upper)
    shops = ground[shop[ground] > 0.5]
    s = shops[np.abs(fu[shops]) < pitch[shops] / 2 - 0.25 + margin[shops]]
    s = s[np.abs(v[s] - (fh[s] - 0.6) / 2) < (fh[s] - 1.3) / 2 + margin[s]]
    shop_win = rect(fu[s], v[s] - (fh[s] - 0.6) / 2, pitch[s] / 2 - 0.25, (fh[s] - 1.3) / 2, fp[s])
    reflect = np.full(len(u), 0.3, np.float32)
    reflect[w] -= 0.25 * pane  # the two regions are disjoint (upper floors / ground floor)
    reflect[s] -= 0.25 * shop_win
    if not colour:
        return None, reflect

    is_brick = brick > 0.5
    detail = np.empty(len(u), np.float32)
    k = np.flatnonzero(is_brick)
    detail[k] = tex.brick.sample(u[k], v[k], fp[k])
    k = np.flatnonzero(~is_brick)
    detail[k] = tex.plaster.sample(u[k], v[k], fp[k])
    out = _base_colours(params)[b] * detail[:, None]

    rnd = hash01(seed[w], floor[w], col[w])
    sill = rect(fu_w, fv_w - 0.85, ww_w / 2 + 0.08, 0.05, f_w)
    glass = (0.03 + 0.14 * rnd**2)[:, None] * np.array([0.9, 1.0, 1.1], np.float32)
    curtain = (rnd > 0.7) * soft(fv_w - 0.9 - wh_w * (0.3 + 0.5 * rnd), f_w)
    glass = _mix(glass, np.array([0.45, 0.42, 0.36], np.float32) * rnd[:, None], curtain)
    c = _mix(out[w], np.array([0.6, 0.6, 0.57], np.float32), win)
    c = _mix(c, glass, pane)
    out[w] = _mix(c, np.array([0.5, 0.5, 0.48], np.float32), sill)

    goods = tex.leaves.sample(u[s], v[s] * 0.5, fp[s]) * hash01(seed[s], floor[s], col[s])  # behind the glass
    display = (0.05 + 0.2 * goods)[:, None] * np.array([1.0, 0.95, 0.9], np.float32)
    out[s] = _mix(out[s], display, shop_win)
    k = shops[np.abs(v[shops] - fh[shops] + 0.5) < 0.3 + margin[shops]]
    band = soft(0.3 - np.abs(v[k] - fh[k] + 0.5), fp[k])
    sign_col = SIGN_PALETTE[(hash01(seed[k], col[k] // 3) * len(SIGN_PALETTE)).astype(int)]
    letters = np.clip((tex.letters.sample(u[k] * 1.3, v[k] * 1.3, fp[k]) - 0.5) * 4 + 0.5, 0, 1)
    out[k] = _mix(out[k], _mix(sign_col, np.float32(0.8), letters), band)
    # other ground floors: a door in every third column
    k = ground[shop[ground] <= 0.5]
    k = k[(np.abs(fu[k]) < 0.55 + margin[k]) & (np.abs(v[k] - 1.1) < 1.1 + margin[k])]
    k = k[col[k] % 3 == 1]
    door = rect(fu[k], v[k] - 1.1, 0.55, 1.1, fp[k])
    out[k] = _mix(out[k], np.array([0.12, 0.07, 0.04], np.float32) * detail[k, None], door)
    return out, reflect
