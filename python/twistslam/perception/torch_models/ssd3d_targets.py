"""Training targets and losses of 3DSSD, from ground-truth boxes in frame l.

* Vote (shift) loss: every feature-FPS seed inside a ground-truth box should shift onto that
  box's centre (smooth L1, averaged over those seeds).
* Classification: a candidate (shifted seed) inside a box is a positive of the box's class,
  with the candidate's centre-ness as soft target (candidates near the centre score high, so
  NMS keeps them); candidates inside boxes of ignored types (Van, Truck, ...) carry no loss;
  all others are negatives. Sigmoid binary cross-entropy, normalised by the positive count.
* Box regression on the positives: centre offset and log size ratio (smooth L1), heading bin
  (cross-entropy) and the residual within the true bin (smooth L1).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F

from .ssd3d_boxes import box_local_coordinates, centreness, encode_heading, points_in_boxes


@dataclass
class FrameTargets:
    """The ground truth of one frame in frame l.

    Attributes
    ----------
    boxes : (G, 7) float32 ``[x, y, z, l, w, h, theta]`` of the detected classes.
    labels : (G,) int64 class index into the config's ``classes``.
    ignore : (I, 7) float32 boxes of other object types: candidates inside get no loss.
    """

    boxes: torch.Tensor
    labels: torch.Tensor
    ignore: torch.Tensor


#: weights of the loss terms: 3DSSD weighs all its terms 1 (its corner loss is not used here)
LOSS_WEIGHTS = {"cls": 1.0, "vote": 1.0, "centre": 1.0, "size": 1.0, "bin": 1.0, "residual": 1.0}


def assign(points: torch.Tensor, boxes: torch.Tensor) -> torch.Tensor:
    """(P,) index of the box each point lies in (the nearest centre when several), -1 if none."""
    if len(boxes) == 0:
        return torch.full((len(points),), -1, dtype=torch.long, device=points.device)
    inside = points_in_boxes(points, boxes)
    distance = torch.cdist(points, boxes[:, :3]).masked_fill(~inside, float("inf"))
    best = distance.argmin(dim=1)
    return torch.where(inside.any(dim=1), best, torch.full_like(best, -1))


def frame_losses(seeds, shifts, candidates, logits, codes, target: FrameTargets,
                 mean_sizes: torch.Tensor, bins: int) -> dict[str, torch.Tensor]:
    """The loss terms of one frame: seeds, shifts, candidates (M, 3), logits (M, K), codes
    (M, 6 + 2 bins) -> dict of scalar tensors (keys of :data:`LOSS_WEIGHTS`)."""
    zero = codes.sum() * 0.0  # keeps every term attached to the graph even when empty
    boxes, labels = target.boxes, target.labels
    # vote: seeds on objects move to the centre
    seed_box = assign(seeds, boxes)
    on_object = seed_box >= 0
    vote = (F.smooth_l1_loss(shifts[on_object], boxes[seed_box[on_object], :3] - seeds[on_object],
                             reduction="sum") / on_object.sum().clamp(min=1)) if on_object.any() else zero
    # classification with centre-ness targets (candidates are detached: the shift is trained
    # by the vote loss only, as in the paper)
    anchor = candidates.detach()
    box_of = assign(anchor, boxes)
    positive = box_of >= 0
    cls_target = torch.zeros_like(logits)
    weight = torch.ones_like(logits)
    if len(target.ignore):
        ignored = points_in_boxes(anchor, target.ignore).any(dim=1) & ~positive
        weight[ignored] = 0.0
    n_pos = positive.sum().clamp(min=1)
    terms = {"vote": vote}
    if positive.any():
        matched = boxes[box_of[positive]]
        local = box_local_coordinates(anchor[positive], matched).diagonal(dim1=0, dim2=1).T
        cls_target[positive, labels[box_of[positive]]] = centreness(local, matched[:, 3:6])
        code = codes[positive]
        terms["centre"] = F.smooth_l1_loss(code[:, 0:3], matched[:, :3] - anchor[positive], reduction="sum") / n_pos
        log_size = torch.log(matched[:, 3:6] / mean_sizes[labels[box_of[positive]]])
        terms["size"] = F.smooth_l1_loss(code[:, 3:6], log_size, reduction="sum") / n_pos
        bin_index, residual = encode_heading(matched[:, 6], bins)
        terms["bin"] = F.cross_entropy(code[:, 6:6 + bins], bin_index, reduction="sum") / n_pos
        predicted = torch.gather(code[:, 6 + bins:], 1, bin_index.unsqueeze(1)).squeeze(1)
        terms["residual"] = F.smooth_l1_loss(predicted, residual, reduction="sum") / n_pos
    else:
        terms.update(centre=zero, size=zero, bin=zero, residual=zero)
    terms["cls"] = F.binary_cross_entropy_with_logits(logits, cls_target, weight, reduction="sum") / n_pos
    return terms


def batch_losses(output: dict[str, torch.Tensor], targets: list[FrameTargets], mean_sizes: torch.Tensor,
                 bins: int) -> dict[str, torch.Tensor]:
    """Mean over the batch of each loss term, plus their weighted sum under ``"total"``."""
    per_frame = [frame_losses(output["seeds"][b], output["shifts"][b], output["candidates"][b],
                              output["logits"][b], output["codes"][b], target, mean_sizes, bins)
                 for b, target in enumerate(targets)]
    losses = {key: torch.stack([terms[key] for terms in per_frame]).mean() for key in LOSS_WEIGHTS}
    losses["total"] = sum(LOSS_WEIGHTS[key] * value for key, value in losses.items())
    return losses
