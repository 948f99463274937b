"""Swimming analysis of centreline tracks (simulated or measured from images).

Every public function accepts a :class:`Track` or any result-like object with ``t``, ``x``,
``y`` (and optionally ``s``, ``theta``, ``kappa``, ``field_angle``, ``params``).
"""

from .cycles import Cycles, body_axis_angle, detect_cycles, lateral_signal
from .descriptors import Descriptors, describe, per_cycle, shape_modes, stroke_area
from .intersection import polyline_self_intersects, self_intersections
from .kymograph import BodyKymograph, LineKymograph, body_kymograph, kymograph_windows, line_kymograph
from .section import estimate_period, section_crossings
from .track import Track, as_track, polyline_curvature, polyline_tangent_angle

__all__ = [
    "BodyKymograph", "Cycles", "Descriptors", "LineKymograph", "Track", "as_track", "body_axis_angle",
    "body_kymograph", "describe", "detect_cycles", "estimate_period", "kymograph_windows", "lateral_signal",
    "line_kymograph", "per_cycle", "polyline_curvature", "polyline_self_intersects", "polyline_tangent_angle",
    "section_crossings", "self_intersections", "shape_modes", "stroke_area",
]
