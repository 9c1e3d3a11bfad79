"""Point sampling and grouping of 3DSSD in plain torch (CPU): distance and feature farthest
point sampling, their fusion, ball query and neighbour gathering.

Every function works on a batch: ``xyz`` is (B, N, 3), features are (B, C, N). Sampling
returns indices and carries no gradient (it picks points; the network never differentiates
through the choice).
"""

from __future__ import annotations

import torch

#: centres handled per ball-query chunk: bounds the (chunk, N) distance matrix to
#: 512 x 16384 floats = 32 MB whatever the centre count
BALL_QUERY_CHUNK = 512


@torch.no_grad()
def farthest_point_sample(points: torch.Tensor, count: int, start: int = 0) -> torch.Tensor:
    """Greedy farthest point sampling: (B, count) int64 indices into ``points`` (B, N, D).

    The first pick is ``start``; each next pick is the point farthest (squared Euclidean
    distance in D dimensions) from all picks so far. ``D = 3`` is 3DSSD's D-FPS; the point
    features (optionally with the coordinates appended) give F-FPS. When ``count >= N`` every
    point is returned in order (repeating the last one up to ``count``).
    """
    batch, n, _ = points.shape
    if count >= n:
        index = torch.arange(count, device=points.device).clamp(max=n - 1)
        return index.expand(batch, count).contiguous()
    rows = torch.arange(batch, device=points.device)
    picks = torch.empty(batch, count, dtype=torch.long, device=points.device)
    nearest = torch.full((batch, n), float("inf"), dtype=points.dtype, device=points.device)
    current = torch.full((batch,), start, dtype=torch.long, device=points.device)
    for i in range(count):
        picks[:, i] = current
        offset = points - points[rows, current].unsqueeze(1)
        torch.minimum(nearest, offset.square().sum(-1), out=nearest)
        current = nearest.argmax(dim=1)
    return picks


def feature_fps_space(xyz: torch.Tensor, features: torch.Tensor, xyz_weight: float) -> torch.Tensor:
    """The (B, N, 3 + C) space F-FPS measures distances in: the point features next to the
    coordinates scaled by ``sqrt(xyz_weight)`` (so that squared distances add as
    ``xyz_weight * d_xyz^2 + d_feature^2``, the paper's fused distance)."""
    return torch.cat([xyz * xyz_weight ** 0.5, features.transpose(1, 2)], dim=2)


@torch.no_grad()
def fusion_sample(xyz: torch.Tensor, features: torch.Tensor | None, n_dfps: int, n_ffps: int,
                  xyz_weight: float = 1.0) -> torch.Tensor:
    """3DSSD's fusion sampling: (B, n_ffps + n_dfps) indices, the F-FPS picks first.

    F-FPS keeps the points whose features differ most (it keeps many points on objects,
    whose features stand out from the ground); D-FPS covers the scene evenly (context for
    the background). A point picked by both appears twice, as in the paper.
    """
    parts = []
    if n_ffps > 0:
        if features is None:
            raise ValueError("feature FPS needs point features")
        parts.append(farthest_point_sample(feature_fps_space(xyz, features, xyz_weight), n_ffps))
    if n_dfps > 0:
        parts.append(farthest_point_sample(xyz, n_dfps))
    return torch.cat(parts, dim=1)


def gather_points(values: torch.Tensor, index: torch.Tensor) -> torch.Tensor:
    """``values`` (B, N, D) at ``index`` (B, ...) -> (B, ..., D)."""
    batch, _, dim = values.shape
    flat = index.reshape(batch, -1)
    picked = torch.gather(values, 1, flat.unsqueeze(-1).expand(-1, -1, dim))
    return picked.reshape(*index.shape, dim)


def gather_features(features: torch.Tensor, index: torch.Tensor) -> torch.Tensor:
    """``features`` (B, C, N) at ``index`` (B, M) or (B, M, K) -> (B, C, M[, K])."""
    batch, channels, _ = features.shape
    flat = index.reshape(batch, 1, -1).expand(-1, channels, -1)
    return torch.gather(features, 2, flat).reshape(batch, channels, *index.shape[1:])


@torch.no_grad()
def ball_query(xyz: torch.Tensor, centres: torch.Tensor, radius: float,
               samples: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Up to ``samples`` points of ``xyz`` (B, N, 3) within ``radius`` of each centre
    (B, M, 3), lowest indices first (as the CUDA op of PointNet++ does).

    Returns
    -------
    index : (B, M, samples) int64; slots beyond a ball's population repeat its first point,
        and an empty ball points at the nearest point (so grouping always has data).
    valid : (B, M, samples) bool, True where the slot holds a distinct in-ball point.
    """
    batch, n, _ = xyz.shape
    order = torch.arange(n, device=xyz.device)
    indices, valids = [], []
    for begin in range(0, centres.shape[1], BALL_QUERY_CHUNK):
        chunk = centres[:, begin:begin + BALL_QUERY_CHUNK]
        d2 = torch.cdist(chunk, xyz).square()  # (B, m, N)
        inside = d2 <= radius * radius
        # in-ball points keep their index as sort key, others sort after every real index
        key = torch.where(inside, order, n + order)
        k = min(samples, n)
        first = key.topk(k, dim=2, largest=False).values
        valid = first < n
        # padding slots repeat the ball's first point; an empty ball takes the nearest point
        fill = torch.where(valid[..., :1], first[..., :1], d2.argmin(dim=2, keepdim=True))
        index = torch.where(valid, first, fill)
        if k < samples:  # fewer points than slots: pad by repeating the first
            index = torch.cat([index, index[..., :1].expand(-1, -1, samples - k)], dim=2)
            valid = torch.cat([valid, torch.zeros_like(valid[..., :1]).expand(-1, -1, samples - k)], dim=2)
        indices.append(index)
        valids.append(valid)
    return torch.cat(indices, dim=1), torch.cat(valids, dim=1)


def group(xyz: torch.Tensor, features: torch.Tensor | None, centres: torch.Tensor, radius: float,
          samples: int) -> torch.Tensor:
    """PointNet++ grouping: (B, 3 + C, M, samples), each neighbour's offset to its centre
    divided by ``radius`` (a unit-scale input for every scale), then its features."""
    index, _ = ball_query(xyz, centres, radius, samples)
    offsets = (gather_points(xyz, index) - centres.unsqueeze(2)) / radius  # (B, M, K, 3)
    grouped = offsets.permute(0, 3, 1, 2)
    if features is not None:
        grouped = torch.cat([grouped, gather_features(features, index)], dim=1)
    return grouped
