"""Activity law of the hydrogel (eq. MOD:eq:nondim_EVO), dimensionless (time by tau).

The spontaneous curvature relaxes towards the field-driven target:
    kappa_t = -kappa - chi sigma sin(theta - phi),
with chi = kappa_E l, sigma the field strength (relative) and phi its direction.
Arrays: kappa and theta at the joints, shape (N+1,).
"""

from __future__ import annotations

import numpy as np

__all__ = ["activity_rate", "activity_slope"]


def activity_rate(kappa: np.ndarray, theta: np.ndarray, chi_sigma: float, phi: float) -> np.ndarray:
    """kappa_t = -kappa - chi sigma sin(theta - phi), (N+1,)."""
    return -kappa - chi_sigma * np.sin(theta - phi)


def activity_slope(theta: np.ndarray, chi_sigma: float, phi: float) -> np.ndarray:
    """d kappa_t / d theta (diagonal), -chi sigma cos(theta - phi), (N+1,); d kappa_t / d kappa = -1."""
    return -chi_sigma * np.cos(theta - phi)
