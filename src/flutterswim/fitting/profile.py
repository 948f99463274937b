"""Profile likelihood: chi^2 minimised over the other parameters with one held fixed."""

from __future__ import annotations

import math

import numpy as np

from .model import LOG_MAP, to_physical
from .uncertainty import NAMES

__all__ = ["profile_likelihood", "profile_interval"]


def profile_likelihood(model, base, x_best: np.ndarray, mean: np.ndarray, sem: np.ndarray,
                       sigma_rel: np.ndarray, *, n: int = 9, span: float = 2.5) -> dict:
    """For each of log B, log tau, log kappa_E: chi^2 on ``n`` values within +-``span`` sigma of
    the best fit, minimised over the other two; ``sigma_rel`` from where chi^2 rises by 1."""
    from scipy.optimize import least_squares

    from .fit import Penalty, _weighted, model_jacobian

    from .model import NotSwimming

    minv = np.linalg.inv(LOG_MAP)
    y_best = LOG_MAP @ x_best
    out = {}
    for i, name in enumerate(NAMES):
        free = [k for k in range(3) if k != i]
        # within +-span sigma, at most a factor e either way (sigma may be huge if unidentifiable)
        vals = y_best[i] + np.linspace(-span, span, n) * min(max(sigma_rel[i], 1e-6), 1.0 / span)
        chi2 = np.full(vals.size, np.inf)  # inf: no stroke there (the profile rises without bound)
        # outwards from the best fit, each value started from its inner neighbour's minimum (a
        # start far out along the scan with the other parameters at their best can have no
        # stroke: the Jacobian there failed and the whole fit was lost)
        centre = int(np.argmin(np.abs(vals - y_best[i])))
        order = list(range(centre, vals.size)) + list(range(centre - 1, -1, -1))
        starts = {centre: y_best[free].copy()}
        for j in order:
            v = vals[j]
            z = starts.get(j + 1 if j < centre else j - 1, starts[centre])
            def to_x(zz, v=v, i=i, free=free):
                y = y_best.copy()
                y[i] = v
                y[free] = zz
                return minv @ y

            penalty = Penalty()

            def fun(zz, to_x=to_x, penalty=penalty):
                return _weighted(model, to_x(zz), mean, sem, penalty)[0]

            def jac(zz, free=free, to_x=to_x):
                xx = to_x(zz)
                return (model_jacobian(model, xx, model(xx)) / sem[:, None]) @ minv[:, free]

            try:
                model(to_x(z))
                r = least_squares(fun, z, jac=jac, method="trf", xtol=1e-12, ftol=1e-14, gtol=1e-14, max_nfev=40)
            except NotSwimming:
                starts[j] = z
                continue
            starts[j] = r.x
            chi2[j] = float(np.sum(r.fun ** 2))
        lo, hi = profile_interval(vals - y_best[i], chi2)
        sig = 0.5 * (lo + hi) if math.isfinite(lo + hi) else min(lo, hi)
        phys = []
        for v in vals:
            y = y_best.copy()
            y[i] = v
            phys.append(to_physical(base, minv @ y)[i])
        out[name] = {"values": np.array(phys), "chi2": chi2, "sigma_rel": sig, "lower": lo, "upper": hi}
    return out


def profile_interval(dv: np.ndarray, chi2: np.ndarray) -> tuple[float, float]:
    """Distances below and above the minimum where the profile ``chi2`` (sampled at offsets
    ``dv``, increasing) first rises by 1 over its minimum, by linear interpolation between
    samples; a side that does not rise by 1 within the scan gives the distance to its last
    sample (a lower bound, never NaN) when it is still rising at its end (end slope at least a
    quarter of its mean slope), and inf when it has levelled off."""
    d = np.asarray(chi2, float) - np.min(chi2)
    k = int(np.argmin(d))
    out = []
    for idx in (range(k - 1, -1, -1), range(k + 1, d.size)):
        prev, width = k, math.inf
        for j in idx:
            if d[j] >= 1.0:
                w = (1.0 - d[prev]) / (d[j] - d[prev])
                width = abs(dv[prev] + w * (dv[j] - dv[prev]) - dv[k])
                break
            prev = j
        else:
            last = list(idx)
            if len(last) >= 2:
                j1, j0 = last[-1], last[-2]
                span = abs(dv[j1] - dv[k])
                end_slope = (d[j1] - d[j0]) / abs(dv[j1] - dv[j0])
                if d[j1] > 0 and end_slope >= 0.25 * d[j1] / span:  # still rising: at least the scan
                    width = span
        out.append(width)
    return out[0], out[1]
