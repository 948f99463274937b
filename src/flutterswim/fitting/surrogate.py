"""A cheap local surrogate of the descriptor model, for calibration studies (hundreds of
refits): each log-descriptor as a full quadratic in (log eta_perp, log chi), fitted to the
model's orbits on a 3 x 3 grid around a centre. Same interface as DescriptorModel."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .model import DescriptorModel

__all__ = ["LocalSurrogate", "ScalingSurrogate"]


def _features(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.stack([np.ones_like(a), a, b, a * a, a * b, b * b], axis=-1)


@dataclass
class LocalSurrogate:
    base: object
    centre: np.ndarray  # (log eta_perp, log chi)
    coef: np.ndarray  # (6, 3)
    max_fit_error: float

    @classmethod
    def of(cls, model: DescriptorModel, eta_perp: float, chi: float, half_width: float = 0.05) -> "LocalSurrogate":
        c = np.array([math.log(eta_perp), math.log(chi)])
        da, db = np.meshgrid([-half_width, 0.0, half_width], [-half_width, 0.0, half_width])
        a, b = da.ravel(), db.ravel()
        y = np.log([model.dimensionless(math.exp(c[0] + p), math.exp(c[1] + q)) for p, q in zip(a, b)])
        f = _features(a, b)
        coef, *_ = np.linalg.lstsq(f, y, rcond=None)
        err = float(np.max(np.abs(f @ coef - y)))
        return cls(model.base, c, coef, err)

    def dimensionless(self, eta_perp: float, chi: float) -> np.ndarray:
        a, b = math.log(eta_perp) - self.centre[0], math.log(chi) - self.centre[1]
        return np.exp(_features(np.array(a), np.array(b)) @ self.coef)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        eta_perp, chi, tau = np.exp(x)
        d = self.dimensionless(eta_perp, chi)
        return np.array([d[0] * tau, d[1] * self.base.l * 1e3, d[2] * self.base.l * 1e3])


@dataclass
class ScalingSurrogate:
    """A cheap smooth stand-in with the model's structure, for tests of the fitting machinery:
    period = tau g(eta_perp, chi), advance = l h_a(eta_perp, chi), lateral = l h_l(eta_perp, chi),
    each log-quadratic in (a, b) = (log eta_perp / eta_ref, log chi / chi_ref) with coefficients
    ``coef`` (3, 6) on the features (1, a, b, a^2, ab, b^2). The defaults are of the size of
    the orbit model's near the paper point (period 1 tau, advance 0.1 l, lateral 0.3 l)."""

    base: object
    coef: np.ndarray = field(default_factory=lambda: np.array([
        [0.0, 0.25, -0.55, 0.05, 0.04, 0.10],
        [math.log(0.107), 0.35, 0.90, -0.10, 0.05, -0.60],
        [math.log(0.305), 0.12, 0.45, -0.30, 0.10, -0.20]]))
    eta_ref: float = 71.5
    chi_ref: float = 70.7

    def dimensionless(self, eta_perp: float, chi: float) -> np.ndarray:
        a, b = math.log(eta_perp / self.eta_ref), math.log(chi / self.chi_ref)
        return np.exp(self.coef @ np.array([1.0, a, b, a * a, a * b, b * b]))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        eta_perp, chi, tau = np.exp(x)
        d = self.dimensionless(eta_perp, chi)
        return np.array([d[0] * tau, d[1] * self.base.l * 1e3, d[2] * self.base.l * 1e3])
