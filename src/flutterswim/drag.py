"""Resistive-force drag law (eq. MOD:eq:d_RRFT), dimensionless (forces by B/l^2).

The drag density on a filament element with unit tangent t = (cos a, sin a) and normal
n = (-sin a, cos a) moving at velocity v is f = -(eta_par t t + eta_perp n n) v, with
eta = mu l^4 / (B tau) the Koens-Lauga coefficients in scaled form (:mod:`flutterswim.params`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["resistance"]


def resistance(angle, weight, eta_par, eta_perp):
    """Weighted resistance tensor w (eta_par t t + eta_perp n n) at tangent angle ``angle``.

    Scalars in, components (rxx, rxy, ryy) out.
    Compiled (inlined into the mobility kernels) when numba is installed."""
    cn = np.cos(angle)
    sn = np.sin(angle)
    rxx = weight * (eta_par * cn * cn + eta_perp * sn * sn)
    ryy = weight * (eta_par * sn * sn + eta_perp * cn * cn)
    rxy = weight * ((eta_par - eta_perp) * cn * sn)
    return rxx, rxy, ryy
