"""The layers of 3DSSD: multi-scale set abstraction, the shift (vote) layer of candidate
generation, and the point-wise MLPs they are built from."""

from __future__ import annotations

import torch
from torch import nn

from .ssd3d_sampling import fusion_sample, gather_points, group


def shared_mlp(in_channels: int, widths: tuple[int, ...], dims: int = 2) -> nn.Sequential:
    """1x1 convolutions + batch norm + ReLU, applied to every point (and neighbour) alike."""
    conv, norm = (nn.Conv2d, nn.BatchNorm2d) if dims == 2 else (nn.Conv1d, nn.BatchNorm1d)
    layers: list[nn.Module] = []
    for width in widths:
        layers += [conv(in_channels, width, 1, bias=False), norm(width), nn.ReLU(inplace=True)]
        in_channels = width
    return nn.Sequential(*layers)


class MultiScaleGrouping(nn.Module):
    """Group the points around given centres at several radii, run each scale's shared MLP,
    max-pool over the neighbours, concatenate and aggregate with a 1x1 convolution."""

    def __init__(self, in_channels: int, radii, samples, mlps, out_channels: int) -> None:
        super().__init__()
        self.radii, self.samples = tuple(radii), tuple(samples)
        self.mlps = nn.ModuleList(shared_mlp(in_channels + 3, tuple(widths)) for widths in mlps)
        self.aggregate = shared_mlp(sum(widths[-1] for widths in mlps), (out_channels,), dims=1)

    def forward(self, xyz: torch.Tensor, features: torch.Tensor | None, centres: torch.Tensor) -> torch.Tensor:
        """``xyz`` (B, N, 3), ``features`` (B, C, N) or None, ``centres`` (B, M, 3) ->
        (B, out_channels, M)."""
        pooled = [mlp(group(xyz, features, centres, radius, samples)).amax(dim=3)
                  for radius, samples, mlp in zip(self.radii, self.samples, self.mlps)]
        return self.aggregate(torch.cat(pooled, dim=1))


class SetAbstraction(nn.Module):
    """One SA layer: fusion-sampled centres (F-FPS first, then D-FPS) and their grouped features."""

    def __init__(self, in_channels: int, layer) -> None:
        super().__init__()
        self.n_dfps, self.n_ffps = layer.n_dfps, layer.n_ffps
        self.grouping = MultiScaleGrouping(in_channels, layer.radii, layer.samples, layer.mlps,
                                           layer.out_channels)

    def forward(self, xyz: torch.Tensor, features: torch.Tensor | None) -> tuple[torch.Tensor, torch.Tensor]:
        """(B, N, 3), (B, C, N) -> centres (B, M, 3), their features (B, out_channels, M)."""
        index = fusion_sample(xyz, features, self.n_dfps, self.n_ffps)
        centres = gather_points(xyz, index)
        return centres, self.grouping(xyz, features, centres)


class ShiftLayer(nn.Module):
    """Candidate generation's vote: each feature-FPS point predicts the offset to the centre of
    the object it lies on, clamped to ``max_shift`` metres per axis."""

    def __init__(self, in_channels: int, hidden: tuple[int, ...], max_shift: tuple[float, float, float]) -> None:
        super().__init__()
        self.mlp = shared_mlp(in_channels, hidden, dims=1)
        self.out = nn.Conv1d(hidden[-1] if hidden else in_channels, 3, 1)
        self.register_buffer("max_shift", torch.tensor(max_shift, dtype=torch.float32), persistent=False)

    def forward(self, features: torch.Tensor) -> torch.Tensor:
        """(B, C, M) -> shifts (B, M, 3)."""
        shift = self.out(self.mlp(features)).transpose(1, 2)
        return torch.maximum(torch.minimum(shift, self.max_shift), -self.max_shift)


class PointHead(nn.Module):
    """Anchor-free head: per candidate, one logit per class and the box code
    (3 centre + 3 size + heading bins + heading residuals per bin)."""

    def __init__(self, in_channels: int, hidden: tuple[int, ...], num_classes: int, heading_bins: int) -> None:
        super().__init__()
        width = hidden[-1] if hidden else in_channels
        self.cls_mlp = shared_mlp(in_channels, hidden, dims=1)
        self.cls_out = nn.Conv1d(width, num_classes, 1)
        self.box_mlp = shared_mlp(in_channels, hidden, dims=1)
        self.box_out = nn.Conv1d(width, 6 + 2 * heading_bins, 1)
        # a low prior on objects keeps the first iterations from being swamped by the many
        # background candidates (the focal-loss initialisation, here with a plain BCE)
        nn.init.constant_(self.cls_out.bias, -2.0)

    def forward(self, features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(B, C, M) -> logits (B, M, classes), box codes (B, M, 6 + 2 bins)."""
        logits = self.cls_out(self.cls_mlp(features)).transpose(1, 2)
        codes = self.box_out(self.box_mlp(features)).transpose(1, 2)
        return logits, codes

