"""The RAFT optical-flow network (Teed & Deng, "RAFT: Recurrent All-Pairs Field Transforms for
Optical Flow", ECCV 2020) in plain torch, with torchvision's ``raft_small`` / ``raft_large``
architectures and state-dict layout: a torchvision checkpoint (e.g. the ``raft_small_C_T_V2``
file) loads with ``load_state_dict(strict=True)``. torchvision itself is not needed.

    network = raft_small()
    network.load_state_dict(torch.load("raft_small_C_T_V2-01064c6d.pth", weights_only=True))
    flows = network.eval()(image1, image2, num_flow_updates=12)  # images in [-1, 1], H, W % 8 == 0

:class:`RaftConfig` describes any size, e.g. a tiny untrained model for tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import nn

from .raft_blocks import (CONVEX_NEIGHBOURS, DOWNSAMPLE_FACTOR, CorrelationPyramid, FeatureEncoder, conv_layer,
                          pixel_grid, upsample_bilinear, upsample_convex)

#: torchvision scales the upsampling-mask logits by 1/4 (from the original RAFT code, where it
#: damped that branch's gradients); trained weights expect it
MASK_LOGIT_SCALE = 0.25


@dataclass(frozen=True)
class RaftConfig:
    """Sizes of a RAFT network. The defaults are ``raft_small``'s; see :data:`RAFT_LARGE`.

    Attributes
    ----------
    feature_layers, context_layers : encoder channels (stem, 3 stages, output); the context
        output splits into the GRU's initial hidden state and the context features.
    feature_block, context_block : "residual" or "bottleneck".
    feature_norm, context_norm : None, "instance" or "batch".
    corr_levels, corr_radius : correlation pyramid levels and lookup radius (cells).
    motion_corr_layers : 1 or 2 conv widths applied to the correlation features.
    motion_flow_layers : 2 conv widths applied to the current flow.
    motion_channels : motion-encoder output channels (including the 2 flow channels).
    hidden_size : GRU hidden state channels.
    gru_kernels : one kernel per ConvGRU, applied in turn: ((3, 3),) or the separable
        ((1, 5), (5, 1)).
    flow_head_hidden : channels of the flow head's hidden layer.
    mask_hidden : channels of the convex-upsampling mask predictor; None upsamples bilinearly.
    """

    feature_layers: tuple[int, ...] = (32, 32, 64, 96, 128)
    feature_block: str = "bottleneck"
    feature_norm: str | None = "instance"
    context_layers: tuple[int, ...] = (32, 32, 64, 96, 160)
    context_block: str = "bottleneck"
    context_norm: str | None = None
    corr_levels: int = 4
    corr_radius: int = 3
    motion_corr_layers: tuple[int, ...] = (96,)
    motion_flow_layers: tuple[int, int] = (64, 32)
    motion_channels: int = 82
    hidden_size: int = 96
    gru_kernels: tuple[tuple[int, int], ...] = ((3, 3),)
    flow_head_hidden: int = 128
    mask_hidden: int | None = None


RAFT_SMALL = RaftConfig()
RAFT_LARGE = RaftConfig(
    feature_layers=(64, 64, 96, 128, 256), feature_block="residual", feature_norm="instance",
    context_layers=(64, 64, 96, 128, 256), context_block="residual", context_norm="batch",
    corr_levels=4, corr_radius=4, motion_corr_layers=(256, 192), motion_flow_layers=(128, 64),
    motion_channels=128, hidden_size=128, gru_kernels=((1, 5), (5, 1)), flow_head_hidden=256, mask_hidden=256)


class MotionEncoder(nn.Module):
    """Correlation features and the current flow -> motion features (the flow appended)."""

    def __init__(self, corr_channels: int, corr_layers: tuple[int, ...], flow_layers: tuple[int, int],
                 out_channels: int) -> None:
        super().__init__()
        if len(corr_layers) not in (1, 2) or len(flow_layers) != 2:
            raise ValueError(f"RAFT motion encoder: expected 1-2 correlation and 2 flow layers, got "
                             f"{tuple(corr_layers)} and {tuple(flow_layers)}")
        self.convcorr1 = conv_layer(corr_channels, corr_layers[0], 1)
        self.convcorr2 = conv_layer(corr_layers[0], corr_layers[1], 3) if len(corr_layers) == 2 else nn.Identity()
        self.convflow1 = conv_layer(2, flow_layers[0], 7)
        self.convflow2 = conv_layer(flow_layers[0], flow_layers[1], 3)
        self.conv = conv_layer(corr_layers[-1] + flow_layers[1], out_channels - 2, 3)

    def forward(self, flow: torch.Tensor, corr: torch.Tensor) -> torch.Tensor:
        corr_features = self.convcorr2(self.convcorr1(corr))
        flow_features = self.convflow2(self.convflow1(flow))
        motion = self.conv(torch.cat([corr_features, flow_features], dim=1))
        return torch.cat([motion, flow], dim=1)


class ConvGRU(nn.Module):
    """Gated recurrent unit whose gates are convolutions over [hidden, input]."""

    def __init__(self, input_size: int, hidden_size: int, kernel: tuple[int, int]) -> None:
        super().__init__()
        padding = tuple((k - 1) // 2 for k in kernel)
        channels = hidden_size + input_size
        self.convz = nn.Conv2d(channels, hidden_size, kernel, padding=padding)  # update gate
        self.convr = nn.Conv2d(channels, hidden_size, kernel, padding=padding)  # reset gate
        self.convq = nn.Conv2d(channels, hidden_size, kernel, padding=padding)  # candidate state

    def forward(self, hidden: torch.Tensor, x: torch.Tensor) -> torch.Tensor:
        hx = torch.cat([hidden, x], dim=1)
        update = torch.sigmoid(self.convz(hx))
        reset = torch.sigmoid(self.convr(hx))
        candidate = torch.tanh(self.convq(torch.cat([reset * hidden, x], dim=1)))
        return hidden + update * (candidate - hidden)


class RecurrentBlock(nn.Module):
    """One ConvGRU per kernel, applied in turn (``convgru1``, ``convgru2``)."""

    def __init__(self, input_size: int, hidden_size: int, kernels: tuple[tuple[int, int], ...]) -> None:
        super().__init__()
        if len(kernels) not in (1, 2):
            raise ValueError(f"RAFT recurrent block: expected 1 or 2 GRU kernels, got {kernels}")
        self.grus = [f"convgru{i + 1}" for i in range(len(kernels))]
        for name, kernel in zip(self.grus, kernels):
            setattr(self, name, ConvGRU(input_size, hidden_size, tuple(kernel)))

    def forward(self, hidden: torch.Tensor, x: torch.Tensor) -> torch.Tensor:
        for name in self.grus:
            hidden = getattr(self, name)(hidden, x)
        return hidden


class FlowHead(nn.Module):
    """Hidden state -> flow increment (2 channels), through one 3x3 ReLU layer."""

    def __init__(self, in_channels: int, hidden: int) -> None:
        super().__init__()
        self.conv1 = nn.Conv2d(in_channels, hidden, 3, padding=1)
        self.conv2 = nn.Conv2d(hidden, 2, 3, padding=1)
        self.relu = nn.ReLU(inplace=True)

    def forward(self, hidden: torch.Tensor) -> torch.Tensor:
        return self.conv2(self.relu(self.conv1(hidden)))


class UpdateBlock(nn.Module):
    """One refinement step: motion encoding, GRU update of the hidden state, flow increment."""

    def __init__(self, config: RaftConfig, corr_channels: int) -> None:
        super().__init__()
        context_channels = config.context_layers[-1] - config.hidden_size
        self.motion_encoder = MotionEncoder(corr_channels, config.motion_corr_layers, config.motion_flow_layers,
                                            config.motion_channels)
        self.recurrent_block = RecurrentBlock(config.motion_channels + context_channels, config.hidden_size,
                                              config.gru_kernels)
        self.flow_head = FlowHead(config.hidden_size, config.flow_head_hidden)

    def forward(self, hidden, context, corr, flow):
        motion = self.motion_encoder(flow, corr)
        hidden = self.recurrent_block(hidden, torch.cat([context, motion], dim=1))
        return hidden, self.flow_head(hidden)


class MaskPredictor(nn.Module):
    """Hidden state -> logits of the convex upsampling weights (9 neighbours x 8 x 8 sub-pixels)."""

    def __init__(self, in_channels: int, hidden: int) -> None:
        super().__init__()
        self.convrelu = conv_layer(in_channels, hidden, 3)
        self.conv = nn.Conv2d(hidden, CONVEX_NEIGHBOURS * DOWNSAMPLE_FACTOR ** 2, 1)

    def forward(self, hidden: torch.Tensor) -> torch.Tensor:
        return MASK_LOGIT_SCALE * self.conv(self.convrelu(hidden))


class RAFT(nn.Module):
    """RAFT: features of both images, their all-pairs correlation pyramid, and a GRU that
    refines a 1/8-resolution flow field from zero by looking up correlations around each
    pixel's current target.

    Parameters
    ----------
    config : the sizes (:data:`RAFT_SMALL`, :data:`RAFT_LARGE` or a custom one).
    """

    def __init__(self, config: RaftConfig = RAFT_SMALL) -> None:
        super().__init__()
        if config.context_layers[-1] <= config.hidden_size:
            raise ValueError(f"RAFT: the context encoder's {config.context_layers[-1]} output channels must "
                             f"exceed the hidden state's {config.hidden_size} (the rest is the context)")
        self.config = config
        self.feature_encoder = FeatureEncoder(config.feature_layers, config.feature_block, config.feature_norm)
        self.context_encoder = FeatureEncoder(config.context_layers, config.context_block, config.context_norm)
        corr_channels = config.corr_levels * (2 * config.corr_radius + 1) ** 2
        self.update_block = UpdateBlock(config, corr_channels)
        self.mask_predictor = (None if config.mask_hidden is None
                               else MaskPredictor(config.hidden_size, config.mask_hidden))

    def forward(self, image1: torch.Tensor, image2: torch.Tensor, num_flow_updates: int = 12) -> list[torch.Tensor]:
        """Flow from ``image1`` to ``image2`` (N, 3, H, W), scaled to [-1, 1], H and W multiples
        of 8: a list of ``num_flow_updates`` (N, 2, H, W) predictions in pixels (x, y), the last
        the finest."""
        n, _, h, w = image1.shape
        if image2.shape != image1.shape:
            raise ValueError(f"RAFT: images differ in shape, {tuple(image1.shape)} vs {tuple(image2.shape)}")
        if h % DOWNSAMPLE_FACTOR or w % DOWNSAMPLE_FACTOR:
            raise ValueError(f"RAFT: image height and width must be multiples of {DOWNSAMPLE_FACTOR}, got {h} x {w}")
        if num_flow_updates < 1:
            raise ValueError(f"RAFT: num_flow_updates must be >= 1, got {num_flow_updates}")
        # both images in one batch: the instance norm is per image, so this only saves a pass
        features1, features2 = self.feature_encoder(torch.cat([image1, image2], dim=0)).chunk(2, dim=0)
        pyramid = CorrelationPyramid(features1, features2, levels=self.config.corr_levels,
                                     radius=self.config.corr_radius)
        hidden, context = self.context_encoder(image1).split(
            [self.config.hidden_size, self.config.context_layers[-1] - self.config.hidden_size], dim=1)
        hidden, context = torch.tanh(hidden), F.relu(context)

        start = pixel_grid(n, h // DOWNSAMPLE_FACTOR, w // DOWNSAMPLE_FACTOR, features1)
        flow = torch.zeros_like(start)
        predictions = []
        for _ in range(num_flow_updates):
            # the lookup position is a constant for the gradient (as in the paper's training)
            corr = pyramid.lookup((start + flow).detach())
            hidden, delta = self.update_block(hidden, context, corr, flow.detach())
            flow = flow.detach() + delta
            if self.mask_predictor is None:
                predictions.append(upsample_bilinear(flow))
            else:
                predictions.append(upsample_convex(flow, self.mask_predictor(hidden)))
        return predictions


def raft_small() -> RAFT:
    """torchvision's ``raft_small`` architecture (0.99 M parameters), untrained."""
    return RAFT(RAFT_SMALL)


def raft_large() -> RAFT:
    """torchvision's ``raft_large`` architecture (5.26 M parameters), untrained."""
    return RAFT(RAFT_LARGE)
