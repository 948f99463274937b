"""A cheap local surrogate of the descriptor model, for calibration studies (hundreds of
refits): each log-descriptor as a full quadratic in (log eta_perp, log chi), fitted to the
model's orbits on a 3 x 3 grid around a centre. Same interface as DescriptorModel."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .model import DescriptorModel

__all__ = ["LocalSurrogate"]


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
