"""Kymographs: crossings of fixed lab-frame lines by the filament over time (as in the paper's
experiments), and body-frame curvature / tangent-angle maps kappa(s, t), theta(s, t)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import ParameterError
from .cycles import Cycles, detect_cycles
from .track import Track, as_track, polyline_curvature

__all__ = ["LineKymograph", "BodyKymograph", "line_kymograph", "body_kymograph", "kymograph_windows"]


@dataclass(frozen=True, eq=False)
class LineKymograph:
    """Where the centreline crosses a fixed line, at each frame.

    orientation: "horizontal" (line y = level; positions are x) or "vertical" (x = level;
    positions are y). positions, s: (T, K) crossing coordinate along the line and arc length
    of the crossing point on the filament, NaN-padded (K = most crossings in any frame).
    """

    t: np.ndarray
    positions: np.ndarray
    s: np.ndarray
    orientation: str
    level: float
    units: str

    @property
    def counts(self) -> np.ndarray:
        return np.count_nonzero(np.isfinite(self.positions), axis=1)


@dataclass(frozen=True, eq=False)
class BodyKymograph:
    """Body-frame maps: kappa (T, P) the shape's curvature theta_s at s (P,), theta (T, N) at s_mid
    (N,) (the rigid rotation, i.e. the mean of theta along s, removed when ``body_frame``)."""

    t: np.ndarray
    s: np.ndarray
    kappa: np.ndarray
    s_mid: np.ndarray
    theta: np.ndarray
    body_frame: bool
    units: str


def _crossings(a: np.ndarray, b: np.ndarray, s: np.ndarray, level: float):
    f = a - level
    f0, f1 = f[:, :-1], f[:, 1:]
    hit = ((f0 < 0) & (f1 >= 0)) | ((f0 >= 0) & (f1 < 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(hit, f0 / (f0 - f1), np.nan)
    pos = b[:, :-1] + frac * (b[:, 1:] - b[:, :-1])
    sc = s[:-1] + frac * np.diff(s)
    counts = hit.sum(axis=1)
    K = int(counts.max()) if counts.size else 0
    T = a.shape[0]
    P = np.full((T, max(K, 1)), np.nan)
    S = np.full((T, max(K, 1)), np.nan)
    if K:
        order = np.argsort(~hit, axis=1, kind="stable")[:, :K]
        rows = np.arange(T)[:, None]
        P[:] = pos[rows, order]
        S[:] = sc[rows, order]
        valid = np.arange(K)[None, :] < counts[:, None]
        P[~valid] = np.nan
        S[~valid] = np.nan
    return P, S


def line_kymograph(obj: Any, orientation: str = "horizontal", level: float | None = None) -> LineKymograph:
    """Crossings of the filament with the fixed line y = level ("horizontal") or x = level
    ("vertical"). Default level: the time-mean centroid coordinate (y for a horizontal line,
    x at the middle of the record for a vertical one)."""
    tr: Track = as_track(obj)
    xc, yc = tr.centroid()
    if orientation == "horizontal":
        lv = float(np.mean(yc)) if level is None else float(level)
        P, S = _crossings(tr.y, tr.x, tr.s, lv)
    elif orientation == "vertical":
        lv = float(np.interp(0.5 * (tr.t[0] + tr.t[-1]), tr.t, xc)) if level is None else float(level)
        P, S = _crossings(tr.x, tr.y, tr.s, lv)
    else:
        raise ParameterError(f"orientation={orientation!r} is not allowed; use 'horizontal' or 'vertical'")
    if not math.isfinite(lv):
        raise ParameterError(f"level={level!r} must be finite")
    return LineKymograph(t=tr.t, positions=P, s=S, orientation=orientation, level=lv, units=tr.units)


def body_kymograph(obj: Any, *, body_frame: bool = True) -> BodyKymograph:
    """Curvature of the shape kappa = theta_s(s, t), from the centreline (:func:`polyline_curvature`),
    and tangent angle theta(s, t) (given, or from the polyline).

    The curvature is the shape's for a simulation and a tracked movie alike, so that their maps
    compare. A simulation's spontaneous curvature (``Track.kappa``, the model's active state)
    lags it inside the body, and at the free end joints, where it does not enter the bending
    moment, it follows the end segment's angle half a segment in (0.5 /mm below the shape's
    there on the paper's onset at 32 segments)."""
    tr: Track = as_track(obj)
    s, k = tr.s, polyline_curvature(tr.x, tr.y)
    s_mid, th = tr.tangent_angle()
    if body_frame:
        th = th - th.mean(axis=1, keepdims=True)
    return BodyKymograph(t=tr.t, s=s, kappa=k, s_mid=s_mid, theta=th, body_frame=body_frame, units=tr.units)


def kymograph_windows(obj: Any, n_cycles: int = 3, cycles: Cycles | None = None) -> dict[str, tuple[float, float]]:
    """Time windows of ``n_cycles`` cycles "near onset" (centred on the onset time, or the first
    cycles) and "limit cycle" (the last cycles)."""
    tr = as_track(obj)
    cyc = detect_cycles(tr) if cycles is None else cycles
    st = cyc.starts
    if st.size < 2:
        half = 0.5 * (tr.t[-1] - tr.t[0])
        return {"onset": (float(tr.t[0]), float(tr.t[0] + half)), "limit": (float(tr.t[-1] - half), float(tr.t[-1]))}
    K = st.size - 1
    n = min(n_cycles, K)
    if math.isfinite(cyc.onset_time):
        k = int(np.clip(np.searchsorted(st, cyc.onset_time) - 1 - n // 2, 0, K - n))
    else:
        k = 0
    return {"onset": (float(st[k]), float(st[k + n])), "limit": (float(st[K - n]), float(st[K]))}
