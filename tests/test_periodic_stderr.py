"""The periodic template's coefficient standard error (tracking.periodic._coef_stderr) against
Monte Carlo: white noise, and noise correlated from frame to frame as a smoothed end's is."""

import numpy as np
import pytest

from flutterswim.tracking.periodic import _coef_stderr, fourier_basis


@pytest.mark.parametrize("theta", [0.0, 0.5])
def test_coefficient_stderr_matches_monte_carlo(theta):
    # 101 frames, 18.9 per stroke, 6 harmonics (13 coefficients per coordinate) fitted to noise
    # e_t = w_t + theta w_(t-1) (lag-1 correlation 0.4 at theta = 0.5): the empirical scatter of
    # the first harmonic's coefficients against the mean estimate from the fits' residuals
    rng = np.random.default_rng(7)
    n, H = 101, 6
    B = fourier_basis(np.arange(n) / 18.9, H)
    coefs, est, white = [], [], []
    for _ in range(1500):
        w = rng.normal(size=(n + 1, 2))
        e = w[1:] + theta * w[:-1]
        c = np.linalg.lstsq(B, e, rcond=None)[0]
        coefs.append(c[[1, 1 + H]].ravel())
        d = e - B @ c
        est.append(_coef_stderr(d, B.shape[1]))
        white.append(np.sqrt(np.sum(d**2) / (2 * (n - B.shape[1])) * 2 / n))  # no correlation factor
    sd = float(np.std(np.concatenate(coefs)))
    assert np.mean(est) == pytest.approx(sd, rel=0.1)
    if theta:  # without the correlation factor the white-noise scale misses it
        assert np.mean(white) < 0.85 * sd
