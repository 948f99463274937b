"""Checking a tracker on a rendered movie: the truth as a Track, and pixel errors.

For users who want to check their set-up: render a simulation with their pixel size, blur
and noise (:func:`flutterswim.tracking.render`), track it, and compare.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import CubicSpline

from ..analysis.track import Track

__all__ = ["truth_track", "pixel_errors"]


def truth_track(movie, length_mm: float | None = None) -> Track:
    """The simulated centrelines of a rendered :class:`Movie` in its image frame [mm] (x =
    column, y = row), at the movie's times."""
    mm = movie.um_per_px / 1000.0
    return Track(t=movie.t, x=movie.x_px * mm, y=movie.y_px * mm, units="mm", length=length_mm)


def pixel_errors(tr: Track, movie) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Errors of a track made by :func:`flutterswim.tracking.track` on ``movie``.

    Returns (D, E, idx): D (n, P) distances [px] of the tracked points to the true curve (the
    renderer's spline through the simulated nodes); E (n, 2) distances [px] of the tracked
    s = 0 and s = l ends to the true ends they were matched to in the first tracked frame
    (a later head/tail swap shows as errors of a body length); idx (n,) the tracked frames."""
    info = tr.meta["frames"]
    idx = np.nonzero(info["ok"])[0]
    X, Y = info["x_px"], info["y_px"]
    i0 = idx[0]
    if math.hypot(X[i0, 0] - movie.x_px[i0, 0], Y[i0, 0] - movie.y_px[i0, 0]) > math.hypot(
            X[i0, 0] - movie.x_px[i0, -1], Y[i0, 0] - movie.y_px[i0, -1]):
        X, Y = X[:, ::-1], Y[:, ::-1]
    D, E = [], []
    for i in idx:
        x, y = movie.x_px[i], movie.y_px[i]
        s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
        q = np.linspace(0.0, s[-1], 8000)
        xs, ys = CubicSpline(s, x)(q), CubicSpline(s, y)(q)
        D.append(np.min(np.hypot(X[i][:, None] - xs[None], Y[i][:, None] - ys[None]), axis=1))
        E.append([math.hypot(X[i, 0] - x[0], Y[i, 0] - y[0]), math.hypot(X[i, -1] - x[-1], Y[i, -1] - y[-1])])
    return np.array(D), np.array(E), idx
