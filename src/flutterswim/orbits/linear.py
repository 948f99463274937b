"""Linear stability of the straight state from the simulator's own discrete model, and its
Hopf point.

The eigenvalues of the exact Jacobian of the shape dynamics (:class:`.system.ShapeSystem`)
at the straight state aligned with the field. One eigenvalue is exactly zero: the straight
state belongs to the family of bent equilibria theta_s = kappa = -chi sin(theta). The
leading complex pair converges at second order in h = 1/N to the root of the continuum
characteristic equation (:mod:`flutterswim.stability`), which stays an independent reference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from .._validate import ParameterError, finite
from .._validate import n_segments as segments_checked
from .parameter import Axis
from ._threads import one_blas_thread
from .system import ShapeSystem

__all__ = ["RoundoffWarning", "UnresolvedFrequencyWarning", "discrete_spectrum", "leading_pair", "leading_mode", "HopfPoint", "hopf_point", "hopf_bracket"]


def discrete_spectrum(params, n_segments: int) -> np.ndarray:
    """All eigenvalues (2N+1,) of the discrete shape dynamics at the straight state [1/tau],
    sorted by decreasing real part."""
    sysm = ShapeSystem.of(params, n_segments)
    lam = np.linalg.eigvals(sysm.jac(sysm.straight()))
    return lam[np.argsort(-lam.real)]


class RoundoffWarning(RuntimeWarning):
    """The discrete spectrum's round-off is no longer small against the leading pair."""


class UnresolvedFrequencyWarning(RoundoffWarning):
    """Other pairs decay as fast as the leading one: its growth rate is resolved, not which
    pair leads, nor so its frequency (far below the threshold)."""


#: the leading pair's round-off bound beyond which it is said to be round-off limited: relative
#: to |lambda| (the growth rate), or to its Im (the frequency of a slow oscillation)
ROUNDOFF_WARN = 1e-4
ROUNDOFF_WARN_IM = 1e-2


def _roundoff_warning(n_segments: int, a: np.ndarray, what: str) -> None:
    import warnings

    warnings.warn(f"n_segments={n_segments}: round-off in the discrete Jacobian (its norm grows like N^4 / eta_perp) "
                  f"{what}; the growth rate and the Hopf point are round-off limited here: fewer segments, or the "
                  "continuum's flutterswim.stability.leading_eigenvalue", RoundoffWarning, stacklevel=3)


