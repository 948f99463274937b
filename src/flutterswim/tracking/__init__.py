"""Tracking from video: synthetic movies, segmentation, sub-pixel centrelines, tracks.

Heavy dependencies (scikit-image, tifffile, imageio) are imported inside the functions
that need them (extra ``flutterswim[track]``).
"""

from __future__ import annotations

from .render import Movie, render


__all__ = ["Movie", "render"]
