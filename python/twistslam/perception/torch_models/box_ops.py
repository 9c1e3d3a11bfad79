"""Box arithmetic of the two-stage detector in plain torch: the (dx, dy, dw, dh) box coding,
clipping, small-box removal, and greedy non-maximum suppression (NMS), also batched so boxes of
different classes (or pyramid levels) never suppress each other.

Boxes are ``(N, 4)`` float tensors ``(x1, y1, x2, y2)`` in pixels; a box's width is
``x2 - x1`` (no "+1" pixel convention), as in torchvision.
"""

from __future__ import annotations

import math

import numpy as np
import torch

#: largest log-scale change a decoded box may get: a box grows at most 1000/16 = 62.5 times,
#: so an untrained or diverging regressor cannot produce overflowing exp() sizes
BOX_LOG_SCALE_CLIP = math.log(1000.0 / 16)


class BoxCoder:
    """Encodes a box relative to a reference box as ``(dx, dy, dw, dh)`` scaled by ``weights``.

    ``dx = wx (x_c - x_c_ref) / w_ref``, ``dw = ww log(w / w_ref)`` (same for y, h), with
    box centres ``x_c = x1 + w / 2``.

    Parameters
    ----------
    weights : (wx, wy, ww, wh): the proposal network uses (1, 1, 1, 1), the box head
        (10, 10, 5, 5) (its regression targets are small, the weights normalise them).
    """

    def __init__(self, weights: tuple[float, float, float, float],
                 log_scale_clip: float = BOX_LOG_SCALE_CLIP) -> None:
        self.weights = weights
        self.log_scale_clip = log_scale_clip

    def encode(self, boxes: torch.Tensor, references: torch.Tensor) -> torch.Tensor:
        """(N, 4) codes of ``boxes`` relative to ``references`` (both (N, 4))."""
        wx, wy, ww, wh = self.weights
        ref_w = references[:, 2] - references[:, 0]
        ref_h = references[:, 3] - references[:, 1]
        ref_x = references[:, 0] + 0.5 * ref_w
        ref_y = references[:, 1] + 0.5 * ref_h
        w = boxes[:, 2] - boxes[:, 0]
        h = boxes[:, 3] - boxes[:, 1]
        x = boxes[:, 0] + 0.5 * w
        y = boxes[:, 1] + 0.5 * h
        return torch.stack([wx * (x - ref_x) / ref_w, wy * (y - ref_y) / ref_h,
                            ww * torch.log(w / ref_w), wh * torch.log(h / ref_h)], dim=1)

    def decode(self, codes: torch.Tensor, references: torch.Tensor) -> torch.Tensor:
        """Boxes from ``codes`` (N, 4 K) relative to ``references`` (N, 4): (N, K, 4), one box
        per group of four codes (the box head predicts one box per class)."""
        codes = codes.reshape(codes.shape[0], codes.shape[1] // 4, 4).to(references.dtype)
        wx, wy, ww, wh = self.weights
        ref_w = (references[:, 2] - references[:, 0])[:, None]
        ref_h = (references[:, 3] - references[:, 1])[:, None]
        ref_x = references[:, 0, None] + 0.5 * ref_w
        ref_y = references[:, 1, None] + 0.5 * ref_h
        dw = torch.clamp(codes[..., 2] / ww, max=self.log_scale_clip)
        dh = torch.clamp(codes[..., 3] / wh, max=self.log_scale_clip)
        x = codes[..., 0] / wx * ref_w + ref_x
        y = codes[..., 1] / wy * ref_h + ref_y
        half_w = 0.5 * torch.exp(dw) * ref_w
        half_h = 0.5 * torch.exp(dh) * ref_h
        return torch.stack([x - half_w, y - half_h, x + half_w, y + half_h], dim=2)


def clip_boxes(boxes: torch.Tensor, image_size: tuple[int, int]) -> torch.Tensor:
    """Boxes (..., 4) clamped into an image of ``(height, width)``."""
    height, width = image_size
    x = boxes[..., 0::2].clamp(0, width)
    y = boxes[..., 1::2].clamp(0, height)
    return torch.stack([x[..., 0], y[..., 0], x[..., 1], y[..., 1]], dim=-1)


def keep_large_boxes(boxes: torch.Tensor, min_size: float) -> torch.Tensor:
    """Indices of the boxes whose width and height are both >= ``min_size`` pixels."""
    w = boxes[:, 2] - boxes[:, 0]
    h = boxes[:, 3] - boxes[:, 1]
    return torch.where((w >= min_size) & (h >= min_size))[0]


def box_iou(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """(N, M) intersection over union of the boxes ``a`` (N, 4) and ``b`` (M, 4)."""
    area_a = (a[:, 2] - a[:, 0]) * (a[:, 3] - a[:, 1])
    area_b = (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])
    top_left = torch.maximum(a[:, None, :2], b[None, :, :2])
    bottom_right = torch.minimum(a[:, None, 2:], b[None, :, 2:])
    wh = (bottom_right - top_left).clamp(min=0)
    inter = wh[..., 0] * wh[..., 1]
    return inter / (area_a[:, None] + area_b[None, :] - inter)


def nms(boxes: torch.Tensor, scores: torch.Tensor, iou_threshold: float) -> torch.Tensor:
    """Greedy NMS: indices of the kept boxes, by decreasing score. A box is dropped when its
    IoU with a kept, higher-scoring box is strictly above ``iou_threshold``."""
    if boxes.numel() == 0:
        return torch.zeros(0, dtype=torch.int64, device=boxes.device)
    order = torch.argsort(scores, descending=True, stable=True)
    # the whole IoU matrix at once (a few thousand proposals: tens of MB), then one cheap
    # pass in sorted order over its thresholded rows
    overlaps = (box_iou(boxes[order], boxes[order]) > iou_threshold).cpu().numpy()
    suppressed = np.zeros(len(order), dtype=bool)
    kept = []
    for i in range(len(order)):
        if suppressed[i]:
            continue
        kept.append(i)
        suppressed |= overlaps[i]
    return order[torch.as_tensor(kept, dtype=torch.int64, device=boxes.device)]


#: above this many boxes, batched NMS runs group by group: the shifted-boxes trick needs one
#: N x N IoU matrix (5 pyramid levels x 1000 proposals would be 25 M entries, ~0.5 GB of
#: temporaries), the per-group loop only the groups' own blocks
OFFSET_TRICK_MAX_BOXES = 2000


def batched_nms(boxes: torch.Tensor, scores: torch.Tensor, groups: torch.Tensor,
                iou_threshold: float) -> torch.Tensor:
    """NMS within each group (class or pyramid level) only; indices by decreasing score.

    Up to :data:`OFFSET_TRICK_MAX_BOXES` boxes, each group's boxes are shifted by
    ``group * (largest coordinate + 1)`` so boxes of different groups never overlap and one
    NMS serves all groups; above it, one NMS per group (same result, less memory)."""
    if boxes.numel() == 0:
        return torch.zeros(0, dtype=torch.int64, device=boxes.device)
    if len(boxes) <= OFFSET_TRICK_MAX_BOXES:
        offsets = groups.to(boxes.dtype) * (boxes.max() + 1)
        return nms(boxes + offsets[:, None], scores, iou_threshold)
    kept = []
    for group in torch.unique(groups):
        members = torch.where(groups == group)[0]
        kept.append(members[nms(boxes[members], scores[members], iou_threshold)])
    kept = torch.cat(kept)
    return kept[torch.argsort(scores[kept], descending=True, stable=True)]
