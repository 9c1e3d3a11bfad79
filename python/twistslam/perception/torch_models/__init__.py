"""Plain-torch re-implementations (inference only) of torchvision's Mask R-CNN R50-FPN and
DeepLabV3 / FCN ResNet-50, with torchvision's state-dict keys so its checkpoints load.

torchvision itself is not needed (its wheels must match the exact torch build, which a CPU
torch often does not have). torch is an optional extra: this package imports it, so import
the package only when a torch source is built. Modules of this package import each other
by module (``from .maskrcnn import ...``), never through this file.
"""

from .box_ops import BoxCoder, batched_nms, box_iou, nms
from .checkpoint import load_maskrcnn, load_segmentation, read_state_dict
from .deeplab import SegmentationNet, deeplabv3_resnet50, fcn_resnet50
from .maskrcnn import ImageResize, MaskRCNN, MaskRCNNShape, maskrcnn_resnet50_fpn
from .resnet import FrozenBatchNorm2d, ResNetFeatures, ResNetShape
from .roi_align import MultiScaleRoIAlign, roi_align
from .roi_heads import DetectionSettings, paste_masks
from .rpn import ProposalSettings

__all__ = ["BoxCoder", "DetectionSettings", "FrozenBatchNorm2d", "ImageResize", "MaskRCNN",
           "MaskRCNNShape", "MultiScaleRoIAlign", "ProposalSettings", "ResNetFeatures",
           "ResNetShape", "SegmentationNet", "batched_nms", "box_iou", "deeplabv3_resnet50",
           "fcn_resnet50", "load_maskrcnn", "load_segmentation", "maskrcnn_resnet50_fpn", "nms",
           "paste_masks", "read_state_dict", "roi_align"]
