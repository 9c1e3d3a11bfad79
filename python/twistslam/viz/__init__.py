"""Live view of a run in rerun (optional extra: ``pip install 'twistslam[viz]'``).

``import twistslam.viz`` works without rerun; creating a :class:`RerunLogger` needs it.
"""

from .colors import CITYSCAPES_COLORS, track_color
from .lidar_view import LidarView, lidar_view
from .logger import RerunLogger
from .views import ObjectView

__all__ = ["CITYSCAPES_COLORS", "LidarView", "ObjectView", "RerunLogger", "lidar_view",
           "track_color"]
