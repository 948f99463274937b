"""Planar polyline geometry: self-intersection of a centreline."""

from __future__ import annotations

import numpy as np

__all__ = ["self_intersects"]


def self_intersects(x: np.ndarray, y: np.ndarray) -> bool:
    """True if the open polyline (x, y) (P,) crosses itself (non-adjacent segments)."""
    px, py = x[:-1], y[:-1]
    dx, dy = np.diff(x), np.diff(y)
    m = px.size
    if m < 3:
        return False
    i, j = np.triu_indices(m, k=2)
    rx, ry = px[j] - px[i], py[j] - py[i]
    den = dx[i] * dy[j] - dy[i] * dx[j]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = (rx * dy[j] - ry * dx[j]) / den
        v = (rx * dy[i] - ry * dx[i]) / den
    hit = (den != 0) & (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
    return bool(np.any(hit))