def _eig_bounds(m: np.ndarray, norm: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenvalues of m, each one's round-off bound (condition number times eps ``norm``) and
    the right eigenvectors."""
    import scipy.linalg as sl

    lam, vl, vr = sl.eig(m, left=True, right=True)
    cond = (np.linalg.norm(vl, axis=0) * np.linalg.norm(vr, axis=0)
            / np.maximum(np.abs(np.einsum("ij,ij->j", vl.conj(), vr)), np.finfo(float).tiny))
    return lam, cond * np.finfo(float).eps * norm, vr


def leading_pair(params, n_segments: int) -> complex:
    """The complex eigenvalue with Im > 0 of largest real part [1/tau].

    Each eigenvalue's round-off is bounded by its condition number times eps ||A||_F (||A||
    grows like N^4 / eta_perp: 1e10 at N = 256 and eta_perp = 8; the bound is about 10 times the
    error seen). An eigenvalue is complex when its Im exceeds round-off relative to itself and
    10 times its own bound: at N = 384-512 and eta_perp = 8 round-off made spurious pairs near 0
    (0.12 + 1.07i, bound 0.3, condition 3e3) that read as an unstable straight state, and the
    Hopf point search found 104 for 121. A leading pair whose bound exceeds :data:`ROUNDOFF_WARN`
    of |lambda| or :data:`ROUNDOFF_WARN_IM` of its Im warns (RoundoffWarning), and so does a
    straight state whose only pairs are within round-off of the real axis."""
    sysm = ShapeSystem.of(params, n_segments)
    a = sysm.jac(sysm.straight())
    lam, bound, _ = _eig_bounds(a, float(np.linalg.norm(a)))
    # complex: Im beyond round-off relative to the eigenvalue itself (a cut relative to the
    # largest |lambda|, which grows like N^4, dropped the flutter pair 0.60 +- 7.2i at N = 256)
    cplx = lam.imag > 1e-6 * np.abs(lam)
    ok = cplx & (lam.imag > 10.0 * bound)
    if not ok.any():
        if cplx.any():
            _roundoff_warning(n_segments, a, "puts every complex pair within its bound of the real axis")
        raise ParameterError("the straight state has no oscillatory mode here (no complex eigenvalue)")
    k = np.flatnonzero(ok)[np.argmax(lam.real[ok])]
    if bound[k] > ROUNDOFF_WARN * abs(lam[k]) or bound[k] > ROUNDOFF_WARN_IM * lam[k].imag:
        # (no numbers in the text: a Hopf search meets it at every step, and says it once)
        _roundoff_warning(n_segments, a, "limits the leading pair")
    elif np.any(ok & (np.abs(lam.imag - lam[k].imag) > ROUNDOFF_WARN_IM * lam[k].imag)
                & (lam.real > lam.real[k] - ROUNDOFF_WARN * abs(lam[k]))):
        # far below the threshold (|chi| < 1) the pairs crowd at Re = -1 (the passive relaxation):
        # which one leads is decided by 1e-5 in Re, and the pair taken had 0.2-0.6 of the
        # continuum's frequency at N = 96-160 (a review: 22 of 160 cases, without a word)
        import warnings

        warnings.warn(f"n_segments={n_segments}: other oscillatory modes decay within {ROUNDOFF_WARN:g} of the "
                      "leading pair's rate (a cluster, far below the threshold): its growth rate is resolved, but not "
                      "which of them leads, and so not its frequency", UnresolvedFrequencyWarning, stacklevel=2)
    return complex(lam[k])


def flutter_growth(axis: Axis, value: float, n_segments: int) -> float:
    """Re of the leading complex pair at ``value`` of ``axis`` [1/tau]; -1 where there is no
    oscillatory mode at all (chi = 0: the passive relaxation's real eigenvalues), no flutter."""
    import warnings

    params = axis.at(value)  # a value the model refuses is an error, not "no flutter"
    try:
        with warnings.catch_warnings():  # (the growth rate alone: resolved in a cluster)
            warnings.simplefilter("ignore", UnresolvedFrequencyWarning)
            return leading_pair(params, n_segments).real
    except ParameterError:
        return -1.0


def hopf_bracket(axis: Axis, n: int, base: float, to: float, *, prefer: float | None = None
                 ) -> tuple[float, float] | None:
    """A bracket (lo, hi) of a Hopf point of ``axis`` between ``base`` and ``to`` (a sign change
    of the flutter growth rate on 9 values), or None if there is none there; of several, the
    one nearest ``prefer`` (default: the first from the smaller end)."""
    grid = np.linspace(min(base, to), max(base, to), 9)
    g = [flutter_growth(axis, v, n) for v in grid]
    found = [(float(grid[i]), float(grid[i + 1])) for i in range(len(grid) - 1) if g[i] * g[i + 1] <= 0]
    if not found:
        return None
    if prefer is None:
        return found[0]
    return min(found, key=lambda b: abs(0.5 * (b[0] + b[1]) - prefer))


def _leader(lam: np.ndarray, bound: np.ndarray, keep: np.ndarray) -> tuple[int, bool]:
    """The eigenvalue of largest real part among ``keep`` and resolved from 0 (beyond 10 times
    its bound), and whether an unresolved one lies to its right."""
    resolved = keep & (np.abs(lam) > 10.0 * bound)
    pool = resolved if resolved.any() else keep
    k = int(np.flatnonzero(pool)[np.argmax(lam.real[pool])])
    return k, bool(np.any(keep & ~pool & (lam.real > lam.real[k])))


def leading_mode(params, n_segments: int) -> complex:
    """The eigenvalue of largest real part [1/tau] (Im >= 0), leaving out the zero mode of the
    bent-equilibrium family: the growth rate and angular frequency of the straight state.

    Two ways, checked against each other. (a) A's own spectrum less the eigenvalue along its
    null vector (the right singular vector of its smallest singular value): accurate, but
    round-off can move the zero mode far from 0 at high N (+2.81 at eta_perp = 0.1, N = 256;
    split into 2.2 +- 3.4i at N = 384, where another eigenvalue then lies nearer the null vector).
    (b) The zero mode deflated: A maps into its range, the complement of its left null vector,
    so with Q an orthonormal basis of it A Q = Q (Q^T A Q), whose eigenvalues are A's but the
    zero one; but Q^T A Q splits the defective cluster of the relaxation's modes at -1 further
    (a real -0.99998 beside the pair -0.99999 + 0.111i at eta_perp = 1, chi = 1, N = 24). Where
    their leaders' real parts agree within 10 times (b)'s bound, the one with the smaller bound is
    returned; else (b)'s, with a RoundoffWarning. Each takes its leader among eigenvalues resolved from 0 (beyond 10
    times their bound), and warns when an unresolved one lies to its right or the leader's
    bound exceeds :data:`ROUNDOFF_WARN` of |lambda|. (A cut at 1e-9 of the largest |lambda|,
    which grows like N^4 / eta_perp, had dropped the flutter pair itself at eta_perp = 8 from
    N = 256.) A pair within its round-off of the real axis counts as real."""
    sysm = ShapeSystem.of(params, n_segments)
    a = sysm.jac(sysm.straight())
    norm = float(np.linalg.norm(a))
    u, _, vt = np.linalg.svd(a)
    lam_a, b_a, vr = _eig_bounds(a, norm)
    keep = np.ones(lam_a.size, bool)
    keep[int(np.argmax(np.abs(vr.conj().T @ vt[-1]) / np.linalg.norm(vr, axis=0)))] = False
    ka, hidden_a = _leader(lam_a, b_a, keep)
    q = u[:, :-1]
    lam_b, b_b, _ = _eig_bounds(q.T @ a @ q, norm)
    kb, hidden_b = _leader(lam_b, b_b, np.ones(lam_b.size, bool))
    agree = abs(lam_a[ka].real - lam_b[kb].real) <= 10.0 * b_b[kb] + 1e-12 * abs(lam_b[kb])
    if agree and b_a[ka] <= b_b[kb]:  # (a) the sharper
        lam, bound, hidden, warn = lam_a[ka], b_a[ka], hidden_a, False
    else:  # (b): as sharp, or (a) kept round-off's zero mode, or lost the leader to it
        lam, bound, hidden, warn = lam_b[kb], b_b[kb], hidden_b, not agree
    if warn or hidden or bound > ROUNDOFF_WARN * abs(lam):
        _roundoff_warning(n_segments, a, "limits the leading eigenvalue")
    im = abs(lam.imag) if abs(lam.imag) > 10.0 * bound else 0.0
    return complex(lam.real, im)


@dataclass(frozen=True)
class HopfPoint:
    """Hopf bifurcation of the discrete model along ``axis``: the parameter value, the onset
    angular frequency omega [1/tau], the rate d Re(lambda)/d value, the right and left
    eigenvectors q, p (A q = i omega q, A^T p = -i omega p, |q| = 1, conj(p).q = 1), and the
    Jacobian A there."""

    axis: Axis
    value: float
    omega: float
    growth_slope: float
    q: np.ndarray = field(repr=False)  # the arrays are left out of the repr (a notebook printed 97 x 97)
    p: np.ndarray = field(repr=False)
    jacobian: np.ndarray = field(repr=False)
    n_segments: int

    @property
    def params(self):
        return self.axis.at(self.value)


@one_blas_thread
def hopf_point(params, parameter: str = "kappa_E_ratio", *, n_segments: int = 48,
               bracket: tuple[float, float] | None = None, xtol: float = 1e-13,
               start: float | None = None) -> HopfPoint:
    """The Hopf point of the straight state along ``parameter`` (see :class:`.parameter.Axis`),
    where the leading complex pair crosses the imaginary axis. ``bracket``: values on either
    side; by default it is searched geometrically below and above ``start`` (default: the
    base value; e.g. minus it for the mirror branch of a negative field). ``xtol`` is relative
    to the parameter's size."""
    n_segments = segments_checked(n_segments)
    axis = Axis(params, parameter)

    def growth(v: float) -> float:
        return flutter_growth(axis, v, n_segments)

    if bracket is None:
        v0 = axis.value() if start is None else finite("start", start)
        if v0 == 0:
            raise ParameterError(f"{'start' if start is not None else parameter}=0: the search scans geometrically "
                                 "from it (0.8x, 1.25x, ...); give a non-zero value, or a bracket")
        bracket = _bracket(growth, v0, parameter)
    else:
        try:
            lo, hi = (float(v) for v in bracket)
        except (TypeError, ValueError):
            raise ParameterError(f"bracket={bracket!r} must be two numbers (values of {parameter})") from None
        if not (math.isfinite(lo) and math.isfinite(hi)) or lo == hi:
            raise ParameterError(f"bracket={bracket!r} must be two different finite values of {parameter}")
        bracket = (lo, hi)
    lo, hi = bracket
    glo, ghi = growth(lo), growth(hi)
    if glo * ghi > 0:
        raise ParameterError(f"{parameter} in [{lo:g}, {hi:g}] does not bracket a Hopf point "
                             f"(growth rates {glo:.3g} and {ghi:.3g} have one sign)")
    # xtol relative to the parameter's size (physical parameters such as B are ~1e-14)
    v = brentq(growth, lo, hi, xtol=xtol * max(abs(lo), abs(hi)), rtol=4 * np.finfo(float).eps, maxiter=200)
    sysm = ShapeSystem.of(axis.at(v), n_segments)
    a = sysm.jac(sysm.straight())
    lam, vr = np.linalg.eig(a)
    i = int(np.argmin(np.abs(lam - leading_pair(axis.at(v), n_segments))))
    omega = float(lam[i].imag)
    q = vr[:, i] / np.linalg.norm(vr[:, i])
    lam_l, vl = np.linalg.eig(a.T)
    j = int(np.argmin(np.abs(lam_l - np.conj(lam[i]))))
    p = vl[:, j]
    p = p / np.conj(np.vdot(p, q))  # conj(p).q = 1
    # d lambda / d value = conj(p) . (dA / d value) q: the difference of the Jacobian, whose
    # entries are smooth in the value, not of the eigenvalue, which carries the eigensolver's
    # round-off (2e-9 at N = 48, 7e-8 at N = 96: over a step of 1e-6 relative that made the
    # slope off by 0.5-6 %, depending on where the search started)
    dv = 1e-6 * abs(v) if v != 0 else 1e-6  # relative: physical parameters may be ~1e-14
    jac_at = [ShapeSystem.of(axis.at(x), n_segments) for x in (v + dv, v - dv)]
    da = (jac_at[0].jac(jac_at[0].straight()) - jac_at[1].jac(jac_at[1].straight())) / (2 * dv)
    slope = float(np.vdot(p, da @ q).real)
    return HopfPoint(axis, float(v), omega, slope, q, p, a, n_segments)


def _bracket(growth, v0: float, name: str = "the parameter") -> tuple[float, float]:
    """Bracket (lo, hi) the sign change of the growth rate by scanning geometrically towards and
    away from zero from v0 (below and above a positive v0).
    A direction ends at the first value the model refuses (b beyond l/2, a above b ...): the
    scan never reports on values nobody asked for; nor does it warn about them."""
    import warnings

    from ..params import SlendernessWarning

    def sign_change(v: float) -> bool | None:  # None: v is not a valid value of the parameter
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", SlendernessWarning)
                return growth(v) * g0 <= 0
        except ParameterError:
            return None

    g0 = growth(v0)
    # three decades each way: a point far past onset (kappa_E_ratio 60, chi = 4242) has its Hopf
    # point at chi = 48.3, a sixtieth of it (two decades had missed it and said there was none)
    below = v0 * np.array([0.8, 0.6, 0.45, 0.3, 0.2, 0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001])
    above = v0 * np.array([1.25, 1.6, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0])
    last = {"below": v0, "above": v0}  # the last valid value scanned on each side
    open_ = {"below": True, "above": True}
    for vb, va in zip(below, above):
        for side, v in (("below", vb), ("above", va)):
            if not open_[side]:
                continue
            change = sign_change(v)
            if change is None:
                open_[side] = False
            elif change:
                return (float(min(v, last[side])), float(max(v, last[side])))
            else:
                last[side] = v
    ends = sorted((last["below"], last["above"]))
    raise ParameterError(f"no Hopf point found for {name} between {ends[0]:g} and {ends[1]:g} "
                         f"(the straight state is {'un' if g0 > 0 else ''}stable throughout)")


def omega_to_period(omega: float) -> float:
    return 2 * math.pi / omega
