"""Sizes of a 3DSSD network (Yang et al., "3DSSD: Point-based 3D Single Stage Object Detector",
CVPR 2020): one dataclass, so that the tiny test model, the small CPU model and the paper-size
model share every line of code.

What is kept from the paper: the whole network works on raw points (no voxels, no feature
propagation layers); set abstraction (SA) layers whose centres come from fusion sampling
(distance FPS plus feature FPS); a candidate generation layer that shifts the feature-FPS
points towards their object's centre (the vote loss) and groups the last SA layer's points
around the shifted candidates; an anchor-free head with a centre-ness classification target,
centre / size residuals and a bin-based heading (classification + residual).

What is scaled down or simplified (see :data:`TINY`, :data:`SMALL` and docs/detector_3dssd.md):
fewer input points and sampled centres, narrower MLPs; every SA layer samples from the whole
previous layer (the paper keeps the D-FPS and F-FPS halves apart in its last SA layer);
sizes are regressed as log ratios to a class mean size; no corner loss.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class SALayerConfig:
    """One set-abstraction layer.

    Attributes
    ----------
    n_dfps, n_ffps : centres picked by distance FPS and by feature FPS (their sum is the
        layer's output point count; feature FPS needs the previous layer's features, so the
        first layer has ``n_ffps == 0``).
    radii : ball-query radius of each grouping scale, metres.
    samples : neighbours gathered per centre at each scale.
    mlps : channels of the shared MLP of each scale (the input width is implicit).
    out_channels : width of the 1x1 aggregation of the concatenated scales.
    """

    n_dfps: int
    n_ffps: int
    radii: tuple[float, ...]
    samples: tuple[int, ...]
    mlps: tuple[tuple[int, ...], ...]
    out_channels: int

    @property
    def n_points(self) -> int:
        return self.n_dfps + self.n_ffps


@dataclass(frozen=True)
class SSD3DConfig:
    """The whole network and its box coding.

    Attributes
    ----------
    classes : detected KITTI types, in score-column order.
    mean_sizes : (l, w, h) metres per class, the anchors of the size residuals.
    num_points : points fed to the network (a random subset of the field-of-view scan).
    point_range : (x_min, y_min, z_min, x_max, y_max, z_max) metres in the LiDAR-like frame
        (x forward, y left, z up) where points are kept; KITTI's usual detection range.
    sa_layers : the set-abstraction layers, input to output.
    vote_channels : hidden widths of the shift-prediction MLP.
    max_shift : (x, y, z) metres, the largest predicted shift (the paper's 3, 2, 3).
    cg_radii, cg_samples, cg_mlps, cg_channels : the candidate-generation grouping (as in
        :class:`SALayerConfig`).
    head_channels : hidden widths of the classification and box-regression MLPs.
    heading_bins : heading classification bins over 2 pi (the paper: 12).
    """

    classes: tuple[str, ...] = ("Car", "Pedestrian", "Cyclist")
    mean_sizes: tuple[tuple[float, float, float], ...] = ((3.9, 1.6, 1.56), (0.8, 0.6, 1.73),
                                                          (1.76, 0.6, 1.73))
    num_points: int = 16384
    point_range: tuple[float, ...] = (0.0, -40.0, -3.0, 70.4, 40.0, 1.0)
    sa_layers: tuple[SALayerConfig, ...] = (
        SALayerConfig(4096, 0, (0.2, 0.4, 0.8), (32, 32, 64), ((16, 16, 32), (16, 16, 32), (32, 32, 64)), 64),
        SALayerConfig(256, 256, (0.4, 0.8, 1.6), (32, 32, 64), ((64, 64, 128), (64, 64, 128), (64, 96, 128)), 128),
        SALayerConfig(256, 256, (1.6, 3.2, 4.8), (32, 32, 32), ((128, 128, 256), (128, 192, 256), (128, 256, 256)), 256),
    )
    vote_channels: tuple[int, ...] = (128,)
    max_shift: tuple[float, float, float] = (3.0, 2.0, 3.0)
    cg_radii: tuple[float, ...] = (4.8, 6.4)
    cg_samples: tuple[int, ...] = (16, 32)
    cg_mlps: tuple[tuple[int, ...], ...] = ((256, 256, 512), (256, 512, 1024))
    cg_channels: int = 512
    head_channels: tuple[int, ...] = (256, 128)
    heading_bins: int = 12

    def __post_init__(self) -> None:
        if len(self.mean_sizes) != len(self.classes):
            raise ValueError(f"{len(self.classes)} classes but {len(self.mean_sizes)} mean sizes")
        if not self.sa_layers or self.sa_layers[0].n_ffps != 0:
            raise ValueError("the first SA layer has no features to run feature FPS on: n_ffps must be 0")
        if self.sa_layers[-1].n_ffps == 0:
            raise ValueError("the last SA layer needs feature-FPS points: they become the candidates")
        for layer in (*self.sa_layers, self):
            radii, samples, mlps = ((layer.radii, layer.samples, layer.mlps) if layer is not self
                                    else (self.cg_radii, self.cg_samples, self.cg_mlps))
            if not len(radii) == len(samples) == len(mlps):
                raise ValueError("each grouping scale needs one radius, one sample count and one MLP")

    def to_dict(self) -> dict:
        """Plain lists and numbers (what a checkpoint stores; ``torch.load(weights_only=True)``
        reads it back)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, values: dict) -> "SSD3DConfig":
        """Inverse of :meth:`to_dict` (lists back to tuples)."""
        def tup(x):
            return tuple(tup(v) for v in x) if isinstance(x, (list, tuple)) else x
        values = dict(values)
        values["sa_layers"] = tuple(SALayerConfig(**{k: tup(v) for k, v in layer.items()})
                                    for layer in values["sa_layers"])
        return cls(**{k: (tup(v) if k != "sa_layers" else v) for k, v in values.items()})


#: the paper's KITTI network (16384 points; slow to train on a CPU)
FULL = SSD3DConfig()

#: a CPU-sized model: a quarter of the points, half-width MLPs (what `--epochs` trains here)
SMALL = SSD3DConfig(
    num_points=8192,
    sa_layers=(
        SALayerConfig(2048, 0, (0.4, 0.8), (16, 32), ((16, 32), (16, 32)), 32),
        SALayerConfig(256, 256, (0.8, 1.6), (16, 32), ((32, 64), (32, 64)), 64),
        SALayerConfig(128, 128, (1.6, 3.2), (16, 32), ((64, 128), (64, 128)), 128),
    ),
    vote_channels=(64,),
    cg_radii=(3.2, 4.8), cg_samples=(16, 32), cg_mlps=((128, 128), (128, 128)), cg_channels=128,
    head_channels=(128,),
)

#: a network of a few thousand parameters for tests
TINY = SSD3DConfig(
    num_points=2048,
    sa_layers=(
        SALayerConfig(512, 0, (0.8,), (16,), ((16,),), 16),
        SALayerConfig(64, 64, (1.6,), (16,), ((32,),), 32),
        SALayerConfig(32, 32, (3.2,), (16,), ((32,),), 32),
    ),
    vote_channels=(32,),
    cg_radii=(4.8,), cg_samples=(16,), cg_mlps=((32,),), cg_channels=32,
    head_channels=(32,),
)

PRESETS = {"tiny": TINY, "small": SMALL, "full": FULL}
