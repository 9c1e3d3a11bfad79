"""Building blocks of the RAFT optical-flow network (Teed & Deng, ECCV 2020) in plain torch:
convolution layers, the residual / bottleneck image encoders, the all-pairs correlation
pyramid and the flow upsampling.

Module and attribute names follow torchvision's ``raft_small`` / ``raft_large`` so that their
state dicts load unchanged (see :mod:`twistslam.perception.raft_model`); a convolution layer
is a ``Sequential`` of (conv, [norm], [ReLU]) because its keys are then ``<name>.0.weight``,
``<name>.1.running_mean``, ... as in those checkpoints.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

#: the encoders and the flow grid work at 1/8 of the image resolution (three stride-2 stages)
DOWNSAMPLE_FACTOR = 8
#: neighbours of a coarse flow vector that the convex upsampling mixes (a 3 x 3 window)
CONVEX_NEIGHBOURS = 9
NORMS = (None, "instance", "batch")


def conv_layer(in_channels: int, out_channels: int, kernel_size: int | tuple[int, int], *, stride: int = 1,
               norm: str | None = None, relu: bool = True) -> nn.Sequential:
    """Convolution ('same' padding for odd kernels, with bias), then optionally a norm and a ReLU.

    The bias is kept even before a norm layer: trained RAFT weights have it (their batch norms
    were frozen after the first training stage, so the bias still mattered).
    """
    if norm not in NORMS:
        raise ValueError(f"RAFT norm '{norm}': expected one of {NORMS}")
    kernel = (kernel_size, kernel_size) if isinstance(kernel_size, int) else tuple(kernel_size)
    padding = tuple((k - 1) // 2 for k in kernel)
    layers: list[nn.Module] = [nn.Conv2d(in_channels, out_channels, kernel, stride=stride, padding=padding)]
    if norm == "instance":
        layers.append(nn.InstanceNorm2d(out_channels))  # no affine parameters, no running statistics
    elif norm == "batch":
        layers.append(nn.BatchNorm2d(out_channels))
    if relu:
        layers.append(nn.ReLU(inplace=True))
    return nn.Sequential(*layers)


class ResidualBlock(nn.Module):
    """Two 3x3 conv-norm-ReLU layers plus a shortcut (a 1x1 projection when striding), then ReLU."""

    def __init__(self, in_channels: int, out_channels: int, *, norm: str | None, stride: int = 1) -> None:
        super().__init__()
        self.convnormrelu1 = conv_layer(in_channels, out_channels, 3, stride=stride, norm=norm)
        self.convnormrelu2 = conv_layer(out_channels, out_channels, 3, norm=norm)
        self.downsample = (nn.Identity() if stride == 1
                           else conv_layer(in_channels, out_channels, 1, stride=stride, norm=norm, relu=False))
        self.relu = nn.ReLU(inplace=True)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = self.convnormrelu2(self.convnormrelu1(x))
        return self.relu(self.downsample(x) + y)


class BottleneckBlock(nn.Module):
    """1x1 squeeze to a quarter of the channels, 3x3 (strided), 1x1 expand, plus a shortcut."""

    #: channel reduction inside the bottleneck (the standard ResNet bottleneck ratio)
    SQUEEZE = 4

    def __init__(self, in_channels: int, out_channels: int, *, norm: str | None, stride: int = 1) -> None:
        super().__init__()
        if out_channels % self.SQUEEZE:
            raise ValueError(f"RAFT bottleneck block: {out_channels} channels do not divide by {self.SQUEEZE}")
        inner = out_channels // self.SQUEEZE
        self.convnormrelu1 = conv_layer(in_channels, inner, 1, norm=norm)
        self.convnormrelu2 = conv_layer(inner, inner, 3, stride=stride, norm=norm)
        self.convnormrelu3 = conv_layer(inner, out_channels, 1, norm=norm)
        self.relu = nn.ReLU(inplace=True)
        self.downsample = (nn.Identity() if stride == 1
                           else conv_layer(in_channels, out_channels, 1, stride=stride, norm=norm, relu=False))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = self.convnormrelu3(self.convnormrelu2(self.convnormrelu1(x)))
        return self.relu(self.downsample(x) + y)


BLOCKS = {"residual": ResidualBlock, "bottleneck": BottleneckBlock}


class FeatureEncoder(nn.Module):
    """Image -> features at 1/8 resolution: a 7x7 stride-2 stem, three stages of two blocks
    (strides 1, 2, 2) and a 1x1 output convolution. Used for both the matching features and
    the context.

    Parameters
    ----------
    layers : channels of the stem, the three stages and the output (5 numbers).
    block : "residual" or "bottleneck".
    norm : None, "instance" or "batch".
    """

    #: strides of the stem and of the first block of each stage: 2 * 1 * 2 * 2 = DOWNSAMPLE_FACTOR
    STRIDES = (2, 1, 2, 2)

    def __init__(self, layers: tuple[int, ...], block: str, norm: str | None) -> None:
        super().__init__()
        if len(layers) != 5:
            raise ValueError(f"RAFT encoder layers: expected 5 channel counts, got {tuple(layers)}")
        if block not in BLOCKS:
            raise ValueError(f"RAFT encoder block '{block}': expected one of {', '.join(BLOCKS)}")
        make = BLOCKS[block]
        self.convnormrelu = conv_layer(3, layers[0], 7, stride=self.STRIDES[0], norm=norm)
        for stage in range(1, 4):
            first = make(layers[stage - 1], layers[stage], norm=norm, stride=self.STRIDES[stage])
            second = make(layers[stage], layers[stage], norm=norm, stride=1)
            setattr(self, f"layer{stage}", nn.Sequential(first, second))
        self.conv = nn.Conv2d(layers[3], layers[4], kernel_size=1)
        self.output_channels = layers[4]
        for module in self.modules():
            # He initialisation keeps the activations of an untrained encoder in range through the
            # ReLUs (only matters before a state dict is loaded)
            if isinstance(module, nn.Conv2d):
                nn.init.kaiming_normal_(module.weight, mode="fan_out", nonlinearity="relu")
            elif isinstance(module, nn.BatchNorm2d):
                nn.init.ones_(module.weight)
                nn.init.zeros_(module.bias)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = self.convnormrelu(x)
        x = self.layer3(self.layer2(self.layer1(x)))
        return self.conv(x)


class CorrelationPyramid:
    """All-pairs correlation of two feature maps, average-pooled ``levels - 1`` times over the
    second image's axes, and looked up in a (2 radius + 1)^2 window around each flow target.

    Not a module (no parameters): one is built per image pair by :meth:`RAFT.forward`.
    """

    def __init__(self, features1: torch.Tensor, features2: torch.Tensor, *, levels: int, radius: int) -> None:
        if features1.shape != features2.shape:
            raise ValueError(f"RAFT correlation: feature maps differ in shape, {tuple(features1.shape)} "
                             f"vs {tuple(features2.shape)}")
        n, channels, h, w = features1.shape
        # the coarsest level must keep >= 2 cells per axis: sampling a 1-cell axis is undefined
        smallest = 2 ** levels
        if h < smallest or w < smallest:
            raise ValueError(f"RAFT correlation: {levels} pyramid levels need feature maps of at least "
                             f"{smallest} x {smallest} (images of {smallest * DOWNSAMPLE_FACTOR} px per "
                             f"side); got {h} x {w}")
        self.levels, self.radius = levels, radius
        # scaled dot product, as in attention: keeps the scores' variance independent of channels
        volume = torch.einsum("nci,ncj->nij", features1.flatten(2), features2.flatten(2)) / channels ** 0.5
        volume = volume.reshape(n * h * w, 1, h, w)  # one 2-D map over image 2 per pixel of image 1
        self.volumes = [volume]
        for _ in range(levels - 1):
            volume = F.avg_pool2d(volume, kernel_size=2, stride=2)
            self.volumes.append(volume)
        side = 2 * radius + 1
        offsets = torch.arange(-radius, radius + 1, dtype=features1.dtype, device=features1.device)
        # window offsets (dx, dy) with dx varying along the window's first axis: the correlation
        # channels of trained RAFT weights are ordered x-offset major, y-offset minor
        dx, dy = torch.meshgrid(offsets, offsets, indexing="ij")
        self.window = torch.stack([dx, dy], dim=-1).reshape(1, side, side, 2)

    @property
    def channels(self) -> int:
        return self.levels * (2 * self.radius + 1) ** 2

    def lookup(self, targets: torch.Tensor) -> torch.Tensor:
        """Correlation features (N, levels * (2r+1)^2, h, w) around the targets (N, 2, h, w),
        given as (x, y) cells of the level-0 grid; bilinear between cells, zero outside."""
        n, _, h, w = targets.shape
        centres = targets.permute(0, 2, 3, 1).reshape(n * h * w, 1, 1, 2)
        features = []
        for level, volume in enumerate(self.volumes):
            points = centres / 2 ** level + self.window
            sampled = sample_at_pixels(volume, points)  # (n*h*w, 1, side, side)
            features.append(sampled.reshape(n, h, w, -1))
        return torch.cat(features, dim=-1).permute(0, 3, 1, 2).contiguous()


def sample_at_pixels(image: torch.Tensor, points: torch.Tensor) -> torch.Tensor:
    """Bilinear samples of ``image`` (B, C, H, W) at pixel coordinates ``points`` (B, ..., 2) in
    (x, y) order, pixel centres at integers; zero outside the image."""
    h, w = image.shape[-2:]
    scale = points.new_tensor([2.0 / (w - 1), 2.0 / (h - 1)])
    return F.grid_sample(image, points * scale - 1.0, mode="bilinear", align_corners=True)


def pixel_grid(n: int, h: int, w: int, like: torch.Tensor) -> torch.Tensor:
    """(n, 2, h, w) pixel coordinates, channel 0 x (column), channel 1 y (row)."""
    ys, xs = torch.meshgrid(torch.arange(h, device=like.device, dtype=like.dtype),
                            torch.arange(w, device=like.device, dtype=like.dtype), indexing="ij")
    return torch.stack([xs, ys])[None].expand(n, 2, h, w)


def upsample_bilinear(flow: torch.Tensor, factor: int = DOWNSAMPLE_FACTOR) -> torch.Tensor:
    """Coarse flow (N, 2, h, w) -> (N, 2, h * factor, w * factor), vectors scaled to the new pixels."""
    h, w = flow.shape[-2:]
    return factor * F.interpolate(flow, size=(h * factor, w * factor), mode="bilinear", align_corners=True)


def upsample_convex(flow: torch.Tensor, mask: torch.Tensor, factor: int = DOWNSAMPLE_FACTOR) -> torch.Tensor:
    """Each fine pixel is a softmax-weighted (convex) mix of the 3x3 coarse vectors around its
    coarse cell; ``mask`` (N, 9 * factor^2, h, w) holds the logits, neighbour-major then the
    sub-pixel row and column (the layout of trained RAFT weights)."""
    n, _, h, w = flow.shape
    weights = torch.softmax(mask.reshape(n, 1, CONVEX_NEIGHBOURS, factor, factor, h, w), dim=2)
    neighbours = F.unfold(factor * flow, kernel_size=3, padding=1)
    neighbours = neighbours.reshape(n, 2, CONVEX_NEIGHBOURS, 1, 1, h, w)
    fine = (weights * neighbours).sum(dim=2)  # (n, 2, sub-row, sub-column, h, w)
    return fine.permute(0, 1, 4, 2, 5, 3).reshape(n, 2, h * factor, w * factor)
