"""The O(N) mobility solve is backward stable, also where its substitution is not.

The substitution (:func:`flutterswim.mobility.substitute`) divides by pivots that are not
chosen for size; one vanishes at a kink of about 90 degrees between neighbouring segments,
where G itself is regular. :func:`flutterswim.mobility.solve` measures the substitution's
element growth and falls back to a pivoted dense solve where it is too large. Before that,
the default integrator's steps collapsed at chi = 219, N = 24, rtol 1e-8 (t = 6.34): the
rhs carried an error of 1e-2 on a rate of order 1.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import flutterswim as fs
from flutterswim import mobility
from flutterswim.filament import Filament

G = fs.PAPER.groups


def _backward_error(gm, z, b):
    return np.max(np.abs(gm @ z - b)) / (np.max(np.abs(gm)) * np.max(np.abs(z)) + np.max(np.abs(b)))


def _kinky(rng, n):
    """A shape whose neighbouring segments turn by up to about 2 radians (random walk)."""
    kink = rng.uniform(0.0, 2.0) * rng.standard_normal(n - 1)
    return np.concatenate(([0.0], np.cumsum(kink))) + rng.uniform(-3.0, 3.0)


def _problem(fil, theta, rng):
    args = fil._args(theta)
    b = np.zeros(fil.n + 2)
    b[2 : fil.n + 1] = 50.0 * rng.standard_normal(fil.n - 1)
    return args, b


@pytest.mark.parametrize("n", [24, 48])
def test_solve_is_backward_stable_on_kinked_shapes(n):
    rng = np.random.default_rng(11)
    k = mobility.kernels()
    fil = Filament(n, G.eta_par, G.eta_perp, G.chi)
    worst, unstable = 0.0, 0
    for _ in range(300):
        args, b = _problem(fil, _kinky(rng, n), rng)
        gm = k.assemble(*args)
        worst = max(worst, _backward_error(gm, k.solve(*args, b), b))
        unstable += _backward_error(gm, k.substitute(*args, b)[0], b) > 1e-10
    assert unstable > 30  # the substitution alone fails on these shapes: the test can tell
    assert worst < 1e-13


def test_substitution_growth_bounds_its_backward_error():
    """Backward error <= a few eps times the element growth, over smooth and kinked shapes:
    the quantity the fallback is decided on measures what it should."""
    rng = np.random.default_rng(5)
    k = mobility.kernels()
    ratios, growths = [], []
    for n in (24, 48, 96):
        fil = Filament(n, G.eta_par, G.eta_perp, G.chi)
        for _ in range(150):
            args, b = _problem(fil, _kinky(rng, n), rng)
            z, growth = k.substitute(*args, b)
            ratios.append(_backward_error(k.assemble(*args), z, b) / growth)
            growths.append(growth)
    assert max(growths) > 1e8 and min(growths) < 10.0  # the sample spans both regimes
    assert max(ratios) < 50 * np.finfo(float).eps


def test_the_vanishing_pivot_itself():
    """A straight filament with one kink at the angle where the substitution's pivot at that
    joint is zero: solve agrees with a pivoted dense solve; the substitution does not."""
    n, j = 24, 12
    fil = Filament(n, G.eta_par, G.eta_perp, G.chi)
    h = 1.0 / n

    def pivot(kink):
        theta = np.where(np.arange(n) >= j - 1, kink, 0.0)
        tn = fil._avg @ theta
        rxx, rxy, ryy = mobility.resistance(tn[j - 1], fil._weights[j - 1], G.eta_par, G.eta_perp)
        nx, ny = -h * np.sin(theta[j - 2]), h * np.cos(theta[j - 2])
        dfx, dfy = -(rxx * nx + rxy * ny), -(rxy * nx + ryy * ny)
        return -h * np.cos(theta[j - 1]) * dfy + h * np.sin(theta[j - 1]) * dfx

    kink = brentq(pivot, 1.0, 2.5, xtol=1e-15)
    theta = np.where(np.arange(n) >= j - 1, kink, 0.0)
    args, b = _problem(fil, theta, np.random.default_rng(2))
    k = mobility.kernels()
    dense = np.linalg.solve(k.assemble(*args), b)
    assert np.linalg.cond(k.assemble(*args)) < 1e7  # G is regular
    z, growth = k.substitute(*args, b)
    assert growth > mobility.GROWTH_MAX
    assert np.max(np.abs(k.solve(*args, b) - dense)) < 1e-12 * np.max(np.abs(dense))


def test_strongly_curled_filament_at_tight_tolerance():
    """chi = 219 (3.1 times the paper's), N = 24: kinks of up to 200 degrees between segments.
    The default integrator completes at rtol 1e-8 and agrees with itself at 1e-7."""
    g = G.replace(chi=219.0)
    runs = [fs.simulate(g, 7.0, rtol=r, atol=r * 1e-2, n_segments=24, frame_dt=0.5) for r in (1e-7, 1e-8)]
    for r in runs:
        assert r.status == "completed", r.message
    assert np.max(np.abs(runs[0].theta[-1] - runs[1].theta[-1])) < 1e-3
