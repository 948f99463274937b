"""Swimming emerges from flutter; convergence in space and time."""

import numpy as np
import pytest
from conftest import crossings, stroke

from flutterswim.simulate import simulate


@pytest.fixture(scope="module")
def paper_run(paper_groups):
    return simulate(paper_groups, 30.0, n_segments=24, rtol=1e-4, atol=1e-6, n_frames=3001)


def _envelope(res, t0, t1):
    """Peak-to-peak lateral tip offset (from the centroid) over t0 < t < t1."""
    sel = (res.t > t0) & (res.t < t1)
    return np.ptp(res.y[sel, -1] - res.y[sel].mean(axis=1))


def test_straight_state_loses_stability_and_amplitude_grows(paper_run):
    early, mid, late = (_envelope(paper_run, a, a + 2.5) for a in (3.0, 10.0, 27.0))
    assert late > 50 * early and mid > 3 * early
    assert late > 0.1  # body lengths: a large-amplitude stroke


def test_limit_cycle_is_periodic_and_swims_along_the_field(paper_run):
    r = paper_run
    tc = crossings(r.t, r.y[:, -1] - r.y.mean(axis=1))
    periods = np.diff(tc)[-6:]
    # a periodic orbit: consecutive periods agree
    assert np.ptp(periods) < 1e-3 * periods.mean()
    # displacement per cycle of the centroid: along +e1 (the field), not across it
    xc = np.interp(tc, r.t, r.x.mean(axis=1))
    yc = np.interp(tc, r.t, r.y.mean(axis=1))
    dx, dy = np.diff(xc)[-6:], np.diff(yc)[-6:]
    assert np.all(dx > 0.05)  # body lengths per cycle, towards the cathode (direction of E)
    assert np.all(np.abs(dy) < 1e-2 * dx)


def test_stroke_is_nonreciprocal(paper_run):
    """Net displacement per cycle needs a nonreciprocal stroke (scallop theorem): the loop in
    the plane (tip lateral offset, mid-body angle) encloses area. A reciprocal stroke goes
    back along its own path (zero area); two modes in quadrature give pi/4 of the box."""
    r = paper_run
    tc = crossings(r.t, r.y[:, -1] - r.y.mean(axis=1))[-6:]
    sel = (r.t >= tc[0]) & (r.t <= tc[-1])
    a = r.y[sel, -1] - r.y[sel].mean(axis=1)
    b = r.theta[sel, r.theta.shape[1] // 2] - r.theta[sel].mean(axis=1)
    area_per_cycle = 0.5 * abs(np.sum(a[:-1] * np.diff(b) - b[:-1] * np.diff(a))) / (tc.size - 1)
    assert area_per_cycle > 0.02 * np.ptp(a) * np.ptp(b)


def test_below_threshold_the_filament_stays_straight(paper_groups):
    sub = paper_groups.replace(chi=0.5 * paper_groups.chi)
    res = simulate(sub, 30.0, n_segments=16, rtol=1e-6, n_frames=3001)
    dev = np.abs(res.theta - res.theta.mean(axis=1, keepdims=True)).max(axis=1)
    assert dev.max() < 0.1
    assert _envelope(res, 27.0, 29.5) < 0.1 * _envelope(res, 3.0, 5.5)


def _period_adv(n, rtol, groups):
    res = simulate(groups, 30.0, n_segments=n, rtol=rtol, atol=rtol * 1e-2, n_frames=6001)
    return stroke(res, n_last=3)


@pytest.mark.slow
def test_spatial_convergence_is_second_order(paper_groups):
    """Interior stencils are 4th order, those next to the free ends 2nd order, so the
    scheme is 2nd order: the fitted slope tends to 2 from above as N grows."""
    vals = np.array([_period_adv(n, 1e-8, paper_groups) for n in (16, 32, 64)])
    for k in range(2):  # period, advancement
        e1, e2 = abs(vals[0, k] - vals[1, k]), abs(vals[1, k] - vals[2, k])
        slope = np.log2(e1 / e2)
        assert 1.8 < slope < 2.6, (k, vals[:, k], slope)


def test_temporal_error_falls_with_tolerance(paper_groups):
    ref = _period_adv(12, 1e-7, paper_groups)
    errs = [np.abs(np.subtract(_period_adv(12, tol, paper_groups), ref)) for tol in (1e-3, 1e-4, 1e-5)]
    errs = np.array(errs)
    assert np.all(np.diff(errs, axis=0) < 0), errs
    assert np.all(errs[-1] < 1e-3 * np.abs(ref))
