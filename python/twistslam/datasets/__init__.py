"""Dataset readers and writers: KITTI tracking sequences, KITTI object frames, labels,
detections, poses, oxts.

Every reader returns numpy arrays or :class:`ObjectTable`; every sequence yields
:class:`Frame` objects in the frames of docs/design.md (rectified reference camera ``c``).
"""

from .calibration import Calibration, read_calibration, write_calibration
from .data_root import DATA_ENV, data_path, data_root
from .detections import DETECTION_CLASSES, read_detection_file, read_detections
from .frame import Frame, Sequence
from .kitti_tracking import KittiTracking
from .kitti_object import KittiObject, read_object_labels
from .labels import read_labels, read_tracking_results, write_labels, write_tracking_results
from .objects import DONT_CARE, ObjectTable
from .oxts import (
    camera_poses_to_oxts,
    oxts_to_camera_poses,
    oxts_to_imu_poses,
    read_oxts,
    read_oxts_poses,
    write_oxts,
)
from .poses import read_poses, write_poses
from .tracks import ObjectTrack, box_poses, object_tracks, world_poses
from .registry import DATASETS, open_sequence, register_dataset
from .sensors import MissingDataWarning, read_image, read_timestamps, read_velodyne, write_velodyne

__all__ = [
    "DATA_ENV",
    "DATASETS",
    "DETECTION_CLASSES",
    "DONT_CARE",
    "Calibration",
    "Frame",
    "KittiObject",
    "KittiTracking",
    "MissingDataWarning",
    "ObjectTable",
    "ObjectTrack",
    "Sequence",
    "box_poses",
    "camera_poses_to_oxts",
    "data_path",
    "data_root",
    "object_tracks",
    "open_sequence",
    "oxts_to_camera_poses",
    "oxts_to_imu_poses",
    "read_calibration",
    "read_detection_file",
    "read_detections",
    "read_image",
    "read_labels",
    "read_object_labels",
    "read_oxts",
    "read_oxts_poses",
    "read_poses",
    "read_timestamps",
    "read_tracking_results",
    "read_velodyne",
    "register_dataset",
    "write_calibration",
    "write_labels",
    "write_oxts",
    "write_poses",
    "write_tracking_results",
    "world_poses",
    "write_velodyne",
]
