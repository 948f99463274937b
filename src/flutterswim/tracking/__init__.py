"""Tracking from video: synthetic movies, segmentation, sub-pixel centrelines, tracks.

:func:`track` turns a movie (TIFF stack, folder of frames, MP4/AVI, or an array) into the
analysis' :class:`~flutterswim.analysis.track.Track`, so ``describe``, the kymographs and the
fitting work on experiments as on simulations. Heavy dependencies (scikit-image, tifffile,
imageio) are imported inside the functions that need them (extra ``flutterswim[track]``).
"""

from __future__ import annotations

from .batch import find_trials, track_batch
from .kymograph import RawKymographs, plot_raw_kymographs, raw_kymographs
from .netcdf import load_track, save_track
from .render import Movie, render
from .track import failures, track

__all__ = ["Movie", "render", "track", "failures", "save_track", "load_track", "raw_kymographs",
           "plot_raw_kymographs", "RawKymographs", "track_batch", "find_trials"]
