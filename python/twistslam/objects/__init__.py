"""Objects: 3D multi-object tracking (cpp/objects through ``twistslam._core.objects``).

:func:`track_detections` tracks a sequence's objects from 3D detections alone;
:class:`ObjectTracker` is the frame-by-frame face for a user's own loop.
"""

from .detections_input import DetectionWarning, load_detections
from .result import ObjectsResult, TrackedObject
from .tracking import ObjectTracker, track_detections

__all__ = ["DetectionWarning", "ObjectTracker", "ObjectsResult", "TrackedObject",
           "load_detections", "track_detections"]
