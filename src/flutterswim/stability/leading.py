"""Leading eigenvalue omega_max (largest real part, neutral omega = 0 modes excluded).

Spectral collocation (no guess) proposes candidates; Newton on the reduced characteristic
function polishes them. At chi = 0 the curvature decouples (kappa_t = -kappa), so omega = -1
is an eigenvalue of infinite multiplicity, and the bending modes are -k^4/eta_perp with
cos k cosh k = 1; there omega_max = max(-1, -k_1^4/eta_perp) exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import finite, positive, positive_int, within
from .newton import follow_root, newton_root
from .spectral import spectrum

__all__ = ["LeadingEigenvalue", "leading_eigenvalue", "FREE_FREE_K1", "same_root", "ROOT_RTOL"]

#: Below this |chi| the leading roots are continued from +-SMALL_CHI (accumulation at -1).
SMALL_CHI = 0.05

#: the range the solver is checked on and accepts: |chi| up to MAX_CHI, eta_perp up to
#: MAX_ETA_PERP, collocation degree up to MAX_DEGREE (chi = 1e300 ended in an IndexError,
#: eta_perp = 1e300 in omega = -1, n = 1e5 in a 75 GiB allocation)
MAX_CHI = 1e5
MAX_ETA_PERP = 1e7
MAX_DEGREE = 512

#: two eigenvalues within this relative distance are one root (the checks of followed roots)
ROOT_RTOL = 1e-6


def same_root(a: complex, b: complex) -> bool:
    """``a`` and ``b`` (finite) are the same root: |a - b| <= ROOT_RTOL max(1, |b|)."""
    return bool(np.isfinite(a) and np.isfinite(b) and abs(a - b) <= ROOT_RTOL * max(1.0, abs(b)))


#: First positive root of cos k cosh k = 1 (free-free beam).
FREE_FREE_K1 = 4.730040744862704


@dataclass(frozen=True)
class LeadingEigenvalue:
    """omega: leading eigenvalue (Im >= 0), units 1/tau; growth_rate = Re omega;
    angular_frequency = Im omega; second: next eigenvalue of a different pair;
    polished: True if Newton on the characteristic function confirmed it."""

    omega: complex
    second: complex
    chi: float
    eta_perp: float
    polished: bool

    @property
    def growth_rate(self) -> float:
        return self.omega.real

    @property
    def angular_frequency(self) -> float:
        return self.omega.imag

    @property
    def unstable(self) -> bool:
        return self.omega.real > 0.0

    @property
    def flutter(self) -> bool:
        """Unstable with an oscillating mode (Hopf / flutter)."""
        return self.omega.real > 0.0 and self.omega.imag != 0.0


def _distinct_pairs(w: np.ndarray, count: int) -> list[complex]:
    out: list[complex] = []
    for x in w:
        x = complex(x.real, abs(x.imag))
        if any(abs(x - y) <= 1e-6 * max(1.0, abs(y)) for y in out):
            continue
        out.append(x)
        if len(out) >= count:
            break
    return out


def leading_eigenvalue(chi: float, eta_perp: float, *, n: int = 32, candidates: int = 6,
                       backend: str = "auto") -> LeadingEigenvalue:
    """Leading eigenvalue at (chi, eta_perp), from scratch (no guess).

    The ``candidates`` conjugate pairs with largest real part from a degree-``n`` collocation
    are polished by Newton; unresolved candidates (Newton moves them by > 1e-4 relative or
    fails) are dropped, so the answer is a root of the characteristic function. For
    0 < |chi| < 0.05 the eigenvalues crowd the accumulation point -1 (omega + 1 ~ chi), so the
    two leading roots are followed from chi = +-0.05 along a geometric path instead.
    Checked for eta_perp >= 0.1 and |chi| <= 1000; at eta_perp <~ 1e-2 with |chi| >~ 100 raise
    ``n`` and compare. |chi| > MAX_CHI and eta_perp > MAX_ETA_PERP are refused; an answer that
    Newton could not confirm (``polished`` False) comes with a RuntimeWarning.
    """
    chi = within("chi", finite("chi", chi), -MAX_CHI, MAX_CHI, "the range the solver is checked on")
    eta_perp = within("eta_perp", positive("eta_perp", eta_perp), 0.0, MAX_ETA_PERP,
                      "the range the solver is checked on")
    n = positive_int("n", n, minimum=8, maximum=MAX_DEGREE, why="the collocation's degree")
    candidates = positive_int("candidates", candidates)
    if chi == 0.0:
        bend = [-(FREE_FREE_K1**4) / eta_perp, -(7.853204624095838**4) / eta_perp]
        vals = sorted([-1.0] + bend, reverse=True)
        return LeadingEigenvalue(complex(vals[0]), complex(vals[1]), chi, eta_perp, True)
    if abs(chi) < SMALL_CHI:
        ref = leading_eigenvalue(math.copysign(SMALL_CHI, chi), eta_perp, n=n, candidates=candidates,
                                 backend=backend)
        path = math.copysign(1.0, chi) * np.geomspace(SMALL_CHI, abs(chi), 8 + int(20 * math.log10(SMALL_CHI / abs(chi))))
        ends = []
        for w0 in (ref.omega, ref.second):
            res = follow_root(w0, path, eta_perp, backend=backend) if np.isfinite(w0) else None
            ends.append(complex(res.omega[-1]) if res is not None and res.converged[-1] else complex(math.nan, math.nan))
        ends.sort(key=lambda z: -z.real if np.isfinite(z) else math.inf)
        return LeadingEigenvalue(ends[0], ends[1], chi, eta_perp, bool(np.isfinite(ends[0])))
    sp = spectrum(chi, eta_perp, n=n)
    cand = _distinct_pairs(sp.omega, candidates)
    res = newton_root(np.array(cand), chi, eta_perp, maxit=25, backend=backend)
    ok = res.converged & (np.abs(res.omega - cand) <= 1e-4 * np.maximum(1.0, np.abs(cand)))
    if np.any(ok):
        w = res.omega[ok]
        w = np.where(w.imag < 0, w.conj(), w)
        w = np.array(_distinct_pairs(w[np.argsort(-w.real, kind="stable")], 2) + [complex(np.nan, np.nan)])
        return LeadingEigenvalue(complex(w[0]), complex(w[1]), chi, eta_perp, True)
    if not cand:
        raise RuntimeError(f"no eigenvalue found at chi={chi:.6g}, eta_perp={eta_perp:.6g}: the collocation of "
                           f"degree n={n} gave none that is finite")
    second = cand[1] if len(cand) > 1 else complex(math.nan, math.nan)
    import warnings

    warnings.warn(f"leading eigenvalue at chi={chi:.6g}, eta_perp={eta_perp:.6g} not confirmed by Newton on the "
                  f"characteristic function ({cand[0].real:.6g}{cand[0].imag:+.6g}i from the collocation of degree "
                  f"n={n}): raise n and compare", RuntimeWarning, stacklevel=2)
    return LeadingEigenvalue(cand[0], second, chi, eta_perp, False)
