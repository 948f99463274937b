"""Swimming analysis: cycles, descriptors, self-intersection and kymographs of centreline tracks."""

from .cycles import Cycles, detect_cycles, lateral_signal
from .track import Track, as_track

__all__ = ["Cycles", "Track", "as_track", "detect_cycles", "lateral_signal"]
