"""RoIAlign (He et al. 2017) in plain torch, and its multi-scale use on a feature pyramid.

Each box is split into ``output x output`` bins; each bin averages the bilinearly interpolated
feature at ``sampling_ratio x sampling_ratio`` regularly spaced points (bin centres of a finer
grid). Box coordinates are scaled by the level's ``spatial_scale`` with no half-pixel shift
(torchvision's ``aligned=False``, what Mask R-CNN R50-FPN was trained with), and a box is at
least one feature cell wide and high.

A sample point more than one cell outside the map contributes zero; one within a cell of the
border is clamped onto it (the convention of the reference implementation).
"""

from __future__ import annotations

import math

import torch

#: sample points per bin along each axis (Mask R-CNN: 2, i.e. 4 points per bin)
SAMPLING_RATIO = 2
#: box side (square root of area, input pixels) that maps to :data:`CANONICAL_LEVEL` (the
#: ImageNet pre-training size, as in the FPN paper's eq. 1)
CANONICAL_BOX_SIZE = 224
#: pyramid level (log2 of its stride) of a box of :data:`CANONICAL_BOX_SIZE`
CANONICAL_LEVEL = 4
#: added to log2 before flooring, so a box exactly at a level boundary is not lowered by
#: rounding error
LEVEL_EPS = 1e-6
#: boxes pooled at once: bounds the (boxes, samples, samples, channels) temporaries to ~50 MB
#: for 256 channels and the mask head's 28 x 28 samples
BOXES_PER_CHUNK = 64


def _axis_weights(coords: torch.Tensor, size: int) -> tuple[torch.Tensor, torch.Tensor,
                                                             torch.Tensor, torch.Tensor]:
    """Bilinear taps along one axis: (low index, high index, low weight, high weight), each
    shaped like ``coords``; weights are zero for points more than a cell outside."""
    valid = (coords >= -1.0) & (coords <= size)
    c = coords.clamp(min=0)
    low = c.floor().to(torch.int64)
    at_end = low >= size - 1
    low = torch.where(at_end, torch.full_like(low, size - 1), low)
    high = torch.where(at_end, low, low + 1)
    c = torch.where(at_end, low.to(c.dtype), c)
    frac = c - low.to(c.dtype)
    valid = valid.to(c.dtype)
    return low, high, (1 - frac) * valid, frac * valid


def roi_align(features: torch.Tensor, boxes: torch.Tensor, batch_index: torch.Tensor,
              output_size: int, spatial_scale: float,
              sampling_ratio: int = SAMPLING_RATIO) -> torch.Tensor:
    """(K, C, output, output) pooled features of ``boxes`` (K, 4) in input pixels, box k
    taken from image ``batch_index[k]`` of ``features`` (N, C, H, W)."""
    k_boxes = len(boxes)
    channels, height, width = features.shape[1:]
    if k_boxes == 0:
        return features.new_zeros((0, channels, output_size, output_size))
    scaled = boxes.to(features.dtype) * spatial_scale
    start = scaled[:, :2]
    extent = (scaled[:, 2:] - start).clamp(min=1.0)  # (K, 2) box width, height in cells
    bin_size = extent / output_size
    # sample offsets within the box, in bins: (i + (s + 0.5) / ratio) for bin i, sample s
    steps = output_size * sampling_ratio
    offsets = (torch.arange(steps, dtype=features.dtype, device=features.device) + 0.5) / sampling_ratio
    xs = start[:, 0, None] + offsets[None] * bin_size[:, 0, None]  # (K, steps)
    ys = start[:, 1, None] + offsets[None] * bin_size[:, 1, None]
    x0, x1, wx0, wx1 = _axis_weights(xs, width)
    y0, y1, wy0, wy1 = _axis_weights(ys, height)
    # features as rows of channels, so one gather reads a sample point of any image
    rows = features.permute(0, 2, 3, 1).reshape(-1, channels)
    image_offset = (batch_index.to(torch.int64) * (height * width))[:, None, None]
    pooled = []
    for chunk in range(0, k_boxes, BOXES_PER_CHUNK):
        part = slice(chunk, chunk + BOXES_PER_CHUNK)
        total = 0
        for ys_index, wy in ((y0, wy0), (y1, wy1)):
            for xs_index, wx in ((x0, wx0), (x1, wx1)):
                index = image_offset[part] + ys_index[part, :, None] * width + xs_index[part, None, :]
                weight = wy[part, :, None] * wx[part, None, :]
                total = total + rows[index] * weight[..., None]  # (k, steps, steps, C)
        k = total.shape[0]
        total = total.view(k, output_size, sampling_ratio, output_size, sampling_ratio, channels)
        pooled.append(total.mean(dim=(2, 4)).permute(0, 3, 1, 2))
    return torch.cat(pooled)


def level_of_boxes(boxes: torch.Tensor, lowest: int, highest: int) -> torch.Tensor:
    """Pyramid level index (0 = ``lowest``) of each box by its size, FPN paper eq. 1:
    ``floor(4 + log2(sqrt(area) / 224))`` clamped into [lowest, highest]."""
    area = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    level = torch.floor(CANONICAL_LEVEL + torch.log2(torch.sqrt(area) / CANONICAL_BOX_SIZE) + LEVEL_EPS)
    return (level.clamp(min=lowest, max=highest) - lowest).to(torch.int64)


class MultiScaleRoIAlign(torch.nn.Module):
    """RoIAlign over the pyramid levels ``names``, each box read from the level its size
    selects. No parameters (it holds no state-dict entries).

    Parameters
    ----------
    names : feature keys used, finest first (Mask R-CNN: "0".."3", not "pool").
    output_size : bins per side (box head 7, mask head 14).
    """

    def __init__(self, names: tuple[str, ...], output_size: int,
                 sampling_ratio: int = SAMPLING_RATIO) -> None:
        super().__init__()
        self.names, self.output_size, self.sampling_ratio = tuple(names), output_size, sampling_ratio

    def forward(self, features: dict[str, torch.Tensor], boxes: list[torch.Tensor],
                image_sizes: list[tuple[int, int]]) -> torch.Tensor:
        maps = [features[n] for n in self.names]
        largest = max(s[0] for s in image_sizes), max(s[1] for s in image_sizes)
        # each level's scale is the power of two nearest to its size over the image size
        scales = [2.0 ** round(math.log2(m.shape[-2] / largest[0])) for m in maps]
        lowest = -round(math.log2(scales[0]))
        highest = -round(math.log2(scales[-1]))
        all_boxes = torch.cat(boxes)
        batch_index = torch.cat([torch.full((len(b),), i, dtype=torch.int64, device=b.device)
                                 for i, b in enumerate(boxes)])
        channels = maps[0].shape[1]
        out = maps[0].new_zeros((len(all_boxes), channels, self.output_size, self.output_size))
        if len(all_boxes) == 0:
            return out
        levels = level_of_boxes(all_boxes, lowest, highest) if len(maps) > 1 else \
            torch.zeros(len(all_boxes), dtype=torch.int64, device=all_boxes.device)
        for level, (feature, scale) in enumerate(zip(maps, scales)):
            members = torch.where(levels == level)[0]
            if len(members):
                out[members] = roi_align(feature, all_boxes[members], batch_index[members],
                                         self.output_size, scale, self.sampling_ratio)
        return out
