"""Uncertainty of a fit: covariance from the Jacobian, correlations, the identifiability card
(singular values and the poorly determined combination), profile likelihoods, bootstrap.

Coordinates: the solver works in x = (log eta_perp, log chi, log tau); results are reported
for y = (log B, log tau, log kappa_E), y = const + LOG_MAP x, so relative 1-sigma errors are
the square roots of the diagonal of cov_y = LOG_MAP cov_x LOG_MAP^T.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .model import LOG_MAP

__all__ = ["Covariance", "covariance", "IdentifiabilityCard", "identifiability_card", "NAMES"]

NAMES = ("B", "tau", "kappa_E")


@dataclass(frozen=True)
class Covariance:
    """cov_y (3, 3) of (log B, log tau, log kappa_E), relative 1-sigma, correlations."""

    cov: np.ndarray
    sigma_rel: np.ndarray
    correlation: np.ndarray


def covariance(jw_x: np.ndarray) -> Covariance:
    """From the Jacobian of the sigma-weighted residuals with respect to x, (n_res, n_x); the
    first three columns are (log eta_perp, log chi, log tau); further (nuisance) columns, such
    as a phase, are marginalised."""
    # (J^T J)^-1 by the SVD of J, with no truncation: a poorly determined direction must show
    # up as a large variance, not be dropped as a pseudo-inverse would
    _, s, vt = np.linalg.svd(jw_x, full_matrices=False)
    with np.errstate(divide="ignore"):
        inv_s2 = np.where(s > 0, 1.0 / (s * s), np.inf)
    cov_x = ((vt.T * inv_s2) @ vt)[:3, :3]
    cov_y = LOG_MAP @ cov_x @ LOG_MAP.T
    sig = np.sqrt(np.clip(np.diag(cov_y), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov_y / np.outer(sig, sig)
    return Covariance(cov_y, sig, corr)


@dataclass(frozen=True)
class IdentifiabilityCard:
    """Singular values of the weighted Jacobian in y = log(B, tau, kappa_E) (largest first),
    their right singular vectors (columns), the poorly determined combination as exponents
    (B^a tau^b kappa_E^c, normalised to a unit vector) and the sensitivities
    d log(descriptor) / d log(parameter) (descriptors by parameters)."""

    singular_values: np.ndarray
    vectors: np.ndarray
    weakest: np.ndarray
    condition_number: float
    sensitivities: np.ndarray

    def describe(self) -> str:
        a = self.weakest / self.weakest[np.argmax(np.abs(self.weakest))]
        combo = " ".join(f"{n}^{v:+.2f}" for n, v in zip(NAMES, a) if abs(v) > 0.05)
        # ("poorly determined" at every condition number: also at 2.9, with 1-sigmas under 1 %)
        how = "poorly determined" if self.condition_number > POORLY_CONDITIONED else "least determined"
        return (f"condition number {self.condition_number:.3g}; {how}: {combo} "
                f"(singular value {self.singular_values[-1]:.3g} against {self.singular_values[0]:.3g})")


#: a condition number above this calls the weakest combination poorly determined (below it,
#: only the least determined of the three)
POORLY_CONDITIONED = 100.0


def identifiability_card(jw_x: np.ndarray, sens_x: np.ndarray) -> IdentifiabilityCard:
    """``jw_x``: weighted-residual Jacobian in x (first three columns used); ``sens_x``:
    d log(descriptor)/dx (n_desc, 3)."""
    minv = np.linalg.inv(LOG_MAP)  # dx/dy
    jw_y = jw_x[:, :3] @ minv
    _, s, vt = np.linalg.svd(jw_y, full_matrices=False)
    weakest = vt[-1] / np.linalg.norm(vt[-1])
    cond = float(s[0] / s[-1]) if s[-1] > 0 else math.inf
    return IdentifiabilityCard(s, vt.T, weakest, cond, sens_x @ minv)
