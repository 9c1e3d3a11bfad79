"""Frames and box coding of 3DSSD.

The network works in a LiDAR-like frame l (x forward, y left, z up), where boxes are
``[x, y, z, l, w, h, theta]`` (geometric centre; ``theta`` the heading about z, 0 along x):
the frame the paper's choices (heading bins, point range, shift limits) were made in. The
rest of twistslam speaks the rectified camera frame c (x right, y down, z forward) with KITTI
``rotation_y``; the two differ by a fixed axis permutation, so ``theta = -ry - pi/2``.
"""

from __future__ import annotations

import math

import numpy as np
import torch

TWO_PI = 2.0 * math.pi


def camera_to_lidar_points(xyz_c: np.ndarray) -> np.ndarray:
    """(N, 3) rectified camera coordinates -> the LiDAR-like frame (x = z_c, y = -x_c, z = -y_c)."""
    return np.stack([xyz_c[:, 2], -xyz_c[:, 0], -xyz_c[:, 1]], axis=1)


def camera_to_lidar_boxes(boxes_c: np.ndarray) -> np.ndarray:
    """(N, 7) ``[x, y, z, l, w, h, ry]`` in frame c -> ``[x, y, z, l, w, h, theta]`` in frame l."""
    boxes_c = np.asarray(boxes_c, dtype=np.float64).reshape(-1, 7)
    out = np.empty_like(boxes_c)
    out[:, :3] = camera_to_lidar_points(boxes_c[:, :3])
    out[:, 3:6] = boxes_c[:, 3:6]
    out[:, 6] = -boxes_c[:, 6] - math.pi / 2
    return out


def lidar_to_camera_boxes(boxes_l: np.ndarray) -> np.ndarray:
    """Inverse of :func:`camera_to_lidar_boxes`; ``ry`` wrapped to [-pi, pi)."""
    boxes_l = np.asarray(boxes_l, dtype=np.float64).reshape(-1, 7)
    out = np.empty_like(boxes_l)
    out[:, 0], out[:, 1], out[:, 2] = -boxes_l[:, 1], -boxes_l[:, 2], boxes_l[:, 0]
    out[:, 3:6] = boxes_l[:, 3:6]
    out[:, 6] = np.mod(-boxes_l[:, 6] - math.pi / 2 + math.pi, TWO_PI) - math.pi
    return out


def box_local_coordinates(points: torch.Tensor, boxes: torch.Tensor) -> torch.Tensor:
    """Offsets of ``points`` (P, 3) from each box centre in that box's own axes: (P, G, 3)
    for ``boxes`` (G, 7) in frame l."""
    offset = points.unsqueeze(1) - boxes[:, :3].unsqueeze(0)
    cos, sin = torch.cos(boxes[:, 6]), torch.sin(boxes[:, 6])
    along = offset[..., 0] * cos + offset[..., 1] * sin
    across = -offset[..., 0] * sin + offset[..., 1] * cos
    return torch.stack([along, across, offset[..., 2]], dim=-1)


def points_in_boxes(points: torch.Tensor, boxes: torch.Tensor, margin: float = 0.0) -> torch.Tensor:
    """(P, G) bool: point p lies inside box g enlarged by ``margin`` metres on every side."""
    local = box_local_coordinates(points, boxes)
    half = boxes[:, 3:6].unsqueeze(0) / 2 + margin
    return (local.abs() <= half).all(dim=-1)


def centreness(local: torch.Tensor, sizes: torch.Tensor) -> torch.Tensor:
    """3DSSD's centre-ness of points at box-local offsets ``local`` (..., 3) in boxes of
    ``sizes`` (..., 3): the cube root of the product, over the three axes, of
    min(distance to the two faces) / max(...). 1 at the centre, 0 on a face (clamped outside)."""
    half = sizes / 2
    near = (half - local.abs()).clamp(min=0)
    far = half + local.abs()
    ratio = (near / far.clamp(min=1e-6)).prod(dim=-1)
    return ratio.clamp(min=0).pow(1.0 / 3.0)


def encode_heading(theta: torch.Tensor, bins: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Heading -> (bin index, residual in units of half a bin, in [-1, 1])."""
    width = TWO_PI / bins
    shifted = torch.remainder(theta + width / 2, TWO_PI)
    index = torch.div(shifted, width, rounding_mode="floor").long().clamp(max=bins - 1)
    residual = (shifted - (index.to(theta.dtype) + 0.5) * width) / (width / 2)
    return index, residual


def decode_heading(index: torch.Tensor, residual: torch.Tensor, bins: int) -> torch.Tensor:
    """Inverse of :func:`encode_heading`."""
    width = TWO_PI / bins
    return index.to(residual.dtype) * width + residual * (width / 2)


def decode_boxes(candidates: torch.Tensor, codes: torch.Tensor, mean_sizes: torch.Tensor,
                 bins: int) -> torch.Tensor:
    """Candidate points (..., 3), box codes (..., 6 + 2 bins) and the mean size of each
    candidate's class (..., 3) -> boxes (..., 7) in frame l.

    Code layout: centre offset (3, metres), log size ratio to the class mean (3), heading
    bin logits (bins), heading residual of each bin (bins, half-bin units)."""
    centre = candidates + codes[..., 0:3]
    size = mean_sizes * torch.exp(codes[..., 3:6].clamp(max=4.0))  # exp(4) = 55x: a finite bound
    bin_logits = codes[..., 6:6 + bins]
    index = bin_logits.argmax(dim=-1)
    residual = torch.gather(codes[..., 6 + bins:6 + 2 * bins], -1, index.unsqueeze(-1)).squeeze(-1)
    theta = decode_heading(index, residual, bins)
    return torch.cat([centre, size, theta.unsqueeze(-1)], dim=-1)


def rotated_nms_bev(boxes_c: np.ndarray, scores: np.ndarray, iou_threshold: float) -> np.ndarray:
    """Greedy non-maximum suppression with the exact bird's-eye-view IoU of rotated boxes
    (``twistslam._core.geometry.box_iou_bev``, frame-c boxes): indices of the kept boxes,
    best score first."""
    from twistslam._core.geometry import box_iou_bev  # the C++ core; imported on use

    order = np.argsort(-np.asarray(scores), kind="stable")
    if len(order) == 0:
        return order
    iou = np.asarray(box_iou_bev(boxes_c[order], boxes_c[order]))
    suppressed = np.zeros(len(order), dtype=bool)
    keep = []
    for i in range(len(order)):
        if suppressed[i]:
            continue
        keep.append(order[i])
        suppressed |= iou[i] > iou_threshold
    return np.asarray(keep, dtype=np.int64)
