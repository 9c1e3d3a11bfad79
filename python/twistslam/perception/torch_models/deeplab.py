"""Semantic segmentation networks over a dilated ResNet-50 (output stride 8), inference only,
with the module layout and state-dict keys of torchvision's ``deeplabv3_resnet50`` (ASPP head,
Chen et al. 2017) and ``fcn_resnet50`` (FCN head), auxiliary head included, so their
checkpoints load with ``strict=True``.

Input: a (N, 3, H, W) batch already normalised with the ImageNet statistics. Output:
``{"out": (N, classes, H, W) logits}`` (plus ``"aux"`` in training mode), the
logits upsampled bilinearly to the input size, as torchvision returns them.
"""

from __future__ import annotations

from collections import OrderedDict

import torch
import torch.nn.functional as F
from torch import nn

from .resnet import ResNetFeatures, ResNetShape

#: classes of torchvision's semantic weights: background + the 20 Pascal VOC classes
VOC_NUM_CLASSES = 21
#: dilation rates of the three 3x3 ASPP branches at output stride 8 (DeepLabV3 paper)
ASPP_RATES = (12, 24, 36)
#: channels of every ASPP branch and of the head after it
ASPP_CHANNELS = 256
#: dropout after the ASPP projection (training only; kept for the module layout)
ASPP_DROPOUT = 0.5
#: dropout inside an FCN head (training only; kept for the module layout)
FCN_DROPOUT = 0.1
#: an FCN head's hidden channels are its input channels divided by this
FCN_REDUCTION = 4
#: stages 3 and 4 dilated instead of strided: output stride 8 keeps thin structures
SEGMENTATION_DILATION = (False, True, True)


def _conv_bn_relu(in_channels: int, out_channels: int, kernel: int, dilation: int = 1) -> list[nn.Module]:
    padding = dilation if kernel == 3 else 0
    return [nn.Conv2d(in_channels, out_channels, kernel, padding=padding, dilation=dilation,
                      bias=False), nn.BatchNorm2d(out_channels), nn.ReLU()]


class ImagePooling(nn.Sequential):
    """ASPP branch on the image-wide average: pool, 1x1 conv, BN, ReLU, broadcast back."""

    def __init__(self, in_channels: int, out_channels: int) -> None:
        super().__init__(nn.AdaptiveAvgPool2d(1), *_conv_bn_relu(in_channels, out_channels, 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        size = x.shape[-2:]
        return F.interpolate(super().forward(x), size=size, mode="bilinear", align_corners=False)


class ASPP(nn.Module):
    """Atrous spatial pyramid pooling: a 1x1 branch, one 3x3 branch per rate, the image
    pooling branch, concatenated and projected (keys ``convs.K``, ``project``)."""

    def __init__(self, in_channels: int, rates=ASPP_RATES, channels: int = ASPP_CHANNELS) -> None:
        super().__init__()
        branches = [nn.Sequential(*_conv_bn_relu(in_channels, channels, 1))]
        branches += [nn.Sequential(*_conv_bn_relu(in_channels, channels, 3, rate)) for rate in rates]
        branches.append(ImagePooling(in_channels, channels))
        self.convs = nn.ModuleList(branches)
        self.project = nn.Sequential(*_conv_bn_relu(len(branches) * channels, channels, 1),
                                     nn.Dropout(ASPP_DROPOUT))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.project(torch.cat([branch(x) for branch in self.convs], dim=1))


def deeplab_head(in_channels: int, num_classes: int, channels: int = ASPP_CHANNELS) -> nn.Sequential:
    """ASPP, 3x3 conv-BN-ReLU, 1x1 classifier (keys ``0``..``4``)."""
    return nn.Sequential(ASPP(in_channels, channels=channels),
                         *_conv_bn_relu(channels, channels, 3), nn.Conv2d(channels, num_classes, 1))


def fcn_head(in_channels: int, num_classes: int) -> nn.Sequential:
    """3x3 conv-BN-ReLU to a quarter of the channels, dropout, 1x1 classifier (keys 0..4)."""
    hidden = in_channels // FCN_REDUCTION
    return nn.Sequential(*_conv_bn_relu(in_channels, hidden, 3), nn.Dropout(FCN_DROPOUT),
                         nn.Conv2d(hidden, num_classes, 1))


class SegmentationNet(nn.Module):
    """Dilated ResNet ``backbone``, main ``classifier`` on stage 4, optional
    ``aux_classifier`` (an FCN head on stage 3, used in training; kept so checkpoints load).

    Parameters
    ----------
    head : "deeplabv3" (ASPP) or "fcn".
    num_classes : output classes (torchvision's weights: 21 Pascal VOC classes).
    aux : build the auxiliary head (torchvision's published weights have one).
    backbone : ResNet depth and width (a test shrinks it).
    head_channels : ASPP channels of the DeepLabV3 head.
    """

    HEADS = ("deeplabv3", "fcn")

    def __init__(self, head: str = "deeplabv3", num_classes: int = VOC_NUM_CLASSES, *,
                 aux: bool = True, backbone: ResNetShape = ResNetShape(),
                 head_channels: int = ASPP_CHANNELS) -> None:
        super().__init__()
        if head not in self.HEADS:
            raise ValueError(f"segmentation head '{head}': expected one of {', '.join(self.HEADS)}")
        stages = {"layer3": "aux", "layer4": "out"} if aux else {"layer4": "out"}
        self.backbone = ResNetFeatures(backbone, frozen_norm=False, dilate=SEGMENTATION_DILATION,
                                       return_stages=stages)
        top = backbone.out_channels(3)
        self.classifier = (deeplab_head(top, num_classes, head_channels) if head == "deeplabv3"
                           else fcn_head(top, num_classes))
        self.aux_classifier = fcn_head(backbone.out_channels(2), num_classes) if aux else None

    def forward(self, x: torch.Tensor) -> OrderedDict[str, torch.Tensor]:
        size = x.shape[-2:]
        features = self.backbone(x)
        out: OrderedDict[str, torch.Tensor] = OrderedDict()
        out["out"] = F.interpolate(self.classifier(features["out"]), size=size, mode="bilinear",
                                   align_corners=False)
        if self.aux_classifier is not None and self.training:
            out["aux"] = F.interpolate(self.aux_classifier(features["aux"]), size=size,
                                       mode="bilinear", align_corners=False)
        return out


def deeplabv3_resnet50(num_classes: int = VOC_NUM_CLASSES, aux: bool = True) -> SegmentationNet:
    """Full-size DeepLabV3-ResNet50 (42.0 M parameters with the auxiliary head), random
    weights, eval mode."""
    return SegmentationNet("deeplabv3", num_classes, aux=aux).eval()


def fcn_resnet50(num_classes: int = VOC_NUM_CLASSES, aux: bool = True) -> SegmentationNet:
    """Full-size FCN-ResNet50 (35.3 M parameters with the auxiliary head), random weights,
    eval mode."""
    return SegmentationNet("fcn", num_classes, aux=aux).eval()
