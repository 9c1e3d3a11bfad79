"""3DSSD in plain torch: set abstraction with fusion sampling, candidate generation by
shifts, and the anchor-free head (see :mod:`.ssd3d_config` for what is kept from the paper).

    model = SSD3D(SMALL)
    output = model(points)                       # (B, N, 4) x y z intensity, frame l
    losses = model.losses(output, targets)       # training
    boxes, scores, labels = model.detect(output[...])  # inference, per frame
"""

from __future__ import annotations

import torch
from torch import nn

from .ssd3d_boxes import decode_boxes
from .ssd3d_config import SSD3DConfig
from .ssd3d_layers import MultiScaleGrouping, PointHead, SetAbstraction, ShiftLayer
from .ssd3d_targets import FrameTargets, batch_losses

#: input channels per point besides x y z: the LiDAR intensity
POINT_FEATURES = 1


class SSD3D(nn.Module):
    """The network. ``forward`` returns a dict of per-candidate tensors:

    ``seeds`` (B, M, 3) the feature-FPS points of the last SA layer; ``shifts`` (B, M, 3) their
    predicted offsets to an object centre; ``candidates`` = seeds + shifts; ``logits``
    (B, M, classes); ``codes`` (B, M, 6 + 2 bins) the box codes (see :func:`decode_boxes`).
    """

    def __init__(self, config: SSD3DConfig) -> None:
        super().__init__()
        self.config = config
        channels = POINT_FEATURES
        layers = []
        for layer in config.sa_layers:
            layers.append(SetAbstraction(channels, layer))
            channels = layer.out_channels
        self.sa_layers = nn.ModuleList(layers)
        self.shift = ShiftLayer(channels, config.vote_channels, config.max_shift)
        self.candidate_grouping = MultiScaleGrouping(channels, config.cg_radii, config.cg_samples,
                                                     config.cg_mlps, config.cg_channels)
        self.head = PointHead(config.cg_channels, config.head_channels, len(config.classes),
                              config.heading_bins)
        self.register_buffer("mean_sizes", torch.tensor(config.mean_sizes, dtype=torch.float32),
                             persistent=False)

    def forward(self, points: torch.Tensor) -> dict[str, torch.Tensor]:
        """``points`` (B, N, 3 + 1) float32 in frame l -> the per-candidate tensors."""
        xyz = points[..., :3].contiguous()
        features = points[..., 3:].transpose(1, 2).contiguous()
        for layer in self.sa_layers:
            xyz, features = layer(xyz, features)
        n_seeds = self.config.sa_layers[-1].n_ffps  # fusion sampling puts the F-FPS points first
        seeds, seed_features = xyz[:, :n_seeds], features[:, :, :n_seeds]
        shifts = self.shift(seed_features)
        candidates = seeds + shifts
        # candidates are centres of the last grouping; their location is not differentiated
        # through (the shift learns from the vote loss alone)
        grouped = self.candidate_grouping(xyz, features, candidates.detach())
        logits, codes = self.head(grouped)
        return {"seeds": seeds, "shifts": shifts, "candidates": candidates, "logits": logits, "codes": codes}

    def losses(self, output: dict[str, torch.Tensor], targets: list[FrameTargets]) -> dict[str, torch.Tensor]:
        """Loss terms and their ``"total"`` for a batch (one :class:`FrameTargets` per frame)."""
        return batch_losses(output, targets, self.mean_sizes, self.config.heading_bins)

    @torch.no_grad()
    def decode(self, output: dict[str, torch.Tensor], frame: int = 0) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Every candidate of batch element ``frame`` as a box: boxes (M, 7) in frame l,
        scores (M,) (sigmoid of the best class logit), labels (M,) class indices. NMS and
        score thresholds are the caller's (see :class:`~twistslam.perception.detector_3dssd.Detector3DSSD`)."""
        scores, labels = torch.sigmoid(output["logits"][frame]).max(dim=1)
        boxes = decode_boxes(output["candidates"][frame], output["codes"][frame], self.mean_sizes[labels],
                             self.config.heading_bins)
        return boxes, scores, labels
