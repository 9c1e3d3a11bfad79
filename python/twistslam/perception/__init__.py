"""Perception stages: callables from :class:`~twistslam.datasets.Frame` to numpy arrays
(optical flow and panoptic segmentation), each with interchangeable sources. Not yet wired
into :func:`twistslam.run` (issue 10)."""

from .detection import DETECTION_KINDS, Detections3D, DetectionStage, detection_source
from .detection_classical import ClassicalDetector
from ..datasets import read_detection_file
from .detection_files import FileDetections
from .flow import DisFlow, DisOptions, FileFlow, flow_source
from .flow_files import read_flo, read_kitti_flow, write_flo, write_kitti_flow
from .flow_raft import RaftFlow, load_raft
from .panoptic import CITYSCAPES_CLASSES, DEFAULT_DYNAMIC_CLASSES, Panoptic
from .panoptic_files import CocoPanopticFiles, SimPanopticFiles, read_coco_panoptic, read_sim_panoptic
from .panoptic_from_boxes import BoxMaskConfig, PanopticFromBoxes
from .panoptic_source import PanopticStage, check_panoptic, panoptic_source
from .panoptic_torch import TorchPanoptic
from .stage import FlowStage, TimedStage, check_flow

__all__ = ["ClassicalDetector", "DETECTION_KINDS", "Detections3D", "DetectionStage",
           "FileDetections", "detection_source", "read_detection_file",
           "DisFlow", "DisOptions", "FileFlow", "FlowStage", "RaftFlow", "TimedStage", "check_flow",
           "flow_source", "load_raft", "read_flo", "read_kitti_flow", "write_flo", "write_kitti_flow",
           "BoxMaskConfig", "CITYSCAPES_CLASSES", "CocoPanopticFiles", "DEFAULT_DYNAMIC_CLASSES",
           "Panoptic", "PanopticFromBoxes", "PanopticStage", "SimPanopticFiles", "check_panoptic",
           "panoptic_source", "read_coco_panoptic", "read_sim_panoptic", "TorchPanoptic"]
