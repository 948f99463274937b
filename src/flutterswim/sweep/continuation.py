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


def hysteresis(ds, dim: str | None = None, flag: str = "limit_cycle") -> dict[str, Any]:
    """Onset brackets on the up and down branches of a continuation sweep and whether they differ.

    Returns {"up": (lo, hi), "down": (lo, hi), "hysteresis": bool, "width": float} where the
    brackets are the last non-swimming and first swimming axis values (``flag``)."""
    if "branch" not in ds.dims:
        raise ParameterError("hysteresis needs a continuation sweep (a 'branch' dimension)")
    dim = dim or [d for d in ds[flag].dims if d != "branch"][0]
    x = ds[dim].values
    up = transition(x, ds[flag].sel(branch="up").values)
    down = transition(x, ds[flag].sel(branch="down").values)
    hyst = bool(np.isfinite(up[1]) and np.isfinite(down[1]) and (down[1] < up[0] or up[1] < down[0]))
    width = float(up[1] - down[1]) if hyst else 0.0
    return {"up": up, "down": down, "hysteresis": hyst, "width": width}


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
