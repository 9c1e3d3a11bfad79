"""twistslam: dynamic semantic SLAM fusing stereo images and LiDAR (TwistSLAM++).

The C++ core lives in ``twistslam._core``; this package is its typed Python face:

>>> import twistslam                                               # doctest: +SKIP
>>> result = twistslam.run(("data/sim", "0000"))                   # doctest: +SKIP
>>> result.camera_poses.shape                                      # doctest: +SKIP
(100, 4, 4)
"""

from twistslam._core import build_info

from .config import Config
from .objects import ObjectsResult, track_detections
from .pipeline import run
from .result import Result
from .slam import Slam, TrackedFrame

__version__ = "0.1.0"

__all__ = ["Config", "ObjectsResult", "Result", "Slam", "TrackedFrame", "build_info", "run", "track_detections", "__version__"]
