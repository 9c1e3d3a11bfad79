"""Where the real KITTI data lives: one setting for the whole project.

The folder is ``$TWISTSLAM_DATA`` when that variable is set, otherwise the ``shared/data``
folder beside the repository (``<repo>/../shared/data``, the layout of the development
machines). It holds one sub-folder per collection, each in the KITTI layout::

    kitti_tracking/          training/{calib,label_02,oxts,image_02}, detections/pointrcnn_car_val
    kitti_tracking_lidar/    training/{calib,image_02,image_03,velodyne,label_02,oxts}, detections/
    kitti_object/            training/{calib,image_2,velodyne,label_2}
    ab3dmot/                 raw/tracking, thresholded/tracking (a peer's outputs)

Point it at your own KITTI download by setting ``TWISTSLAM_DATA`` to a folder with the same
sub-folders (symbolic links to your ``data_tracking_*`` extraction are fine).
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

#: the environment variable that names the data folder
DATA_ENV = "TWISTSLAM_DATA"


def data_root() -> Path:
    """The real-data folder: ``$TWISTSLAM_DATA``, else ``shared/data`` beside the repository.

    The path is returned whether or not it exists; :func:`data_path` checks.
    """
    value = os.environ.get(DATA_ENV, "").strip()
    if value:
        return Path(value).expanduser()
    # python/twistslam/datasets/data_root.py -> parents[3] is the repository (editable install)
    return Path(__file__).resolve().parents[3].parent / "shared" / "data"


def data_path(*parts: str) -> Path:
    """A file or folder inside :func:`data_root`; ``FileNotFoundError`` naming the variable
    when it is missing."""
    path = data_root().joinpath(*parts)
    if not path.exists():
        raise FileNotFoundError(
            errno.ENOENT,
            f"real KITTI data not found: {path} (set {DATA_ENV} to the folder holding "
            f"kitti_tracking/, kitti_tracking_lidar/, kitti_object/, ab3dmot/)",
            str(path),
        )
    return path
