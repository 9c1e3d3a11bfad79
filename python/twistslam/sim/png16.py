"""Moved to :mod:`twistslam.datasets.png16` (2026-12-06): the flow and panoptic readers use the
codec, and importing it from the simulator's package loaded the simulator. This name keeps
scripts written against it working."""

from twistslam.datasets.png16 import encode_png, read_png16, write_png, write_png16  # noqa: F401
