"""Perception stages: callables from :class:`~twistslam.datasets.Frame` to numpy arrays
(optical flow now; panoptic segmentation next), each with interchangeable sources."""

from .flow import DisFlow, DisOptions, FileFlow, flow_source
from .flow_files import read_flo, read_kitti_flow, write_flo, write_kitti_flow
from .flow_raft import RaftFlow, load_raft
from .stage import FlowStage, TimedStage, check_flow

__all__ = ["DisFlow", "DisOptions", "FileFlow", "FlowStage", "RaftFlow", "TimedStage", "check_flow",
           "flow_source", "load_raft", "read_flo", "read_kitti_flow", "write_flo", "write_kitti_flow"]
