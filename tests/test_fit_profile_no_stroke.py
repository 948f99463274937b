"""A profile-likelihood scan that reaches parameters without a stroke: those points are the
profile rising without bound, not the end of the fit (a review: `fit --profiles` failed after
3 minutes with "NotSwimming: the straight state is linearly stable here", and no fit.json)."""

import math

import numpy as np

from flutterswim.fitting.model import NotSwimming
from flutterswim.fitting.profile import profile_likelihood
from flutterswim.params import PAPER


class _LinearModel:
    """Descriptors linear in x (log B, log tau, log kappa_E); no stroke below x[2] = -0.02."""

    A = np.array([[0.0, 1.0, -0.3], [0.5, 0.5, 1.0], [0.3, 0.3, 0.8]])

    def __call__(self, x):
        x = np.asarray(x, float)
        if x[2] < -0.02:
            raise NotSwimming("the straight state is linearly stable here")
        return np.array([1.0, 2.0, 3.0]) + self.A @ x


def test_points_without_a_stroke_are_an_unbounded_rise_not_a_failure():
    model = _LinearModel()
    x_best = np.zeros(3)
    mean = model(x_best)
    sem = np.array([0.01, 0.05, 0.03])
    sigma = np.array([0.05, 0.05, 0.05])
    out = profile_likelihood(model, PAPER, x_best, mean, sem, sigma, n=9, span=2.5)
    for name, pr in out.items():
        chi2 = np.asarray(pr["chi2"])
        assert chi2.size == 9
        assert np.isfinite(chi2).any()
        assert np.all((chi2 >= -1e-9) | np.isinf(chi2)), name
        # the best fit itself: chi2 0
        assert np.nanmin(chi2) < 1e-12, name
        assert math.isfinite(pr["lower"]) or math.isfinite(pr["upper"]), name
    # somewhere the scan met the edge of the stroke's region
    assert any(np.isinf(np.asarray(pr["chi2"])).any() for pr in out.values())
