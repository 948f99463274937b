"""Neutral (Hopf) curve chi_cr(eta_perp), computed directly.

At each eta_perp solve g(i beta; chi, eta_perp) = 0 for the real unknowns (chi, beta) by
Newton (g: reduced characteristic function; beta: angular frequency at onset, 1/tau), and
continue in eta_perp from a seed located with the leading eigenvalue. The map is symmetric,
so the curve is reported for chi > 0 (the other branch is -chi_cr).

Continuation follows one pair's crossing. Beyond eta_perp ~ 400 another pair can cross first,
and a coarse grid can step onto another pair's crossing (even at chi < 0): the followed points
are checked against the leading eigenvalue (every CHECK_STRIDE-th point, and wherever chi_cr
jumps by more than CHECK_JUMP between neighbours), and a point that is not the onset is found
again from scratch (:func:`critical_chi`), the continuation going on from it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import ParameterError, positive
from . import _kernels
from .leading import leading_eigenvalue, same_root
from .stability_map import _grid

__all__ = ["NeutralCurve", "neutral_curve", "critical_chi"]

#: the followed curve is checked against the leading eigenvalue at every CHECK_STRIDE-th point
#: and wherever chi_cr moves by more than CHECK_JUMP (relative) from one point to the next
CHECK_STRIDE = 50
CHECK_JUMP = 0.05


@dataclass(frozen=True)
class NeutralCurve:
    """eta_perp (n,); chi_cr (n,) > 0, NaN where no onset with chi_cr <= chi_max or eta_perp <= 0;
    beta (n,) onset angular frequency [1/tau]; iterations (n,) Newton steps (-1: none)."""

    eta_perp: np.ndarray
    chi_cr: np.ndarray
    beta: np.ndarray
    iterations: np.ndarray

    def to_dataset(self):
        import xarray as xr

        from .._cf import cf_dataset

        return cf_dataset(xr.Dataset(
            {"chi_cr": ("eta_perp", self.chi_cr, {"long_name": "critical chi (Hopf)", "units": "1"}),
             "beta": ("eta_perp", self.beta, {"long_name": "onset angular frequency", "units": "1/tau"}),
             "iterations": ("eta_perp", self.iterations, {"long_name": "Newton iterations (-1: none)",
                                                          "units": "1"})},
            coords={"eta_perp": ("eta_perp", self.eta_perp,
                                 {"long_name": "normal drag group eta_perp = mu_perp l^4/(B tau)", "units": "1"})},
        ))


def _seed(eta: float, chi_max: float, tol: float) -> tuple[float, float]:
    """Bracket Re omega_max = 0 in chi at fixed eta, then Hopf-Newton."""
    lo_chi = 0.0
    chi = 1.0
    prev = None
    while chi <= 2 * chi_max:
        le = leading_eigenvalue(chi, eta)
        if le.omega.real > 0:
            if prev is None:
                prev = (lo_chi, leading_eigenvalue(max(lo_chi, 1e-3), eta).omega)
            (c0, w0), (c1, w1) = prev, (chi, le.omega)
            for _ in range(40):  # bisection on the leading eigenvalue to ~1e-3 relative
                if c1 - c0 <= 1e-3 * c1:
                    break
                cm = 0.5 * (c0 + c1)
                wm = leading_eigenvalue(cm, eta).omega
                if wm.real > 0:
                    c1, w1 = cm, wm
                else:
                    c0, w0 = cm, wm
            if c0 > chi_max:  # (the onset lies beyond chi_max: NaN, as documented)
                return np.nan, np.nan
            t = -w0.real / (w1.real - w0.real)
            cg, bg = c0 + t * (c1 - c0), w0.imag + t * (w1.imag - w0.imag)
            lam = np.empty(4, dtype=np.complex128)
            c, b, it = _kernels._hopf_newton(cg, bg, eta, lam, False, tol, 50)
            if it >= 0 and c > chi_max:  # (bracketed below chi_max, the onset just beyond it)
                return np.nan, np.nan
            if it < 0 or not c > 0:
                raise RuntimeError(f"the Hopf point at eta_perp={eta:.6g} was bracketed at chi in [{c0:.6g}, "
                                   f"{c1:.6g}] but its Newton solve did not converge (eta_perp is validated for "
                                   "0.1-5000)")
            return c, b
        prev = (chi, le.omega)
        lo_chi = chi
        chi *= 1.5
    return np.nan, np.nan


def critical_chi(eta_perp: float, *, chi_max: float = 1e4, tol: float = 1e-12) -> tuple[float, float]:
    """(chi_cr, beta) at one eta_perp: smallest chi > 0 with Re omega_max = 0 (NaN if > chi_max)."""
    eta_perp = positive("eta_perp", eta_perp)
    return _seed(eta_perp, positive("chi_max", chi_max), tol)


def neutral_curve(eta_perp=None, *, eta_range: tuple[float, float] = (0.0, 350.0), step: float = 0.1,
                  chi_max: float = 1e4, tol: float = 1e-12, seed_eta: float | None = None) -> NeutralCurve:
    """chi_cr(eta_perp) by Hopf-Newton continued along the sorted eta_perp grid.

    eta_perp: 1-D increasing array, or None for arange(eta_range[0], eta_range[1] + step/2, step).
    The seed is at ``seed_eta`` (default: the largest eta_perp); the curve is continued both
    ways. eta_perp <= 0 (no drag, degenerate) gives NaN.
    """
    eta = _grid(eta_perp, eta_range, step, "eta_perp")  # (at most MAX_MAP_POINTS values, checked first)
    if eta[0] < 0:
        raise ParameterError(f"eta_perp={eta[0]!r} must be >= 0 (eta_perp = 0 gives NaN)")
    chi_max = positive("chi_max", chi_max)
    n = eta.size
    chi_cr = np.full(n, np.nan)
    beta = np.full(n, np.nan)
    its = np.full(n, -1, dtype=np.int64)
    valid = np.flatnonzero(eta > 0)
    if valid.size == 0:
        return NeutralCurve(eta, chi_cr, beta, its)
    k0 = valid[-1] if seed_eta is None else valid[np.argmin(np.abs(eta[valid] - seed_eta))]
    c0, b0 = _seed(float(eta[k0]), chi_max, tol)
    if not np.isfinite(c0):
        return NeutralCurve(eta, chi_cr, beta, its)
    for sl in (slice(k0, valid[0] - 1 if valid[0] > 0 else None, -1), slice(k0, None)):
        chi_cr[sl], beta[sl], its[sl] = _follow(np.ascontiguousarray(eta[sl]), c0, b0, chi_max, tol)
    return NeutralCurve(eta, chi_cr, beta, its)


def _is_onset(c: float, b: float, eta: float) -> bool:
    """(c, b) is the leading pair's crossing at eta: c > 0 and omega_max(c, eta) = i b."""
    if not (np.isfinite(c) and c > 0):
        return False
    return same_root(leading_eigenvalue(float(c), float(eta)).omega, complex(0.0, abs(b)))


