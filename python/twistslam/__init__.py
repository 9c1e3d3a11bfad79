"""twistslam: dynamic semantic SLAM fusing stereo images and LiDAR (TwistSLAM++).

The C++ core lives in ``twistslam._core``; this package is its typed Python face.
"""

from twistslam._core import build_info

__version__ = "0.1.0"

__all__ = ["build_info", "__version__"]
