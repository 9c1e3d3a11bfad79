"""Feature pyramid over the four ResNet stages (Lin et al. 2017), with torchvision's module
names (``fpn.inner_blocks.K.0``, ``fpn.layer_blocks.K.0``): the ``.0`` is the convolution
inside a one-element ``Sequential``, the way torchvision wraps it.
"""

from __future__ import annotations

from collections import OrderedDict

import torch
import torch.nn.functional as F
from torch import nn

from .resnet import ResNetFeatures, ResNetShape

#: output channels of every pyramid level in Mask R-CNN R50-FPN
FPN_CHANNELS = 256


def _wrapped_conv(in_channels: int, out_channels: int, kernel: int) -> nn.Sequential:
    return nn.Sequential(nn.Conv2d(in_channels, out_channels, kernel, padding=kernel // 2))


class FeaturePyramid(nn.Module):
    """Top-down pathway with lateral 1x1 connections, a 3x3 smoothing per level, and one extra
    level ``"pool"`` (the coarsest map subsampled by 2) that only the proposal network uses."""

    def __init__(self, in_channels: list[int], out_channels: int = FPN_CHANNELS) -> None:
        super().__init__()
        self.inner_blocks = nn.ModuleList(_wrapped_conv(c, out_channels, 1) for c in in_channels)
        self.layer_blocks = nn.ModuleList(_wrapped_conv(out_channels, out_channels, 3)
                                          for _ in in_channels)

    def forward(self, features: OrderedDict[str, torch.Tensor]) -> OrderedDict[str, torch.Tensor]:
        names, maps = list(features), list(features.values())
        top_down = self.inner_blocks[-1](maps[-1])
        levels = [self.layer_blocks[-1](top_down)]
        for k in range(len(maps) - 2, -1, -1):
            lateral = self.inner_blocks[k](maps[k])
            upsampled = F.interpolate(top_down, size=lateral.shape[-2:], mode="nearest")
            top_down = lateral + upsampled
            levels.insert(0, self.layer_blocks[k](top_down))
        out = OrderedDict(zip(names, levels))
        # a 1x1 max pool with stride 2 is plain subsampling of the coarsest level
        out["pool"] = F.max_pool2d(levels[-1], kernel_size=1, stride=2, padding=0)
        return out


class ResNetFPN(nn.Module):
    """``body`` (ResNet stages 1-4, frozen batch norms) followed by ``fpn``; outputs the levels
    ``"0"``..``"3"`` (strides 4..32) and ``"pool"`` (stride 64)."""

    def __init__(self, shape: ResNetShape = ResNetShape(), fpn_channels: int = FPN_CHANNELS) -> None:
        super().__init__()
        self.body = ResNetFeatures(shape, frozen_norm=True, return_stages={
            f"layer{k + 1}": str(k) for k in range(4)})
        self.fpn = FeaturePyramid([shape.out_channels(k) for k in range(4)], fpn_channels)
        self.out_channels = fpn_channels

    def forward(self, x: torch.Tensor) -> OrderedDict[str, torch.Tensor]:
        return self.fpn(self.body(x))
