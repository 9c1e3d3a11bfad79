"""The second stage of Mask R-CNN, inference only: box head and class scores per proposal,
per-class NMS, then a mask per detection, pasted back into the image.

Module names follow torchvision (``roi_heads.box_head.fc6``, ``.fc7``,
``roi_heads.box_predictor.cls_score``, ``.bbox_pred``, ``roi_heads.mask_head.K.0``,
``roi_heads.mask_predictor.conv5_mask``, ``.mask_fcn_logits``) so its checkpoints load.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import nn

from .box_ops import BoxCoder, batched_nms, clip_boxes, keep_large_boxes
from .roi_align import MultiScaleRoIAlign

#: RoIAlign bins per side for the box head (7 x 7, Mask R-CNN's choice)
BOX_POOL_SIZE = 7
#: RoIAlign bins per side for the mask head (14 x 14, upsampled to 28 x 28 masks)
MASK_POOL_SIZE = 14
#: hidden width of the box head's two fully connected layers
BOX_HEAD_WIDTH = 1024
#: channels of the mask head's convolutions
MASK_HEAD_CHANNELS = 256
#: convolutions of the mask head
MASK_HEAD_CONVS = 4
#: box-regression weights (wx, wy, ww, wh) of the second stage (normalise small targets)
BOX_HEAD_CODING_WEIGHTS = (10.0, 10.0, 5.0, 5.0)


class TwoMLPHead(nn.Module):
    """Flattened pooled features -> fc6 -> ReLU -> fc7 -> ReLU."""

    def __init__(self, in_features: int, width: int) -> None:
        super().__init__()
        self.fc6 = nn.Linear(in_features, width)
        self.fc7 = nn.Linear(width, width)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return F.relu(self.fc7(F.relu(self.fc6(x.flatten(start_dim=1)))))


class BoxPredictor(nn.Module):
    """Class logits (background = class 0) and one box code per class."""

    def __init__(self, width: int, num_classes: int) -> None:
        super().__init__()
        self.cls_score = nn.Linear(width, num_classes)
        self.bbox_pred = nn.Linear(width, num_classes * 4)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.cls_score(x), self.bbox_pred(x)


class MaskHead(nn.Sequential):
    """``MASK_HEAD_CONVS`` 3x3 conv + ReLU blocks (each a ``Sequential``: keys ``K.0``)."""

    def __init__(self, in_channels: int, channels: int, convs: int = MASK_HEAD_CONVS) -> None:
        blocks = []
        for k in range(convs):
            blocks.append(nn.Sequential(nn.Conv2d(in_channels if k == 0 else channels, channels,
                                                  3, padding=1), nn.ReLU(inplace=True)))
        super().__init__(*blocks)


class MaskPredictor(nn.Module):
    """2x transposed conv + ReLU, then one mask logit map per class."""

    def __init__(self, channels: int, num_classes: int) -> None:
        super().__init__()
        self.conv5_mask = nn.ConvTranspose2d(channels, channels, 2, stride=2)
        self.mask_fcn_logits = nn.Conv2d(channels, num_classes, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.mask_fcn_logits(F.relu(self.conv5_mask(x)))


@dataclass
class DetectionSettings:
    """Which second-stage boxes become detections (Mask R-CNN R50-FPN inference settings).

    Attributes
    ----------
    score_threshold : class probability a detection must exceed (0.05: drops the long tail
        of background-like boxes before NMS; the panoptic stage applies its own, higher one).
    nms_iou : IoU above which a lower-scoring box of the same class is dropped (0.5).
    detections_per_image : most detections kept per image (count, highest scores first).
    min_size : smallest box side kept, pixels (1e-2: only degenerate boxes go).
    """

    score_threshold: float = 0.05
    nms_iou: float = 0.5
    detections_per_image: int = 100
    min_size: float = 1e-2


class RoIHeads(nn.Module):
    """Detections ``list[dict(boxes, scores, labels, masks)]`` per image from proposals; the
    masks are (D, 1, 28, 28) probabilities of the detected class, not yet pasted."""

    def __init__(self, channels: int, num_classes: int, box_head_width: int = BOX_HEAD_WIDTH,
                 mask_channels: int = MASK_HEAD_CHANNELS,
                 feature_names: tuple[str, ...] = ("0", "1", "2", "3"),
                 settings: DetectionSettings | None = None) -> None:
        super().__init__()
        self.box_roi_pool = MultiScaleRoIAlign(feature_names, BOX_POOL_SIZE)
        self.box_head = TwoMLPHead(channels * BOX_POOL_SIZE ** 2, box_head_width)
        self.box_predictor = BoxPredictor(box_head_width, num_classes)
        self.mask_roi_pool = MultiScaleRoIAlign(feature_names, MASK_POOL_SIZE)
        self.mask_head = MaskHead(channels, mask_channels)
        self.mask_predictor = MaskPredictor(mask_channels, num_classes)
        self.box_coder = BoxCoder(BOX_HEAD_CODING_WEIGHTS)
        self.settings = settings or DetectionSettings()

    def _detections(self, logits: torch.Tensor, codes: torch.Tensor, proposals: torch.Tensor,
                    image_size: tuple[int, int]) -> dict[str, torch.Tensor]:
        s = self.settings
        num_classes = logits.shape[-1]
        boxes = clip_boxes(self.box_coder.decode(codes, proposals), image_size)  # (P, K, 4)
        scores = F.softmax(logits, dim=-1)
        labels = torch.arange(num_classes, device=logits.device).expand_as(scores)
        # class 0 is background: never a detection
        boxes, scores, labels = boxes[:, 1:].reshape(-1, 4), scores[:, 1:].reshape(-1), \
            labels[:, 1:].reshape(-1)
        keep = torch.where(scores > s.score_threshold)[0]
        keep = keep[keep_large_boxes(boxes[keep], s.min_size)]
        boxes, scores, labels = boxes[keep], scores[keep], labels[keep]
        keep = batched_nms(boxes, scores, labels, s.nms_iou)[:s.detections_per_image]
        return {"boxes": boxes[keep], "scores": scores[keep], "labels": labels[keep]}

    def forward(self, features: dict[str, torch.Tensor], proposals: list[torch.Tensor],
                image_sizes: list[tuple[int, int]]) -> list[dict[str, torch.Tensor]]:
        pooled = self.box_roi_pool(features, proposals, image_sizes)
        logits, codes = self.box_predictor(self.box_head(pooled))
        counts = [len(p) for p in proposals]
        results = [self._detections(lg, cd, pr, size) for lg, cd, pr, size in
                   zip(logits.split(counts), codes.split(counts), proposals, image_sizes)]
        boxes = [r["boxes"] for r in results]
        mask_logits = self.mask_predictor(self.mask_head(
            self.mask_roi_pool(features, boxes, image_sizes)))
        per_image = mask_logits.split([len(b) for b in boxes])
        for result, logits_of_image in zip(results, per_image):
            index = torch.arange(len(result["labels"]), device=logits_of_image.device)
            result["masks"] = torch.sigmoid(logits_of_image[index, result["labels"]])[:, None]
        return results


def paste_masks(masks: torch.Tensor, boxes: torch.Tensor, image_size: tuple[int, int]) -> torch.Tensor:
    """(D, 1, H, W) full-image mask probabilities from (D, 1, M, M) box masks.

    Each M x M mask is padded by one zero cell (so its border fades out instead of ending
    sharply), its box grown by the same (M + 2) / M, rounded to whole pixels; the mask is
    resized bilinearly to that box and copied in where the box overlaps the image.
    """
    height, width = image_size
    out = masks.new_zeros((len(masks), 1, height, width))
    if len(masks) == 0:
        return out
    m = masks.shape[-1]
    padded = F.pad(masks, (1, 1, 1, 1))
    scale = (m + 2) / m
    half_w = (boxes[:, 2] - boxes[:, 0]) * 0.5 * scale
    half_h = (boxes[:, 3] - boxes[:, 1]) * 0.5 * scale
    cx, cy = (boxes[:, 2] + boxes[:, 0]) * 0.5, (boxes[:, 3] + boxes[:, 1]) * 0.5
    grown = torch.stack([cx - half_w, cy - half_h, cx + half_w, cy + half_h], 1).to(torch.int64)
    for k, (x1, y1, x2, y2) in enumerate(grown.tolist()):
        # the grown box covers pixels x1..x2 inclusive
        box_w, box_h = max(x2 - x1 + 1, 1), max(y2 - y1 + 1, 1)
        resized = F.interpolate(padded[k:k + 1], size=(box_h, box_w), mode="bilinear",
                                align_corners=False)[0, 0]
        left, right = max(x1, 0), min(x2 + 1, width)
        top, bottom = max(y1, 0), min(y2 + 1, height)
        if right > left and bottom > top:
            out[k, 0, top:bottom, left:right] = resized[top - y1:bottom - y1, left - x1:right - x1]
    return out
