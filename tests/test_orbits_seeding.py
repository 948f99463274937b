"""Strokes found from scratch away from the paper's point (a held-out review, stop 39).

- Where eta_perp < eta_par the onset takes about 110 tau to reach the stroke: Newton from the
  80 tau seed failed (OrbitNotFound at eta_perp 33 and 36) or, just above the Hopf point,
  returned the unstable orbit of the branch from the Hopf point (eta_perp 30).
- 32 Radau steps per period were taken on trust: a strongly bent stroke (eta_perp / eta_par =
  2.5, chi three times its threshold) had its advance off by 1.8e-5, against the 1e-5 an
  orbit must meet. A stroke from scratch now doubles its steps until they no longer matter.
- A sweep point whose run had not reached its stroke by the cap was called "not periodic".
"""

import math

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.orbits import periodic_orbit
from flutterswim.orbits.linear import hopf_point
from flutterswim.orbits.periodic import STEP_TOLERANCE
from flutterswim.settle import settle

G = fs.PAPER.groups


def _stays_on(orb, periods=12):
    """A simulation started on the orbit's shape: the end angle's upward crossings are one
    period apart, and its swing is the orbit's (a stable orbit holds it, an unstable one would
    be left)."""
    n = orb.n_segments
    from flutterswim.initial import InitialState

    T = orb.period_dimensionless
    run = fs.simulate(orb.params, periods * T, initial=InitialState(theta=orb.theta[0].copy(), kappa=orb.kappa[0].copy()),
                      n_segments=n, rtol=1e-8, atol=1e-10, frame_dt=T / 200)
    q = run.theta[:, 0]
    mid = 0.5 * (q.max() + q.min())
    i = np.nonzero((q[:-1] < mid) & (q[1:] >= mid))[0]
    t = run.t[i] + (mid - q[i]) / (q[i + 1] - q[i]) * (run.t[i + 1] - run.t[i])
    last = q[run.t > (periods - 2) * T]
    return np.diff(t[-4:]), float(np.ptp(last)), float(np.ptp(orb.theta[:, 0]))


@pytest.mark.parametrize("eta_perp", [36.0])
def test_stroke_found_where_the_onset_is_slow(eta_perp):
    g = fs.Groups(G.eta_par, eta_perp, G.chi)
    orb = periodic_orbit(g, n_segments=24)
    assert orb.stable and orb.max_multiplier < 1
    periods, swing_run, swing_orbit = _stays_on(orb)
    assert periods == pytest.approx(orb.period_dimensionless, rel=1e-5)
    assert swing_run == pytest.approx(swing_orbit, rel=2e-3)


@pytest.mark.slow
def test_stable_stroke_found_just_above_an_unstable_hopf_branch():
    """eta_perp = 30: near the Hopf point, whose branch is unstable there (a real multiplier
    above 1); the stroke a run settles into is found from a simulation instead."""
    g = fs.Groups(G.eta_par, 30.0, G.chi)
    orb = periodic_orbit(g, n_segments=24)
    assert orb.stable
    periods, swing_run, swing_orbit = _stays_on(orb)
    assert periods == pytest.approx(orb.period_dimensionless, rel=1e-5)
    assert swing_run == pytest.approx(swing_orbit, rel=2e-3)


def test_steps_per_period_are_doubled_until_they_do_not_matter():
    """The default orbit against one with 256 steps per period (an independent, finer
    discretisation): within the tolerance, and within its own stated step error."""
    n = 24
    g0 = fs.Groups(71.5 / 2.5, 71.5, 70.7)
    chi_c = hopf_point(g0, "chi", n_segments=n).value
    g = fs.Groups(g0.eta_par, g0.eta_perp, 3 * chi_c)
    orb = periodic_orbit(g, n_segments=n)
    fine = periodic_orbit(g, orb.compact(), steps=256)
    e_T = abs(orb.period / fine.period - 1)
    e_a = abs(orb.advance / fine.advance - 1)
    assert e_T < STEP_TOLERANCE[0] and e_a < STEP_TOLERANCE[1]
    assert orb.steps > 32 and math.isfinite(orb.step_error)
    assert max(e_T, e_a) < 2 * orb.step_error
    # with 32 steps (what it was) the advance misses the tolerance: the check is needed here
    coarse = periodic_orbit(g, orb.compact(), steps=32)
    assert abs(coarse.advance / fine.advance - 1) > STEP_TOLERANCE[1]


def test_a_run_still_on_its_way_to_the_stroke_is_capped_not_irregular():
    """eta_perp = 30, capped at 60 tau: the end angle's maxima still rise one way (the stroke is
    reached at 110 tau): capped, with the reason; 300 tau reaches the stroke. A motion whose
    maxima wander (chi = 220) is not periodic."""
    g = fs.Groups(G.eta_par, 30.0, G.chi)
    s = settle(g, n_segments=24, t_max=60.0)
    assert s.outcome == "capped" and "longer t_max" in s.reason, s.reason
    s = settle(g, n_segments=24, t_max=300.0)
    assert s.outcome == "limit_cycle", s.reason
    s = settle(fs.Groups(G.eta_par, G.eta_perp, 220.0), n_segments=24, t_max=100.0)
    assert s.outcome == "not_periodic" and "maxima" in s.reason, s.reason


@pytest.mark.parametrize("ratio", [1.0, 1.3])
def test_the_orbit_from_scratch_is_the_stroke_simulate_reaches(ratio):
    """At N = 12 two stable strokes coexist: the onset from a 1 degree tilt reaches one whose
    end is turned back (period 4-10 % shorter, trailing excursion a third), the onset from
    simulate's 0.01 degree the other. periodic_orbit seeded from 1 degree and settle, the sweeps
    and simulate from 0.01, so two APIs gave two strokes at one point without a word (a
    review). Both now start from the 0.01 degree tilt: the same orbit."""
    g = G.replace(chi=ratio * G.chi)
    orb = periodic_orbit(g, n_segments=12)
    st = settle(g, n_segments=12)
    assert st.reached and st.orbit.stable and orb.stable
    assert orb.period == pytest.approx(st.orbit.period, rel=1e-6)
    assert orb.lateral_trailing == pytest.approx(st.orbit.lateral_trailing, rel=1e-4)
