"""The data model of the analysis: a time series of planar centrelines.

A :class:`Track` holds only what an image of a swimming filament can give: times,
centreline points ordered from the s=0 end to the s=l end, and optionally tangent
angle, curvature, the field direction and the body length. Nothing in the analysis
assumes simulation-only knowledge, so the same functions measure experimental data.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validate import ParameterError

__all__ = ["Track", "as_track", "UNIT_SCALE"]

#: Metres per unit of length for the units a Track may carry.
UNIT_SCALE = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6}


def _arr(name: str, value: Any, ndim: int) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={type(value).__name__} is not a numeric array") from None
    if arr.ndim != ndim:
        raise ParameterError(f"{name} has shape {arr.shape}; a {ndim}-d array is required")
    if not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise ParameterError(f"{name} has {bad} non-finite entries; all entries must be finite")
    arr.setflags(write=False)
    return arr


def _seg_lengths(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.hypot(np.diff(x, axis=-1), np.diff(y, axis=-1))


def polyline_tangent_angle(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Tangent angle at segment midpoints, shape (..., P-1), continuous along s."""
    th = np.arctan2(np.diff(y, axis=-1), np.diff(x, axis=-1))
    return np.unwrap(th, axis=-1)


def polyline_curvature(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Signed curvature dtheta/ds at nodes, shape (..., P), from the turning angles.

    Interior nodes use the turning angle between adjacent segments divided by the mean
    of their lengths; the two end nodes are extrapolated linearly.
    """
    th = polyline_tangent_angle(x, y)
    ds = _seg_lengths(x, y)
    P = x.shape[-1]
    k = np.empty(x.shape, dtype=float)
    if P >= 3:
        k[..., 1:-1] = np.diff(th, axis=-1) / (0.5 * (ds[..., 1:] + ds[..., :-1]))
    if P >= 4:
        k[..., 0] = 2 * k[..., 1] - k[..., 2]
        k[..., -1] = 2 * k[..., -2] - k[..., -3]
    else:
        k[..., 0] = k[..., 1]
        k[..., -1] = k[..., -2]
    return k


@dataclass(frozen=True, eq=False)
class Track:
    """Centreline time series of a planar filament.

    t: (T,) times in s, strictly increasing (non-uniform spacing allowed).
    x, y: (T, P) centreline points, ordered from the s=0 end to the s=l end, P >= 3.
    s: (P,) arc length of the points (default: cumulative polyline length of frame 0).
    theta: optional tangent angle [rad], (T, P-1) at segment midpoints or (T, P) at nodes.
    kappa: optional curvature [1/length unit], (T, P) at nodes.
    field_angle: direction of the field, scalar or (T,) [rad]; 0 means +x (default 0).
    length: body length (default: polyline length of frame 0).
    units: length unit of x, y, s, length: one of "m", "mm", "um".
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    s: np.ndarray | None = None
    theta: np.ndarray | None = None
    kappa: np.ndarray | None = None
    field_angle: np.ndarray | float | None = None
    length: float | None = None
    units: str = "m"
    meta: dict = field(default_factory=dict)
    #: the field's strength (a multiplier of kappa_E) per frame, where the source knew it (a
    #: simulation); None otherwise
    field_strength: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = _arr("t", self.t, 1)
        x = _arr("x", self.x, 2)
        y = _arr("y", self.y, 2)
        T = t.size
        if T < 2:
            raise ParameterError(f"t has {T} entries; at least 2 times are required")
        if np.any(np.diff(t) <= 0):
            raise ParameterError("t is not strictly increasing; times must increase")
        if x.shape != y.shape or x.shape[0] != T:
            raise ParameterError(
                f"x has shape {x.shape} and y has shape {y.shape}; both must be (T, P) with T={T}"
            )
        if x.shape[1] < 3:
            raise ParameterError(f"x has P={x.shape[1]} points per frame; P >= 3 is required")
        P = x.shape[1]
        if self.units not in UNIT_SCALE:
            raise ParameterError(f"units={self.units!r} is unknown; choose one of {sorted(UNIT_SCALE)}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)
        if self.s is None:
            ds = _seg_lengths(x[0], y[0])
            s = np.concatenate([[0.0], np.cumsum(ds)])
        else:
            s = _arr("s", self.s, 1)
            if s.size != P:
                raise ParameterError(f"s has {s.size} entries; P={P} are required")
        s.setflags(write=False)
        object.__setattr__(self, "s", s)
        if self.theta is not None:
            th = _arr("theta", self.theta, 2)
            if th.shape not in ((T, P - 1), (T, P)):
                raise ParameterError(f"theta has shape {th.shape}; ({T}, {P - 1}) or ({T}, {P}) is required")
            object.__setattr__(self, "theta", th)
        if self.kappa is not None:
            k = _arr("kappa", self.kappa, 2)
            if k.shape != (T, P):
                raise ParameterError(f"kappa has shape {k.shape}; ({T}, {P}) is required")
            object.__setattr__(self, "kappa", k)
        fa = 0.0 if self.field_angle is None else self.field_angle
        fa = np.array(fa, dtype=float)
        if fa.ndim == 0:
            fa = np.full(T, float(fa))
        if fa.shape != (T,) or not np.all(np.isfinite(fa)):
            raise ParameterError(f"field_angle has shape {fa.shape}; a finite scalar or shape ({T},) is required")
        fa.setflags(write=False)
        object.__setattr__(self, "field_angle", fa)
        if self.field_strength is not None:
            fs_ = np.array(self.field_strength, dtype=float)
            if fs_.shape != (T,) or not np.all(np.isfinite(fs_)):
                raise ParameterError(f"field_strength has shape {fs_.shape}; finite values of shape ({T},) are required")
            fs_.setflags(write=False)
            object.__setattr__(self, "field_strength", fs_)
        if self.length is None:
            L = float(np.sum(_seg_lengths(x[0], y[0])))
        else:
            try:
                L = float(self.length)
            except (TypeError, ValueError):
                raise ParameterError(f"length={self.length!r} is not a real number") from None
        if not (np.isfinite(L) and L > 0):
            raise ParameterError(f"length={L!r} must be a finite number > 0")
        object.__setattr__(self, "length", L)

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_result(cls, result: Any) -> "Track":
        """Build a Track from any object with t, x, y and optionally s, theta, kappa,
        field_angle, params (with .l) attributes (e.g. a flutterswim simulation result)."""
        for name in ("t", "x", "y"):
            if not hasattr(result, name):
                raise ParameterError(
                    f"result of type {type(result).__name__} has no attribute {name!r}; "
                    "a Track or an object with t, x, y is required"
                )
        params = getattr(result, "params", None)
        length = getattr(params, "l", None) if params is not None else None
        meta = {}
        if params is not None:
            meta["params"] = params
        if getattr(result, "status", None) == "failed":  # (a simulation that stopped on a solver failure)
            meta["run_failed"] = str(getattr(result, "message", "the run failed"))
        if getattr(result, "units", "SI") == "dimensionless":
            # lengths in body lengths l, times in tau (a run of fs.Groups): no metres to give
            meta["dimensionless"] = True
        return cls(
            t=np.asarray(result.t),
            x=np.asarray(result.x),
            y=np.asarray(result.y),
            s=getattr(result, "s", None),
            theta=getattr(result, "theta", None),
            kappa=getattr(result, "kappa", None),
            field_angle=getattr(result, "field_angle", None),
            length=length,
            units="m",
            meta=meta,
            field_strength=getattr(result, "field_strength", None),
        )

    # ------------------------------------------------------------------ basics
    @property
    def n_frames(self) -> int:
        return self.t.size

    @property
    def n_points(self) -> int:
        return self.x.shape[1]

    @property
    def scale_m(self) -> float:
        """Metres per length unit."""
        return UNIT_SCALE[self.units]

    @property
    def tau(self) -> float | None:
        """Relaxation time of the material if the source knew it (simulations), else None."""
        p = self.meta.get("params")
        return float(p.tau) if p is not None and hasattr(p, "tau") else None

    def slice(self, i0: int, i1: int) -> "Track":
        """Frames i0 <= i < i1 as a new Track (same length and units)."""
        sl = slice(i0, i1)
        return Track(
            t=self.t[sl], x=self.x[sl], y=self.y[sl], s=self.s,
            theta=None if self.theta is None else self.theta[sl],
            kappa=None if self.kappa is None else self.kappa[sl],
            field_angle=self.field_angle[sl], length=self.length, units=self.units, meta=self.meta,
            field_strength=None if self.field_strength is None else self.field_strength[sl],
        )

    def window(self, t0: float, t1: float) -> "Track":
        """Frames with t0 <= t <= t1."""
        i0 = int(np.searchsorted(self.t, t0, side="left"))
        i1 = int(np.searchsorted(self.t, t1, side="right"))
        if i1 - i0 < 2:
            raise ParameterError(f"window ({t0!r}, {t1!r}) holds {i1 - i0} frames; at least 2 are required")
        return self.slice(i0, i1)

    def segment_weights(self) -> np.ndarray:
        """(P,) weights of the points for arc-length averages: trapezoid rule on ``s`` (fixed
        in time, so measurement noise in segment lengths does not enter the averages)."""
        ds = np.diff(self.s)
        w = np.zeros(self.n_points)
        w[:-1] += 0.5 * ds
        w[1:] += 0.5 * ds
        tot = w.sum()
        return w / tot if tot > 0 else np.full(self.n_points, 1.0 / self.n_points)

    def centroid(self) -> tuple[np.ndarray, np.ndarray]:
        """Arc-length weighted centroid (xc, yc), each (T,)."""
        w = self.segment_weights()
        return self.x @ w, self.y @ w

    def tangent_angle(self) -> tuple[np.ndarray, np.ndarray]:
        """(s_mid (P-1,), theta (T, P-1)): the given theta if at midpoints, else from the polyline."""
        s_mid = 0.5 * (self.s[1:] + self.s[:-1])
        if self.theta is not None and self.theta.shape[1] == self.n_points - 1:
            return s_mid, np.asarray(self.theta)
        return s_mid, polyline_tangent_angle(self.x, self.y)

    def curvature(self) -> tuple[np.ndarray, np.ndarray]:
        """(s (P,), kappa (T, P)): the given kappa, else from the polyline."""
        if self.kappa is not None:
            return self.s, np.asarray(self.kappa)
        return self.s, polyline_curvature(self.x, self.y)


def as_track(obj: Any) -> Track:
    """Return ``obj`` if it is a Track, else build one from a result-like object."""
    if isinstance(obj, Track):
        return obj
    tr = getattr(obj, "track", None)
    if callable(tr):
        try:
            out = tr()
        except Exception:  # noqa: BLE001 - fall back to duck typing
            out = None
        if isinstance(out, Track):
            return out
    return Track.from_result(obj)
