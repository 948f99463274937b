"""Self-intersection of a centreline polyline: segment-segment tests between non-adjacent
segments, at every frame.

Pruned by turning (tol = 0): if segments i < j cross, the polyline from the crossing point on
i through joints i+1..j back to it is a closed polygon, whose exterior angles sum to at least
2 pi; the corner at the crossing is below pi, so the turning at joints i+1..j exceeds pi. Only
pairs with sum_{k=i+1..j} |theta_k - theta_{k-1}| >= pi are tested (compiled with numba when it
is installed: O(N) per frame for a filament that turns by less than pi, O(N^2) at worst)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validate import ParameterError
from .track import Track, as_track

__all__ = ["self_intersections", "polyline_self_intersects"]

_pair_cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _pairs(n_seg: int) -> tuple[np.ndarray, np.ndarray]:
    if n_seg not in _pair_cache:
        i, j = np.triu_indices(n_seg, k=2)
        _pair_cache[n_seg] = (i, j)
    return _pair_cache[n_seg]


def _intersect_frames(x: np.ndarray, y: np.ndarray, tol: float) -> np.ndarray:
    """(F, P) coordinates -> (F,) number of intersecting non-adjacent segment pairs."""
    n_seg = x.shape[1] - 1
    i, j = _pairs(n_seg)
    if i.size == 0:
        return np.zeros(x.shape[0], int)
    px, py = x[:, i], y[:, i]
    rx, ry = x[:, i + 1] - px, y[:, i + 1] - py
    qx, qy = x[:, j], y[:, j]
    sx, sy = x[:, j + 1] - qx, y[:, j + 1] - qy
    den = rx * sy - ry * sx
    wx, wy = qx - px, qy - py
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (wx * sy - wy * sx) / den  # parameter along segment i
        b = (wx * ry - wy * rx) / den  # parameter along segment j
    hit = (np.abs(den) > 0) & (a >= -tol) & (a <= 1 + tol) & (b >= -tol) & (b <= 1 + tol)
    return hit.sum(axis=1)


def polyline_self_intersects(x: np.ndarray, y: np.ndarray, *, tol: float = 0.0) -> bool | np.ndarray:
    """True if the open polyline (x, y) crosses itself (non-adjacent segments intersect).
    For (F, P) arrays (F polylines), an (F,) boolean array."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    if x.shape != y.shape or x.ndim not in (1, 2) or x.shape[-1] < 2:
        raise ParameterError(f"x and y have shapes {x.shape} and {y.shape}; equal 1-d or 2-d shapes are required")
    hits = _count(np.atleast_2d(x), np.atleast_2d(y), tol) > 0
    return bool(hits[0]) if x.ndim == 1 else hits


def count_pruned(x, y, out):
    """out[f] = number of crossing non-adjacent segment pairs of frame f (tol = 0), testing only
    the pairs that turn by at least pi between them (module docstring)."""
    n_frames, n_pts = x.shape
    n_seg = n_pts - 1
    turn = np.zeros(n_seg)
    for f in range(n_frames):
        # cumulative absolute turning at the joints: turn[j] - turn[i] = sum over joints i+1..j
        prev = np.arctan2(y[f, 1] - y[f, 0], x[f, 1] - x[f, 0])
        turn[0] = 0.0
        for k in range(1, n_seg):
            a = np.arctan2(y[f, k + 1] - y[f, k], x[f, k + 1] - x[f, k])
            d = a - prev
            d = abs(d - 2.0 * np.pi * np.floor((d + np.pi) / (2.0 * np.pi)))
            turn[k] = turn[k - 1] + d
            prev = a
        cnt = 0
        j0 = 2
        for i in range(n_seg - 2):
            j0 = max(j0, i + 2)
            while j0 < n_seg and turn[j0] - turn[i] < np.pi * (1.0 - 1e-12):
                j0 += 1
            px, py = x[f, i], y[f, i]
            rx, ry = x[f, i + 1] - px, y[f, i + 1] - py
            for j in range(j0, n_seg):
                qx, qy = x[f, j], y[f, j]
                sx, sy = x[f, j + 1] - qx, y[f, j + 1] - qy
                den = rx * sy - ry * sx
                if den == 0.0:
                    continue
                wx, wy = qx - px, qy - py
                a = (wx * sy - wy * sx) / den
                b = (wx * ry - wy * rx) / den
                if 0.0 <= a <= 1.0 and 0.0 <= b <= 1.0:
                    cnt += 1
        out[f] = cnt
    return out


def self_intersections(obj: Any, *, tol: float = 0.0, chunk_bytes: float = 64e6) -> np.ndarray:
    """Number of crossing non-adjacent segment pairs at each frame, shape (T,).

    A pair (i, j) with j >= i + 2 crosses when the solutions a, b of p_i + a r_i = q_j + b s_j
    both lie in [-tol, 1 + tol] (tol = 0: touching counts, parallel segments do not).
    Frames are processed in chunks to bound memory.
    """
    tr: Track = as_track(obj)
    return _count(tr.x, tr.y, tol, chunk_bytes)


def _count(x: np.ndarray, y: np.ndarray, tol: float, chunk_bytes: float = 64e6) -> np.ndarray:
    """(F, P) coordinates -> (F,) crossing pairs: pruned and compiled for tol = 0 when numba
    is installed, else all pairs in chunks of frames."""
    n_frames, n_seg = x.shape[0], x.shape[1] - 1
    if tol == 0.0 and n_seg >= 3:
        import sys

        from .. import _jit

        mod = sys.modules[__name__]
        if _jit.compile_module(mod, ("count_pruned",)):
            return mod.count_pruned(np.ascontiguousarray(x, float), np.ascontiguousarray(y, float),
                                    np.empty(n_frames, np.int64)).astype(int)
    n_pairs = max(_pairs(n_seg)[0].size, 1)
    per_frame = n_pairs * 8 * 14
    step = max(1, int(chunk_bytes // per_frame))
    out = np.empty(n_frames, int)
    for a in range(0, n_frames, step):
        out[a : a + step] = _intersect_frames(x[a : a + step], y[a : a + step], tol)
    return out
