"""Region proposal network (Ren et al. 2015) over the feature pyramid, inference only, with
torchvision's module names (``rpn.head.conv.0.0``, ``rpn.head.cls_logits``,
``rpn.head.bbox_pred``).

Every pyramid level has anchors of one size (32, 64, 128, 256, 512 pixels for the levels of
strides 4..64) in three aspect ratios; the head scores each anchor and regresses a box from
it; the best boxes of each level survive NMS within their level.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import torch
from torch import nn

from .box_ops import BoxCoder, batched_nms, clip_boxes, keep_large_boxes

#: anchor side (square-root of its area) per pyramid level, pixels: one octave per level
ANCHOR_SIZES = (32, 64, 128, 256, 512)
#: anchor height / width ratios: tall, square and wide objects
ANCHOR_ASPECT_RATIOS = (0.5, 1.0, 2.0)


def base_anchors(size: float, aspect_ratios=ANCHOR_ASPECT_RATIOS) -> torch.Tensor:
    """(A, 4) anchors centred on the origin, one per aspect ratio, rounded to whole pixels."""
    ratios = torch.as_tensor(aspect_ratios, dtype=torch.float32)
    height_factor = torch.sqrt(ratios)
    widths = size / height_factor
    heights = size * height_factor
    return (torch.stack([-widths, -heights, widths, heights], dim=1) / 2).round()


def grid_anchors(base: torch.Tensor, grid: tuple[int, int], stride: tuple[int, int]) -> torch.Tensor:
    """(H W A, 4) anchors of a feature map of ``grid`` (H, W) cells ``stride`` (sy, sx) pixels
    apart: cell-major, aspect-ratio-minor (the order the head's outputs are flattened in)."""
    ys = torch.arange(grid[0], dtype=torch.float32) * stride[0]
    xs = torch.arange(grid[1], dtype=torch.float32) * stride[1]
    y, x = torch.meshgrid(ys, xs, indexing="ij")
    x, y = x.reshape(-1), y.reshape(-1)
    shifts = torch.stack([x, y, x, y], dim=1)
    return (shifts[:, None, :] + base[None, :, :]).reshape(-1, 4)


class RPNHead(nn.Module):
    """3x3 conv + ReLU shared by all levels, then per anchor one objectness logit and four box
    codes."""

    def __init__(self, channels: int, anchors_per_cell: int) -> None:
        super().__init__()
        # torchvision nests the conv twice (a list of conv-activation blocks of one block)
        self.conv = nn.Sequential(nn.Sequential(nn.Conv2d(channels, channels, 3, padding=1),
                                                nn.ReLU(inplace=True)))
        self.cls_logits = nn.Conv2d(channels, anchors_per_cell, 1)
        self.bbox_pred = nn.Conv2d(channels, anchors_per_cell * 4, 1)

    def forward(self, levels: list[torch.Tensor]) -> tuple[list[torch.Tensor], list[torch.Tensor]]:
        logits, codes = [], []
        for x in levels:
            t = self.conv(x)
            logits.append(self.cls_logits(t))
            codes.append(self.bbox_pred(t))
        return logits, codes


def _flatten(x: torch.Tensor, per_anchor: int) -> torch.Tensor:
    """(N, A C, H, W) head output -> (N, H W A, C), matching :func:`grid_anchors`' order."""
    n, _, h, w = x.shape
    return x.view(n, -1, per_anchor, h, w).permute(0, 3, 4, 1, 2).reshape(n, -1, per_anchor)


@dataclass
class ProposalSettings:
    """How many proposals survive, inference settings of Mask R-CNN R50-FPN.

    Attributes
    ----------
    pre_nms_per_level : best-scoring anchors kept per level before NMS (count).
    post_nms : proposals kept per image after NMS (count); the box head sees this many.
    nms_iou : IoU above which a lower-scoring proposal of the same level is dropped
        (0.7: proposals overlap a lot, only near duplicates go).
    min_size : smallest proposal side kept, pixels (1e-3: only degenerate boxes go).
    score_threshold : lowest objectness probability kept (0: keep all, the top-k limits).
    """

    pre_nms_per_level: int = 1000
    post_nms: int = 1000
    nms_iou: float = 0.7
    min_size: float = 1e-3
    score_threshold: float = 0.0


class RegionProposalNetwork(nn.Module):
    """Proposals ``list[(P, 4)]`` per image from the pyramid levels (inference only)."""

    def __init__(self, channels: int, sizes=ANCHOR_SIZES, aspect_ratios=ANCHOR_ASPECT_RATIOS,
                 settings: ProposalSettings | None = None) -> None:
        super().__init__()
        self.sizes, self.aspect_ratios = tuple(sizes), tuple(aspect_ratios)
        self.head = RPNHead(channels, len(self.aspect_ratios))
        self.box_coder = BoxCoder((1.0, 1.0, 1.0, 1.0))
        self.settings = settings or ProposalSettings()

    def anchors(self, padded_size: tuple[int, int], grids: list[tuple[int, int]]) -> list[torch.Tensor]:
        """Anchors of each level for a padded batch of ``padded_size`` (H, W)."""
        out = []
        for size, grid in zip(self.sizes, grids):
            stride = (padded_size[0] // grid[0], padded_size[1] // grid[1])
            out.append(grid_anchors(base_anchors(size, self.aspect_ratios), grid, stride))
        return out

    def forward(self, padded: torch.Tensor, image_sizes: list[tuple[int, int]],
                features: OrderedDict[str, torch.Tensor]) -> list[torch.Tensor]:
        levels = list(features.values())
        if len(levels) != len(self.sizes):
            raise ValueError(f"RPN: {len(levels)} feature levels, {len(self.sizes)} anchor sizes")
        logits, codes = self.head(levels)
        grids = [tuple(x.shape[-2:]) for x in levels]
        anchors = [a.to(padded.device) for a in self.anchors(tuple(padded.shape[-2:]), grids)]
        s = self.settings
        proposals = []
        for i, image_size in enumerate(image_sizes):
            boxes, scores, level_ids = [], [], []
            for level, (logit, code, anchor) in enumerate(zip(logits, codes, anchors)):
                objectness = _flatten(logit[i:i + 1], 1)[0, :, 0]
                k = min(s.pre_nms_per_level, len(objectness))
                top, index = objectness.topk(k)
                deltas = _flatten(code[i:i + 1], 4)[0][index]
                boxes.append(self.box_coder.decode(deltas, anchor[index])[:, 0])
                scores.append(torch.sigmoid(top))
                level_ids.append(torch.full((k,), level, dtype=torch.int64, device=top.device))
            boxes = clip_boxes(torch.cat(boxes), image_size)
            scores, level_ids = torch.cat(scores), torch.cat(level_ids)
            keep = keep_large_boxes(boxes, s.min_size)
            keep = keep[scores[keep] >= s.score_threshold]
            boxes, scores, level_ids = boxes[keep], scores[keep], level_ids[keep]
            keep = batched_nms(boxes, scores, level_ids, s.nms_iou)[:s.post_nms]
            proposals.append(boxes[keep])
        return proposals
