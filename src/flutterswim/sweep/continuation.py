"""Continuation analysis: hysteresis between the up and down branches, onset amplitude law.

A supercritical Hopf bifurcation gives amplitude ~ (chi - chi_cr)^(1/2) just above onset and
no hysteresis; a subcritical one gives a jump and a range where the down branch keeps
swimming below the up branch's onset.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from .._validate import ParameterError

__all__ = ["hysteresis", "onset_fit", "OnsetFit", "transition"]


def transition(x: np.ndarray, unstable: np.ndarray) -> tuple[float, float]:
    """(last stable x, first unstable x above it) bracketing the onset along increasing x;
    NaNs if the sweep does not cross it."""
    x = np.asarray(x, float)
    u = np.asarray(unstable, bool)
    o = np.argsort(x)
    x, u = x[o], u[o]
    idx = np.nonzero(u)[0]
    if idx.size == 0 or idx[0] == 0:
        return math.nan, math.nan
    # onset: first unstable point after which all points are unstable
    k = idx[0]
    for j in idx:
        if np.all(u[j:]):
            k = j
            break
    return float(x[k - 1]), float(x[k])


#: two swimming strokes at one axis value whose periods differ by more than this (relative) are
#: two strokes (coexisting across a fold), not the same one reached from either side
COEXIST_PERIOD = 0.02


def hysteresis(ds, dim: str | None = None, flag: str = "limit_cycle", period: str = "period_s") -> dict[str, Any]:
    """Onset brackets on the up and down branches of a continuation sweep and whether they differ.

    Returns {"up": (lo, hi), "down": (lo, hi), "hysteresis": bool, "width": float, "range":
    (lo, hi), "bistable": [axis values]}. The brackets are the last non-swimming and first
    swimming axis values (``flag``; NaN where the branch does not cross, e.g. a down branch that
    swims down to the sweep's lowest value). Hysteresis is where the two branches differ at one
    axis value: one swims and the other not (a subcritical onset), or both swim with periods
    (``period``, if present) more than :data:`COEXIST_PERIOD` apart (two strokes across a fold),
    where both points are done and not failed (``done``, ``failed``, if present).
    Those values are ``bistable``; ``range`` their span and ``width`` its length (a lower bound:
    the sampled values). A down branch swimming below the up branch's onset had been missed
    (its bracket NaN), and so had a fold where both branches swim."""
    if "branch" not in ds.dims:
        raise ParameterError("hysteresis needs a continuation sweep (a 'branch' dimension)")
    dim = dim or [d for d in ds[flag].dims if d != "branch"][0]
    x = np.asarray(ds[dim].values, float)
    fu = np.asarray(ds[flag].sel(branch="up").values, bool)
    fd = np.asarray(ds[flag].sel(branch="down").values, bool)
    # only points computed count (a failed or undone point's flag reads False: a single failed
    # point on the down branch had made its value "bistable", and moved its branch's bracket)
    ok = {b: np.ones(x.size, bool) for b in ("up", "down")}
    for name, good in (("done", True), ("failed", False)):
        if name in ds:
            for b in ok:
                ok[b] &= np.asarray(ds[name].sel(branch=b).values, bool) == good
    up, down = transition(x[ok["up"]], fu[ok["up"]]), transition(x[ok["down"]], fd[ok["down"]])
    differ = (fu != fd) & ok["up"] & ok["down"]
    if period in ds:
        pu = np.asarray(ds[period].sel(branch="up").values, float)
        pd = np.asarray(ds[period].sel(branch="down").values, float)
        with np.errstate(invalid="ignore"):
            differ |= fu & fd & (np.abs(pu - pd) > COEXIST_PERIOD * np.minimum(np.abs(pu), np.abs(pd)))
    both = np.sort(x[differ])
    hyst = bool(both.size)
    rng = (float(both[0]), float(both[-1])) if hyst else (math.nan, math.nan)
    width = float(both[-1] - both[0]) if hyst else 0.0
    return {"up": up, "down": down, "hysteresis": hyst, "width": width, "range": rng,
            "bistable": [float(v) for v in both]}


@dataclass(frozen=True)
class OnsetFit:
    """amplitude = c (x - x_cr)^exponent fitted on swimming points within ``window`` above x_cr.
    ``supercritical``: exponent within ``tol`` of 1/2."""

    exponent: float
    exponent_stderr: float
    prefactor: float
    x_cr: float
    n_points: int
    supercritical: bool

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def onset_fit(x, amplitude, x_cr: float | tuple[float, float], *, window: float | None = None,
              tol: float = 0.15) -> OnsetFit:
    """Fit log amplitude = log c + exponent log(x - x_cr) over points with x > x_cr (and within
    ``window`` of it) and finite positive amplitude. ``x_cr`` fixed (e.g. the linear threshold)
    or a bracket (lo, hi): then x_cr is fitted too (least squares in log amplitude)."""
    x = np.asarray(x, float)
    a = np.asarray(amplitude, float)
    if isinstance(x_cr, tuple):
        from scipy.optimize import minimize_scalar

        lo, hi = float(x_cr[0]), float(min(x_cr[1], np.min(x[np.isfinite(a) & (a > 0) & (x > x_cr[0])])))

        def sse(xc):
            try:
                f = onset_fit(x, a, float(xc), window=window, tol=tol)
            except ParameterError:
                return math.inf
            m = np.isfinite(a) & (a > 0) & (x > xc) & ((x - xc <= window) if window is not None else True)
            r = np.log(a[m]) - math.log(f.prefactor) - f.exponent * np.log(x[m] - xc)
            return float(r @ r)

        xc = minimize_scalar(sse, bounds=(lo, hi - 1e-9 * max(1.0, abs(hi))), method="bounded",
                             options={"xatol": 1e-10 * max(1.0, abs(hi))}).x
        return onset_fit(x, a, float(xc), window=window, tol=tol)
    m = np.isfinite(a) & (a > 0) & (x > x_cr)
    if window is not None:
        m &= x - x_cr <= window
    if np.count_nonzero(m) < 3:
        raise ParameterError(f"onset_fit needs >= 3 swimming points above x_cr={x_cr:.6g}; got {int(np.count_nonzero(m))}")
    lx, la = np.log(x[m] - x_cr), np.log(a[m])
    A = np.vstack([lx, np.ones_like(lx)]).T
    coef, *_ = np.linalg.lstsq(A, la, rcond=None)
    resid = la - A @ coef
    nn = lx.size
    s2 = float(resid @ resid) / max(nn - 2, 1)
    se = math.sqrt(s2 / float(np.sum((lx - lx.mean()) ** 2))) if nn > 2 else math.nan
    return OnsetFit(float(coef[0]), se, float(math.exp(coef[1])), float(x_cr), int(nn),
                    bool(abs(coef[0] - 0.5) < tol))
