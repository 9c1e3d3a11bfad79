"""ResNet (bottleneck blocks) in plain torch, laid out like torchvision's ``resnet50`` so its
state-dict keys (``conv1``, ``bn1``, ``layer1.0.conv1``, ``layer1.0.downsample.0`` ...) match.

Two variants are used by the segmentation sources:

- the detection backbone of Mask R-CNN, whose batch norms are *frozen* (fixed affine
  transforms kept as buffers, not parameters, as in torchvision's detection models);
- the dilated backbone of DeepLabV3 / FCN (layer3 and layer4 keep stride 8 and dilate their
  3x3 convolutions instead), with ordinary batch norms used in eval mode.

Depth (blocks per stage) and width (channels of the first stage) are configurable so a test can
build a network of a few thousand parameters with the same structure.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import torch
from torch import nn

#: output channels of a bottleneck block are this many times its inner width (ResNet-50's 4)
BOTTLENECK_EXPANSION = 4
#: added to the running variance before the square root, torchvision's batch-norm default
BATCH_NORM_EPS = 1e-5


class FrozenBatchNorm2d(nn.Module):
    """Batch norm with fixed statistics and affine terms, all buffers (never trained).

    A checkpoint written by a ``BatchNorm2d`` carries ``num_batches_tracked``; it is dropped on
    load so such a checkpoint loads too.
    """

    def __init__(self, channels: int, eps: float = BATCH_NORM_EPS) -> None:
        super().__init__()
        self.eps = eps
        self.register_buffer("weight", torch.ones(channels))
        self.register_buffer("bias", torch.zeros(channels))
        self.register_buffer("running_mean", torch.zeros(channels))
        self.register_buffer("running_var", torch.ones(channels))

    def _load_from_state_dict(self, state_dict, prefix, *args, **kwargs):
        state_dict.pop(prefix + "num_batches_tracked", None)
        super()._load_from_state_dict(state_dict, prefix, *args, **kwargs)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        scale = self.weight * (self.running_var + self.eps).rsqrt()
        shift = self.bias - self.running_mean * scale
        return x * scale[None, :, None, None] + shift[None, :, None, None]


@dataclass(frozen=True)
class ResNetShape:
    """Size of a bottleneck ResNet.

    Attributes
    ----------
    blocks : bottleneck blocks in each of the four stages (ResNet-50: 3, 4, 6, 3).
    width : inner channels of the first stage (ResNet-50: 64); stage k uses ``width * 2**k``
        and outputs ``4 * width * 2**k`` channels.
    """

    blocks: tuple[int, int, int, int] = (3, 4, 6, 3)
    width: int = 64

    def out_channels(self, stage: int) -> int:
        """Channels leaving stage ``stage`` (0..3)."""
        return BOTTLENECK_EXPANSION * self.width * 2 ** stage


class Bottleneck(nn.Module):
    """1x1 reduce, 3x3 (strided and/or dilated), 1x1 expand, plus the shortcut."""

    def __init__(self, in_channels: int, width: int, stride: int, dilation: int,
                 norm: type[nn.Module], downsample: nn.Module | None) -> None:
        super().__init__()
        out_channels = width * BOTTLENECK_EXPANSION
        self.conv1 = nn.Conv2d(in_channels, width, 1, bias=False)
        self.bn1 = norm(width)
        self.conv2 = nn.Conv2d(width, width, 3, stride=stride, padding=dilation,
                               dilation=dilation, bias=False)
        self.bn2 = norm(width)
        self.conv3 = nn.Conv2d(width, out_channels, 1, bias=False)
        self.bn3 = norm(out_channels)
        self.relu = nn.ReLU(inplace=True)
        self.downsample = downsample

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        shortcut = x if self.downsample is None else self.downsample(x)
        y = self.relu(self.bn1(self.conv1(x)))
        y = self.relu(self.bn2(self.conv2(y)))
        return self.relu(self.bn3(self.conv3(y)) + shortcut)


class ResNetFeatures(nn.Module):
    """The stem and four stages of a ResNet, without the classifier; ``forward`` returns the
    outputs of the stages named in ``return_stages`` (``{"layer1": "0", ...}``), in order.

    Parameters
    ----------
    shape : depth and width.
    frozen_norm : frozen batch norms (detection) instead of ``BatchNorm2d`` (segmentation).
    dilate : per stage 2..4, replace its stride-2 by a dilation (DeepLabV3: False, True, True).
    return_stages : stage attribute name -> output key.
    """

    def __init__(self, shape: ResNetShape = ResNetShape(), *, frozen_norm: bool = True,
                 dilate: tuple[bool, bool, bool] = (False, False, False),
                 return_stages: dict[str, str] | None = None) -> None:
        super().__init__()
        norm = FrozenBatchNorm2d if frozen_norm else nn.BatchNorm2d
        self.shape = shape
        self.return_stages = dict(return_stages or {"layer4": "out"})
        self.conv1 = nn.Conv2d(3, shape.width, 7, stride=2, padding=3, bias=False)
        self.bn1 = norm(shape.width)
        self.relu = nn.ReLU(inplace=True)
        self.maxpool = nn.MaxPool2d(3, stride=2, padding=1)
        in_channels, dilation = shape.width, 1
        for stage in range(4):
            stride = 1 if stage == 0 else 2
            first_dilation = dilation
            if stage > 0 and dilate[stage - 1]:
                # keep the resolution: the stride becomes dilation of this and later stages
                dilation *= stride
                stride = 1
            width = shape.width * 2 ** stage
            blocks = []
            for k in range(shape.blocks[stage]):
                downsample = None
                if k == 0 and (stride != 1 or in_channels != width * BOTTLENECK_EXPANSION):
                    downsample = nn.Sequential(
                        nn.Conv2d(in_channels, width * BOTTLENECK_EXPANSION, 1, stride=stride,
                                  bias=False),
                        norm(width * BOTTLENECK_EXPANSION))
                blocks.append(Bottleneck(in_channels, width, stride if k == 0 else 1,
                                         first_dilation if k == 0 else dilation, norm, downsample))
                in_channels = width * BOTTLENECK_EXPANSION
            setattr(self, f"layer{stage + 1}", nn.Sequential(*blocks))

    def forward(self, x: torch.Tensor) -> OrderedDict[str, torch.Tensor]:
        out: OrderedDict[str, torch.Tensor] = OrderedDict()
        x = self.maxpool(self.relu(self.bn1(self.conv1(x))))
        for stage in range(1, 5):
            x = getattr(self, f"layer{stage}")(x)
            key = self.return_stages.get(f"layer{stage}")
            if key is not None:
                out[key] = x
            if len(out) == len(self.return_stages):
                break  # later stages would be computed for nothing
        return out
