"""Panoptic labels from two torch networks: a Mask R-CNN for the things (each detection its
own instance) fused with a semantic-segmentation network for the stuff.

The networks have torchvision's architectures (``maskrcnn_resnet50_fpn``,
``deeplabv3_resnet50`` / ``fcn_resnet50``) re-implemented in plain torch
(:mod:`twistslam.perception.torch_models`), so a checkpoint saved from torchvision loads
without torchvision installed. Nothing is downloaded: the user names the weight files, or
passes ready modules (torchvision's own models work too).

torch is an optional extra (``pip install 'twistslam[models]'``), imported only when this
source is built.

Fusion (Kirillov et al.'s panoptic heuristic, simplified): every pixel first takes its
semantic class; then the detections at or above :data:`DETECTION_SCORE` are painted in order
of increasing score, each over its mask pixels (probability > :data:`MASK_PROBABILITY`), so
where masks overlap the most confident detection wins and a thing always wins over stuff.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from .panoptic import CITYSCAPES_CLASSES, DEFAULT_DYNAMIC_CLASSES, UNKNOWN, Panoptic
from .panoptic_files import COCO_TO_CITYSCAPES

#: lowest detection score (class probability) painted as a thing: 0.5 drops the uncertain
#: detections a COCO Mask R-CNN makes on clutter, which would become spurious object clusters
DETECTION_SCORE = 0.5
#: mask probability above which a pixel belongs to its detection (0.5: the mask head's
#: decision boundary, the threshold COCO mask AP is evaluated with)
MASK_PROBABILITY = 0.5
#: shorter image side the semantic network sees, pixels (520: torchvision's evaluation size
#: for its VOC-label DeepLabV3 / FCN weights)
SEMANTIC_MIN_SIZE = 520
#: (shorter side, longer-side cap) the Mask R-CNN resizes images to, pixels: torchvision's
#: COCO evaluation sizes (a KITTI frame 375 x 1242 is scaled by 1333 / 1242)
DETECTOR_SIZE = (800, 1333)
#: ImageNet channel means / standard deviations the semantic backbone was trained with
IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)

#: COCO detection category id -> name (the labels of torchvision's COCO Mask R-CNN weights)
COCO_CATEGORY_NAMES = {
    1: "person", 2: "bicycle", 3: "car", 4: "motorcycle", 5: "airplane", 6: "bus", 7: "train",
    8: "truck", 9: "boat", 10: "traffic light", 11: "fire hydrant", 13: "stop sign",
    14: "parking meter", 15: "bench", 16: "bird", 17: "cat", 18: "dog", 19: "horse",
    20: "sheep", 21: "cow", 22: "elephant", 23: "bear", 24: "zebra", 25: "giraffe",
    27: "backpack", 28: "umbrella", 31: "handbag", 32: "tie", 33: "suitcase", 34: "frisbee",
    35: "skis", 36: "snowboard", 37: "sports ball", 38: "kite", 39: "baseball bat",
    40: "baseball glove", 41: "skateboard", 42: "surfboard", 43: "tennis racket", 44: "bottle",
    46: "wine glass", 47: "cup", 48: "fork", 49: "knife", 50: "spoon", 51: "bowl",
    52: "banana", 53: "apple", 54: "sandwich", 55: "orange", 56: "broccoli", 57: "carrot",
    58: "hot dog", 59: "pizza", 60: "donut", 61: "cake", 62: "chair", 63: "couch",
    64: "potted plant", 65: "bed", 67: "dining table", 70: "toilet", 72: "tv", 73: "laptop",
    74: "mouse", 75: "remote", 76: "keyboard", 77: "cell phone", 78: "microwave", 79: "oven",
    80: "toaster", 81: "sink", 82: "refrigerator", 84: "book", 85: "clock", 86: "vase",
    87: "scissors", 88: "teddy bear", 89: "hair drier", 90: "toothbrush",
}
#: Pascal VOC class names by index (the 21 outputs of torchvision's semantic weights)
VOC_CLASS_NAMES = (
    "background", "aeroplane", "bicycle", "bird", "boat", "bottle", "bus", "car", "cat",
    "chair", "cow", "diningtable", "dog", "horse", "motorbike", "person", "pottedplant",
    "sheep", "sofa", "train", "tvmonitor",
)
#: class names -> Cityscapes ids: the COCO panoptic names plus VOC's spelling of motorcycle
CLASS_NAME_TO_CITYSCAPES = {**COCO_TO_CITYSCAPES, "motorbike": 32}


def _import_torch():
    try:
        import torch
    except ImportError as e:  # pragma: no cover - torch is installed where tests run
        raise ImportError("the 'torch' panoptic source needs torch: "
                          "pip install 'twistslam[models]'") from e
    return torch


def coco_thing_classes() -> dict[int, int]:
    """COCO category id -> Cityscapes id of the categories with a Cityscapes class."""
    return {cid: CLASS_NAME_TO_CITYSCAPES[name] for cid, name in COCO_CATEGORY_NAMES.items()
            if name in CLASS_NAME_TO_CITYSCAPES}


def semantic_lookup(classes: Mapping | Sequence | None, num_classes: int) -> np.ndarray:
    """(num_classes,) int32 Cityscapes id of each semantic output index.

    ``classes``: a mapping index -> Cityscapes id or class name, or a sequence (one id or
    name per index); names go through :data:`CLASS_NAME_TO_CITYSCAPES`; an index or name
    without a Cityscapes class becomes 0 (unknown, static). ``None``: the VOC classes of
    torchvision's semantic weights (only for a 21-class network).
    """
    if classes is None:
        if num_classes != len(VOC_CLASS_NAMES):
            raise ValueError(f"semantic network with {num_classes} classes: pass "
                             "semantic_classes (index -> Cityscapes id or class name); the "
                             f"default is for the {len(VOC_CLASS_NAMES)} VOC classes")
        classes = VOC_CLASS_NAMES
    items = classes.items() if isinstance(classes, Mapping) else enumerate(classes)
    lut = np.full(num_classes, UNKNOWN, dtype=np.int32)
    for index, value in items:
        if not 0 <= int(index) < num_classes:
            raise ValueError(f"semantic_classes: index {index} outside the network's "
                             f"{num_classes} classes")
        cid = CLASS_NAME_TO_CITYSCAPES.get(value, UNKNOWN) if isinstance(value, str) else int(value)
        if cid not in CITYSCAPES_CLASSES:
            raise ValueError(f"semantic_classes: {index} -> {value} is not a Cityscapes id (0-33)")
        lut[int(index)] = cid
    return lut


class TorchPanoptic:
    """Panoptic source ``frame -> Panoptic`` from a Mask R-CNN and a semantic network.

    Parameters
    ----------
    maskrcnn_weights : state-dict file of a torchvision-layout Mask R-CNN (e.g. saved from
        ``maskrcnn_resnet50_fpn(weights="COCO_V1").state_dict()``); its size is read from
        the file.
    semantic_weights : state-dict file of a torchvision-layout DeepLabV3 or FCN; optional:
        without a semantic network every pixel outside the things is unknown (static).
    semantic_classes : the semantic outputs' Cityscapes classes (see :func:`semantic_lookup`);
        default: the VOC classes of torchvision's weights.
    num_semantic_classes : expected output count of the semantic file (checked when given).
    detector, semantic : ready torch modules instead of the files (same call conventions as
        torchvision: ``detector([image])`` -> ``[{boxes, labels, scores, masks}]``,
        ``semantic(batch)["out"]`` -> logits).
    thing_classes : detector label -> Cityscapes id; default: COCO category ids through
        :data:`COCO_CATEGORY_NAMES` and :data:`CLASS_NAME_TO_CITYSCAPES`; other labels are
        not painted. Only detections of Cityscapes thing classes (people, vehicles) get an
        instance id; a traffic light or stop sign paints its class with instance 0.
    score_threshold : :data:`DETECTION_SCORE` (probability).
    mask_threshold : :data:`MASK_PROBABILITY` (probability).
    semantic_min_size : :data:`SEMANTIC_MIN_SIZE` (pixels).
    detector_size : :data:`DETECTOR_SIZE` (pixels) of a detector loaded from
        ``maskrcnn_weights`` (a ``detector`` module keeps its own).
    device : torch device the networks run on.

    Raises
    ------
    ValueError
        Neither weights nor a module for the detector; a weight file that is not that model's
        state dict (the message names the file); bad class mappings or thresholds.
    FileNotFoundError
        A named weight file does not exist.
    """

    def __init__(self, maskrcnn_weights: str | Path | None = None,
                 semantic_weights: str | Path | None = None, *,
                 semantic_classes: Mapping | Sequence | None = None,
                 num_semantic_classes: int | None = None, detector=None, semantic=None,
                 thing_classes: Mapping[int, int] | None = None,
                 score_threshold: float = DETECTION_SCORE, mask_threshold: float = MASK_PROBABILITY,
                 semantic_min_size: int = SEMANTIC_MIN_SIZE,
                 detector_size: tuple[int, int] = DETECTOR_SIZE, device: str = "cpu") -> None:
        for name, value in (("score_threshold", score_threshold), ("mask_threshold", mask_threshold)):
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"torch panoptic {name}: a probability in [0, 1], got {value}")
        if semantic_min_size < 1:
            raise ValueError(f"torch panoptic semantic_min_size: pixels >= 1, got {semantic_min_size}")
        if detector is None and maskrcnn_weights is None:
            raise ValueError("torch panoptic source: name the Mask R-CNN weight file "
                             "(maskrcnn_weights=...) or pass a detector module")
        self.torch = _import_torch()
        if detector is None:
            from .torch_models.checkpoint import load_maskrcnn
            from .torch_models.maskrcnn import ImageResize

            detector = load_maskrcnn(maskrcnn_weights, resize=ImageResize(*detector_size))
        if semantic is None and semantic_weights is not None:
            from .torch_models.checkpoint import load_segmentation

            semantic = load_segmentation(semantic_weights, num_semantic_classes)
        self.detector = detector.to(device).eval()
        self.semantic = semantic.to(device).eval() if semantic is not None else None
        self.semantic_lut = None
        if self.semantic is not None:
            classes = num_semantic_classes or _output_classes(self.semantic)
            self.semantic_lut = semantic_lookup(semantic_classes, classes)
        things = coco_thing_classes() if thing_classes is None else dict(thing_classes)
        for label, cid in things.items():
            if cid not in CITYSCAPES_CLASSES:
                raise ValueError(f"thing_classes: label {label} -> {cid} is not a Cityscapes id")
        self.thing_classes = things
        self.score_threshold, self.mask_threshold = score_threshold, mask_threshold
        self.semantic_min_size, self.device = semantic_min_size, device
        self.source = f"torch:{Path(maskrcnn_weights).name}" if maskrcnn_weights else "torch"

    def _image(self, frame):
        image = getattr(frame, "image_left", None)
        index = getattr(frame, "index", "?")
        if image is None:
            raise ValueError(f"torch panoptic: frame {index} has no left image")
        image = np.asarray(image)
        if image.dtype != np.uint8 or image.ndim not in (2, 3) or (
                image.ndim == 3 and image.shape[2] != 3):
            raise ValueError(f"torch panoptic: frame {index} image must be uint8 (H, W) or "
                             f"(H, W, 3) RGB, got {image.dtype} {image.shape}")
        rgb = np.repeat(image[..., None], 3, axis=2) if image.ndim == 2 else image
        # a copy: frames may hold read-only arrays, which torch.from_numpy warns about
        x = self.torch.from_numpy(np.array(rgb)).permute(2, 0, 1).float() / 255.0
        return x.to(self.device)

    def _stuff(self, image) -> np.ndarray:
        """(H, W) Cityscapes ids from the semantic network, unknown without one."""
        height, width = image.shape[-2:]
        if self.semantic is None:
            return np.zeros((height, width), dtype=np.int32)
        torch = self.torch
        F = torch.nn.functional
        mean = torch.tensor(IMAGENET_MEAN, device=image.device)[:, None, None]
        std = torch.tensor(IMAGENET_STD, device=image.device)[:, None, None]
        x = ((image - mean) / std)[None]
        scale = self.semantic_min_size / min(height, width)
        size = (max(1, round(height * scale)), max(1, round(width * scale)))
        x = F.interpolate(x, size=size, mode="bilinear", align_corners=False)
        logits = self.semantic(x)["out"]
        logits = F.interpolate(logits, size=(height, width), mode="bilinear", align_corners=False)
        index = logits[0].argmax(dim=0).cpu().numpy()
        if index.max(initial=0) >= len(self.semantic_lut):
            raise ValueError(f"torch panoptic: the semantic network outputs "
                             f"{logits.shape[1]} classes, semantic_classes covers "
                             f"{len(self.semantic_lut)}")
        return self.semantic_lut[index]

    def __call__(self, frame) -> Panoptic:
        image = self._image(frame)
        with self.torch.inference_mode():
            class_id = self._stuff(image)
            detections = self.detector([image])[0]
        instance_id = np.zeros_like(class_id)
        scores = detections["scores"].cpu().numpy()
        labels = detections["labels"].cpu().numpy()
        masks = detections["masks"]
        # painted from the least to the most confident: where masks overlap the last wins
        order = [k for k in np.argsort(scores, kind="stable")
                 if scores[k] >= self.score_threshold and int(labels[k]) in self.thing_classes]
        # instance ids by decreasing score: the most confident detection is instance 1
        rank = {k: n + 1 for n, k in enumerate(reversed(order))}
        for k in order:
            pixels = (masks[k, 0] > self.mask_threshold).cpu().numpy()
            cid = self.thing_classes[int(labels[k])]
            class_id[pixels] = cid
            # only Cityscapes thing classes (people, vehicles) carry an instance
            instance_id[pixels] = rank[k] if cid in DEFAULT_DYNAMIC_CLASSES else 0
        return Panoptic(class_id, instance_id, source=self.source)


def _output_classes(semantic) -> int:
    """Output classes of a semantic module: its last classifier conv's output channels."""
    classifier = getattr(semantic, "classifier", None)
    last = classifier[-1] if classifier is not None and len(classifier) else None
    channels = getattr(last, "out_channels", None)
    if channels is None:
        raise ValueError("torch panoptic: cannot tell the semantic module's class count; "
                         "pass num_semantic_classes")
    return int(channels)
