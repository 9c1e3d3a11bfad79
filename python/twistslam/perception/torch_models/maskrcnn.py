"""Mask R-CNN with a ResNet-50-FPN backbone (He et al. 2017), inference only, in plain torch
with the module layout and state-dict keys of torchvision's ``maskrcnn_resnet50_fpn`` (v1),
so a checkpoint written by torchvision loads with ``strict=True``.

Input: a list of (3, H, W) RGB images with values in [0, 1]. Output: per image a dict with
``boxes`` (D, 4) in input pixels, ``labels`` (D,) class indices (COCO category ids for the
COCO weights), ``scores`` (D,) and ``masks`` (D, 1, H, W) probabilities.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import torch
import torch.nn.functional as F
from torch import nn

from .fpn import FPN_CHANNELS, ResNetFPN
from .resnet import ResNetShape
from .roi_heads import (BOX_HEAD_WIDTH, MASK_HEAD_CHANNELS, DetectionSettings, RoIHeads,
                        paste_masks)
from .rpn import ProposalSettings, RegionProposalNetwork

#: ImageNet channel means / standard deviations (RGB, [0, 1] scale) the backbone was trained on
IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)
#: classes of the COCO detection weights: background + 90 category-id slots (80 used)
COCO_NUM_CLASSES = 91
#: padded batch sides are multiples of this (pixels): the coarsest FPN level has stride 32
SIZE_DIVISIBLE = 32


@dataclass
class ImageResize:
    """How images are scaled before the network, and back after.

    Attributes
    ----------
    min_size : target shorter side, pixels (800: the COCO training scale).
    max_size : cap on the longer side, pixels (1333: keeps the 800-pixel scale's aspect
        budget; a KITTI frame 375 x 1242 is scaled by 1333 / 1242 instead of 800 / 375).
    """

    min_size: int = 800
    max_size: int = 1333

    def scale(self, height: int, width: int) -> float:
        return min(self.min_size / min(height, width), self.max_size / max(height, width))


@dataclass
class MaskRCNNShape:
    """Size of a Mask R-CNN; the defaults are R50-FPN's, a test shrinks them.

    Attributes
    ----------
    num_classes : classes including background (COCO: 91).
    backbone : ResNet depth and width.
    fpn_channels : channels of every pyramid level.
    box_head_width : hidden width of the box head.
    mask_channels : channels of the mask head.
    """

    num_classes: int = COCO_NUM_CLASSES
    backbone: ResNetShape = field(default_factory=ResNetShape)
    fpn_channels: int = FPN_CHANNELS
    box_head_width: int = BOX_HEAD_WIDTH
    mask_channels: int = MASK_HEAD_CHANNELS


class MaskRCNN(nn.Module):
    """Backbone + FPN, proposal network, box and mask heads; see the module docstring."""

    def __init__(self, shape: MaskRCNNShape | None = None, resize: ImageResize | None = None,
                 proposals: ProposalSettings | None = None,
                 detections: DetectionSettings | None = None) -> None:
        super().__init__()
        shape = shape or MaskRCNNShape()
        self.shape = shape
        self.resize = resize or ImageResize()
        self.backbone = ResNetFPN(shape.backbone, shape.fpn_channels)
        self.rpn = RegionProposalNetwork(shape.fpn_channels, settings=proposals)
        self.roi_heads = RoIHeads(shape.fpn_channels, shape.num_classes, shape.box_head_width,
                                  shape.mask_channels, settings=detections)
        # not in the state dict (torchvision keeps them as plain attributes too)
        self.image_mean = torch.tensor(IMAGENET_MEAN)
        self.image_std = torch.tensor(IMAGENET_STD)

    def _prepare(self, images: list[torch.Tensor]) -> tuple[torch.Tensor, list[tuple[int, int]]]:
        """Normalised, resized images zero-padded into one batch, and each one's resized size."""
        resized = []
        for image in images:
            if image.ndim != 3 or image.shape[0] != 3:
                raise ValueError(f"Mask R-CNN: expected (3, H, W) images, got {tuple(image.shape)}")
            mean = self.image_mean.to(image)[:, None, None]
            std = self.image_std.to(image)[:, None, None]
            x = (image - mean) / std
            scale = self.resize.scale(*x.shape[-2:])
            x = F.interpolate(x[None], scale_factor=scale, mode="bilinear",
                              recompute_scale_factor=True, align_corners=False)[0]
            resized.append(x)
        sizes = [tuple(x.shape[-2:]) for x in resized]
        padded_h = -(-max(s[0] for s in sizes) // SIZE_DIVISIBLE) * SIZE_DIVISIBLE
        padded_w = -(-max(s[1] for s in sizes) // SIZE_DIVISIBLE) * SIZE_DIVISIBLE
        batch = resized[0].new_zeros((len(resized), 3, padded_h, padded_w))
        for k, x in enumerate(resized):
            batch[k, :, :x.shape[1], :x.shape[2]] = x
        return batch, sizes

    def forward(self, images: list[torch.Tensor]) -> list[dict[str, torch.Tensor]]:
        if self.training:
            raise RuntimeError("this Mask R-CNN is inference only: call .eval() first")
        original_sizes = [tuple(image.shape[-2:]) for image in images]
        batch, sizes = self._prepare(images)
        features = self.backbone(batch)
        proposals = self.rpn(batch, sizes, features)
        results = self.roi_heads(features, proposals, sizes)
        for result, size, original in zip(results, sizes, original_sizes):
            ratio_y, ratio_x = original[0] / size[0], original[1] / size[1]
            scale = result["boxes"].new_tensor([ratio_x, ratio_y, ratio_x, ratio_y])
            result["boxes"] = result["boxes"] * scale
            result["masks"] = paste_masks(result["masks"], result["boxes"], original)
        return results


def maskrcnn_resnet50_fpn(num_classes: int = COCO_NUM_CLASSES, **settings) -> MaskRCNN:
    """The full-size model (44.4 M parameters for 91 classes) with random weights, in eval
    mode; load a torchvision checkpoint into it with ``load_state_dict``. ``settings``:
    ``resize``, ``proposals``, ``detections`` of :class:`MaskRCNN`."""
    return MaskRCNN(MaskRCNNShape(num_classes=num_classes), **settings).eval()