def _follow(e: np.ndarray, c0: float, b0: float, chi_max: float, tol: float):
    """(chi_cr, beta, iterations) along ``e`` (ordered away from the seed (c0, b0) at e[0]):
    Hopf-Newton continuation, checked against the leading eigenvalue; a checked point that is
    not the onset is found again from scratch, with the unchecked points since the last good
    check, and the continuation restarts from it. From the first eta_perp whose onset lies
    beyond chi_max (confirmed from scratch) the curve is NaN."""
    n = e.size
    chi_cr, beta, its = np.full(n, np.nan), np.full(n, np.nan), np.full(n, -1, dtype=np.int64)
    k, c, b, good = 0, c0, b0, -1  # follow from index k with the seed (c, b); good: last point known right
    while k < n:
        oc, ob, oi = np.empty(n - k), np.empty(n - k), np.empty(n - k, dtype=np.int64)
        _kernels._neutral_follow(np.ascontiguousarray(e[k:]), c, b, tol, 50, chi_max, oc, ob, oi)
        chi_cr[k:], beta[k:], its[k:] = oc, ob, oi
        wrong = None
        for j in range(k, n):
            prev = chi_cr[j - 1] if j > 0 else c0
            if not np.isfinite(chi_cr[j]):
                wrong = j  # the continuation stopped: confirmed (or not) from scratch
                break
            if ((j - k) % CHECK_STRIDE == 0 or j == n - 1 or chi_cr[j] <= 0
                    or abs(chi_cr[j] - prev) > CHECK_JUMP * abs(prev)):
                if not _is_onset(chi_cr[j], beta[j], e[j]):
                    wrong = j
                    break
                good = j
        if wrong is None:
            break
        for j in range(good + 1, wrong + 1):  # (the unchecked points may be on the other pair too)
            chi_cr[j], beta[j] = _seed(float(e[j]), chi_max, tol)
            its[j] = 0 if np.isfinite(chi_cr[j]) else -1
        if not np.isfinite(chi_cr[wrong]):
            chi_cr[wrong:], beta[wrong:], its[wrong:] = np.nan, np.nan, -1
            break
        k, c, b, good = wrong + 1, chi_cr[wrong], beta[wrong], wrong
    return chi_cr, beta, its
