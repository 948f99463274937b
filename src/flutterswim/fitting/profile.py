"""Profile likelihood: chi^2 minimised over the other parameters with one held fixed."""

from __future__ import annotations

import math

import numpy as np

from .model import LOG_MAP, to_physical
from .uncertainty import NAMES

__all__ = ["profile_likelihood"]


#: a side of a profile still under chi^2 + 1 this far out (log: a factor 100) is unbounded
MAX_LOG_SPAN = math.log(100.0)
#: bisection steps on the crossing of chi^2 + 1 (its bracket shrinks 32-fold)
BISECT = 5


def profile_likelihood(model, base, x_best: np.ndarray, mean: np.ndarray, sem: np.ndarray,
                       sigma_rel: np.ndarray, *, n: int = 9, span: float = 2.5) -> dict:
    """For each of log B, log tau, log kappa_E: chi^2 on ``n`` values within +-``span`` sigma of
    the best fit (at most a factor e either way), minimised over the other two; ``lower`` and
    ``upper`` (log distances) from where chi^2 rises by 1.

    The crossing is bisected (:data:`BISECT` steps) between the grid's values: interpolating
    linearly across a grid step h places a crossing at distance s near s^2 / h, and at a fold,
    where the Jacobian's sigma is meaningless, the grid step was a factor 1.28 and the intervals
    held the truth in 3 of 18 cases (a review). A side that stays under chi^2 + 1 over the grid is
    followed outwards, doubling the distance, to :data:`MAX_LOG_SPAN`; if it stays under there
    it is unbounded (inf): a flat profile had been given the grid's edge as its width. A value
    whose inner fit ends above its outer neighbour's (a failed minimisation: one spike made a
    bound 1e-4) is refitted from that neighbour's minimum. ``values``/``chi2``: the grid."""
    from scipy.optimize import least_squares

    from .fit import Penalty, _weighted, model_jacobian

    from .model import NotSwimming

    minv = np.linalg.inv(LOG_MAP)
    y_best = LOG_MAP @ x_best
    out = {}
    for i, name in enumerate(NAMES):
        free = [k for k in range(3) if k != i]

        def solve(v: float, z: np.ndarray, i=i, free=free) -> tuple[float, np.ndarray]:
            """chi^2 minimised over the free parameters at value v of parameter i, from z (inf:
            no stroke there, the profile rising without bound)."""
            def to_x(zz):
                y = y_best.copy()
                y[i] = v
                y[free] = zz
                return minv @ y

            penalty = Penalty()

            def fun(zz):
                return _weighted(model, to_x(zz), mean, sem, penalty)[0]

            def jac(zz):
                xx = to_x(zz)
                return (model_jacobian(model, xx, model(xx)) / sem[:, None]) @ minv[:, free]

            try:
                model(to_x(z))
                r = least_squares(fun, z, jac=jac, method="trf", xtol=1e-12, ftol=1e-14, gtol=1e-14, max_nfev=40)
            except NotSwimming:
                return math.inf, z
            return float(np.sum(r.fun ** 2)), r.x

        # within +-span sigma, at most a factor e either way (sigma may be huge if unidentifiable)
        offs = np.linspace(-span, span, n) * min(max(sigma_rel[i], 1e-6), 1.0 / span)
        pts: dict[float, tuple[float, np.ndarray]] = {}  # offset -> (chi2, the free parameters there)
        # outwards from the best fit (always evaluated: an even n has no grid value there, and the
        # minimum taken on the grid put the bounds 6-170 % wide), each value started from its
        # inner neighbour's minimum (a start far out along the scan with the other parameters at
        # their best can have no stroke: the Jacobian there failed and the whole fit was lost)
        pts[0.0] = solve(y_best[i], y_best[free].copy())
        sides = (list(np.flatnonzero(offs > 0)), list(np.flatnonzero(offs < 0)[::-1]))
        for side in sides:
            prev = 0.0
            for j in side:
                pts[offs[j]] = solve(y_best[i] + offs[j], pts[prev][1])
                prev = offs[j]
            # a value above its outer neighbour (both swimming): its inner fit failed; refit it
            for j, o in zip(side[-2::-1], side[:0:-1]):
                cj, co = pts[offs[j]][0], pts[offs[o]][0]
                if math.isfinite(co) and cj > co + 1e-9 * (1.0 + co):
                    again = solve(y_best[i] + offs[j], pts[offs[o]][1])
                    if again[0] < cj:
                        pts[offs[j]] = again
        chi2_min = min(c for c, _ in pts.values())
        bounds = []
        for sign in (-1.0, 1.0):
            on = sorted((o for o in pts if o * sign > 0), key=abs)
            inner = 0.0
            outer = None
            for o in on:
                if pts[o][0] - chi2_min >= 1.0:
                    outer = o
                    break
                inner = o
            # followed outwards, doubling the distance, while it stays under chi^2 + 1
            while outer is None and abs(inner) < MAX_LOG_SPAN:
                o = sign * min(2.0 * abs(inner) if inner != 0 else abs(offs[-1]), MAX_LOG_SPAN)
                pts[o] = solve(y_best[i] + o, pts[inner][1])
                if pts[o][0] - chi2_min >= 1.0:
                    outer = o
                else:
                    inner = o
            if outer is None:
                bounds.append(math.inf)
                continue
            # the crossing bisected, each value started from the inner (swimming) side's minimum
            for _ in range(BISECT):
                mid = 0.5 * (inner + outer)
                pts[mid] = solve(y_best[i] + mid, pts[inner][1])
                if pts[mid][0] - chi2_min >= 1.0:
                    outer = mid
                else:
                    inner = mid
            ci, co = pts[inner][0] - chi2_min, pts[outer][0] - chi2_min
            w = (1.0 - ci) / (co - ci) if math.isfinite(co) else 0.0
            bounds.append(abs(inner + w * (outer - inner)))
        lo, hi = bounds
        sig = 0.5 * (lo + hi) if math.isfinite(lo + hi) else min(lo, hi)
        phys = []
        for o in offs:
            y = y_best.copy()
            y[i] = y_best[i] + o
            phys.append(to_physical(base, minv @ y)[i])
        chi2 = np.array([pts[0.0 if o == 0 else o][0] for o in offs])
        out[name] = {"values": np.array(phys), "chi2": chi2, "sigma_rel": sig, "lower": lo, "upper": hi}
    return out
