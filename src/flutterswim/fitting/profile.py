"""Profile likelihood: chi^2 minimised over the other parameters with one held fixed."""

from __future__ import annotations

import numpy as np

from .model import LOG_MAP, to_physical
from .uncertainty import NAMES

__all__ = ["profile_likelihood"]


def profile_likelihood(model, base, x_best: np.ndarray, mean: np.ndarray, sem: np.ndarray,
                       sigma_rel: np.ndarray, *, n: int = 9, span: float = 2.5) -> dict:
    """For each of log B, log tau, log kappa_E: chi^2 on ``n`` values within +-``span`` sigma of
    the best fit, minimised over the other two; ``sigma_rel`` from where chi^2 rises by 1."""
    from scipy.optimize import least_squares

    from .fit import _weighted, model_jacobian

    minv = np.linalg.inv(LOG_MAP)
    y_best = LOG_MAP @ x_best
    out = {}
    for i, name in enumerate(NAMES):
        free = [k for k in range(3) if k != i]
        # within +-span sigma, at most a factor e either way (sigma may be huge if unidentifiable)
        vals = y_best[i] + np.linspace(-span, span, n) * min(max(sigma_rel[i], 1e-6), 1.0 / span)
        chi2 = []
        z = y_best[free].copy()
        for v in vals:
            def to_x(zz, v=v, i=i, free=free):
                y = y_best.copy()
                y[i] = v
                y[free] = zz
                return minv @ y

            def fun(zz, to_x=to_x):
                return _weighted(model, to_x(zz), mean, sem)[0]

            def jac(zz, free=free, to_x=to_x):
                xx = to_x(zz)
                return (model_jacobian(model, xx, model(xx)) / sem[:, None]) @ minv[:, free]

            r = least_squares(fun, z, jac=jac, method="trf", xtol=1e-12, ftol=1e-14, gtol=1e-14, max_nfev=40)
            chi2.append(float(np.sum(r.fun ** 2)))
        chi2 = np.array(chi2)
        d = chi2 - chi2.min()
        # half-width where the profile rises by one, from a parabola through the points
        c = np.polyfit(vals - y_best[i], d, 2)
        sig = float(1.0 / np.sqrt(c[0])) if c[0] > 0 else float("nan")
        phys = []
        for v in vals:
            y = y_best.copy()
            y[i] = v
            phys.append(to_physical(base, minv @ y)[i])
        out[name] = {"values": np.array(phys), "chi2": chi2, "sigma_rel": sig}
    return out
