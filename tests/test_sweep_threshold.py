"""The kappa_E sweep on the paper preset: no swimming at low ratio, swimming above a sharp
transition that lies within 2% of the linear-stability threshold (continuum, Newton on the
characteristic function; the n_segments=24 discretisation shifts it by well under 1%), and
the continuation up/down shows whether the Hopf bifurcation is hysteretic."""

import numpy as np
import pytest

from flutterswim.params import PAPER
from flutterswim.stability import leading_eigenvalue, physical_stability
from flutterswim.sweep import hysteresis, onset_fit, sweep
from flutterswim.sweep.continuation import transition


@pytest.fixture(scope="module")
def rc():
    return physical_stability(PAPER).critical_kappa_E / PAPER.kappa_E


@pytest.mark.slow
def test_transition_within_2_percent_of_linear_threshold(rc):
    ratios = sorted([0.1, 0.4, 0.98 * rc, 1.02 * rc, 1.0, 1.5])
    ds = sweep({"kappa_E_ratio": ratios}, settings={"t_cap": 40.0}, progress=False)
    assert not ds["failed"].any()
    x = ds["kappa_E_ratio"].values
    straight, unstable, swim = ds["straight"].values, ds["unstable"].values, ds["swimming"].values
    assert straight[x < rc].all() and not unstable[x < rc].any()
    assert unstable[x > rc].all() and not straight[x > rc].any()
    lo, hi = transition(x, unstable)
    assert 0.98 * rc - 1e-12 <= lo < rc < hi <= 1.02 * rc + 1e-12
    # swimming (limit cycle, forward along the field) well above the threshold, not below
    for r in (1.0, 1.5):
        p = ds.sel(kappa_E_ratio=r)
        assert bool(p["swimming"]) and bool(p["limit_cycle_reached"]) and float(p["advance_per_cycle_bl"]) > 0.01
    assert not swim[x < rc].any()
    # measured growth of the oscillation near onset has the sign and size of the linear rate
    for r in (0.98 * rc, 1.02 * rc):
        om = leading_eigenvalue(PAPER.chi * r, PAPER.eta_perp).omega.real
        got = float(ds["amplitude_growth_rate"].sel(kappa_E_ratio=r))
        assert np.sign(got) == np.sign(om) and abs(got - om) < 0.5 * abs(om)


@pytest.mark.slow
def test_continuation_hysteresis_and_onset_law(rc):
    """Up/down continuation near onset: brackets of the onset on both branches, and the
    limit-cycle amplitude against (chi - chi_cr) on the up branch (exponent reported)."""
    ratios = list(np.round(rc * np.array([0.9, 0.96, 1.04, 1.1, 1.2, 1.35, 1.5]), 6))
    ds = sweep({"kappa_E_ratio": ratios}, continuation=True, settings={"t_cap": 80.0}, progress=False)
    assert not ds["failed"].any()
    h = hysteresis(ds)
    up_lo, up_hi = h["up"]
    assert up_lo < rc < up_hi
    # the down branch loses the oscillation no lower than 10% below the linear threshold:
    # a hysteresis, if any, is narrower than the grid; without one both brackets agree
    dn_lo, dn_hi = h["down"]
    assert dn_hi >= 0.9 * rc
    if not h["hysteresis"]:
        assert (dn_lo, dn_hi) == (up_lo, up_hi)
    up = ds.sel(branch="up")
    ok = up["limit_cycle_reached"].values
    chi = up["kappa_E_ratio"].values * PAPER.chi
    fit = onset_fit(chi[ok], up["oscillation_amplitude"].values[ok], rc * PAPER.chi)
    assert 0.2 < fit.exponent < 0.8
