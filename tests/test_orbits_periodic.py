"""Periodic orbits by Newton shooting: against long simulations, Floquet accuracy, order."""

import math

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.initial import InitialState
from flutterswim.orbits import periodic_orbit
from flutterswim.orbits.periodic import seed_from_simulation, solve_orbit
from flutterswim.orbits.system import ShapeSystem
from flutterswim.simulate import simulate

N = 24


@pytest.fixture(scope="module")
def paper_orbit():
    return periodic_orbit(fs.PAPER.groups, n_segments=N, steps=48)


def _returns(run, u0, normal, n):
    """Times, r(0) and states where the simulated shape crosses the Poincare plane
    normal.(u - u0) = 0 upwards, refined by a cubic through the frames around each crossing."""
    from scipy.interpolate import CubicSpline

    u = np.concatenate((run.theta, run.kappa), axis=1)
    g = (u - u0) @ normal
    out = []
    for i in np.nonzero((g[:-1] < 0) & (g[1:] >= 0))[0]:
        if i < 2 or i + 3 > g.size:
            continue
        sl = slice(i - 2, i + 3)
        cs = CubicSpline(run.t[sl], g[sl])
        roots = [r for r in cs.roots(extrapolate=False) if run.t[i] <= r <= run.t[i + 1]]
        tc = roots[0]
        r0 = np.array([CubicSpline(run.t[sl], run.r0[sl, k])(tc) for k in range(2)])
        out.append((tc, r0))
    return out


@pytest.mark.parametrize("where", [
    {},  # the paper point
    {"chi": 60.0},
    {"eta_perp": 100.0, "chi": 90.0},
])
def test_orbit_matches_a_long_accurate_simulation(where):
    g = fs.PAPER.groups.replace(**where) if where else fs.PAPER.groups
    orb = periodic_orbit(g, n_segments=N, steps=48)
    assert orb.residual < 1e-10 and orb.n_newton <= 8
    u0 = orb.u0
    sysm = ShapeSystem.of(g, N)
    normal = sysm.f(u0)
    normal /= np.linalg.norm(normal)
    T = orb.period
    run = simulate(g, 4.2 * T, initial=InitialState.from_state(np.r_[0.0, 0.0, u0], N), n_segments=N,
                   n_frames=int(4.2 * 400) + 1, rtol=1e-11, atol=1e-13)
    ret = _returns(run, u0, normal, N)
    assert len(ret) >= 4
    periods = np.diff([r[0] for r in ret])
    adv = np.array([np.hypot(*(ret[k + 1][1] - ret[k][1])) for k in range(len(ret) - 1)])
    assert np.max(np.abs(periods - T)) < 1e-6 * T
    assert np.max(np.abs(adv - orb.advance)) < 1e-5 * orb.advance


def test_floquet_multipliers_trivial_one_and_stable(paper_orbit):
    assert paper_orbit.trivial_multiplier_error < 1e-8
    assert paper_orbit.stable
    # the monodromy maps the flow direction to itself: the trivial eigenvector is f(u0)
    assert paper_orbit.max_multiplier < 1.0


def test_newton_from_a_simulated_guess_converges_fast():
    sysm = ShapeSystem.of(fs.PAPER.groups, N)
    u0, T0, _ = seed_from_simulation(sysm)
    residuals = []
    u, T, fl, res, it = solve_orbit(sysm, u0, T0, steps=32, tol=1e-10)
    assert res < 1e-10 and it <= 8
    # quadratic convergence: record residuals of successive Newton steps by capping iterations
    for k in (1, 2, 3):
        try:
            solve_orbit(sysm, u0, T0, steps=32, tol=1e-30, max_newton=k)
        except Exception as exc:  # OrbitNotFound carries the residual in its message
            residuals.append(float(str(exc).split("residual ")[1].split(",")[0]))
    assert residuals[1] < 1e-2 * residuals[0] and residuals[2] < 1e-3 * residuals[1] or residuals[2] < 1e-11


def test_time_discretisation_converges_at_fifth_order():
    """Radau IIA is order 5: the period's error falls 32x per halving of the step."""
    g = fs.PAPER.groups
    base = periodic_orbit(g, n_segments=12, steps=12)
    periods = [base.period]
    orb = base
    for steps in (24, 48, 96):
        orb = periodic_orbit(g, orb, n_segments=12, steps=steps)
        periods.append(orb.period)
    e = np.abs(np.diff(periods))
    slopes = np.log2(e[:-1] / e[1:])
    assert np.all(slopes > 4.0), slopes


def test_descriptors_and_symmetry(paper_orbit):
    """Swims along +e1 (towards the field), with the s=l end leading as in the simulator, and the
    stroke is mirror-symmetric: half a period later the shape is its own mirror image."""
    orb = paper_orbit
    assert abs(orb.swim_direction) < 1e-6
    assert orb.advance > 0 and orb.speed == pytest.approx(orb.advance / orb.period, rel=1e-12)
    assert orb.lateral_leading > 0 and orb.lateral_trailing > 0
    m = orb.phase.size
    assert m % 2 == 0
    half = m // 2
    mirror = np.max(np.abs(orb.theta[half:] + orb.theta[:half]))
    assert mirror < 1e-6 * np.abs(orb.theta).max()
    assert abs(orb.nonreciprocity) > 0.1  # a travelling wave, not a reciprocal stroke


def test_to_result_is_described_like_a_simulation(paper_orbit):
    from flutterswim.analysis import describe

    from flutterswim.analysis.track import Track

    res = paper_orbit.to_result(n_cycles=6)
    # the orbit of the groups is dimensionless (l, tau): describe, in mm and s, refuses it
    # rather than label body lengths as metres
    with pytest.raises(fs.ParameterError, match="dimensionless"):
        describe(res, n_last=4)
    l, tau = fs.PAPER.l, fs.PAPER.tau
    tr = Track(t=res.t * tau, x=res.x * l, y=res.y * l, length=l, units="m")
    d = describe(tr, n_last=4)
    assert d.period_s == pytest.approx(paper_orbit.period * tau, rel=1e-6)
    assert d.advance_per_cycle_mm == pytest.approx(paper_orbit.advance * l * 1e3, rel=1e-6)


def test_below_threshold_there_is_no_orbit():
    from flutterswim.orbits import OrbitNotFound

    with pytest.raises(OrbitNotFound, match="stable"):
        periodic_orbit(fs.PAPER.groups.replace(chi=30.0), n_segments=12)


def test_bad_inputs_name_the_parameter():
    with pytest.raises(fs.ParameterError, match="n_segments"):
        periodic_orbit(fs.PAPER, n_segments=2)
    with pytest.raises(fs.ParameterError, match="params"):
        periodic_orbit("paper")
    with pytest.raises(fs.ParameterError, match="guess"):
        periodic_orbit(fs.PAPER, guess=3.0, n_segments=12)
    assert math.isfinite(1.0)


def test_describe_reads_both_ends_within_0p2_percent_at_25_frames_per_cycle(paper_orbit):
    """describe's peak interpolation on frames sampled at 25 per cycle (about 25 per tau)
    against the orbit's spectrally interpolated lateral excursions of both ends."""
    from flutterswim.analysis import describe

    from flutterswim.analysis.track import Track

    res = paper_orbit.to_result(n_cycles=8, frames_per_cycle=25)
    l, tau = fs.PAPER.l, fs.PAPER.tau  # the orbit of the groups is in l and tau
    d = describe(Track(t=res.t * tau, x=res.x * l, y=res.y * l, length=l, units="m"), n_last=6)
    assert d.leading_lateral_p2p_mm == pytest.approx(paper_orbit.lateral_leading * l * 1e3, rel=2e-3)
    assert d.trailing_lateral_p2p_mm == pytest.approx(paper_orbit.lateral_trailing * l * 1e3, rel=2e-3)
    assert d.period_s == pytest.approx(paper_orbit.period * tau, rel=1e-6)


def test_resampling_is_spectrally_exact_for_the_stroke(paper_orbit):
    """Frames resampled at 24 per cycle and back at 48 agree with the solver's own states."""
    from flutterswim.orbits.periodic import _resample

    th = paper_orbit.theta
    back = _resample(_resample(th, 24), th.shape[0])
    assert np.max(np.abs(back - th)) < 1e-4 * np.abs(th).max()


def test_irregular_onset_is_told_from_strokes_that_settle_slowly():
    """The seed's test of the end angle's maxima: irregular motion (a chaotic map's maxima)
    is named; a stroke still growing or decaying towards its amplitude, or one with two or three
    maxima per period, is not."""
    from flutterswim.orbits.periodic import _irregular_peaks

    t = np.linspace(0.0, 40.0, 8001)
    growing = (1.0 - 0.5 * np.exp(-t / 30.0)) * np.sin(2 * np.pi * t)
    decaying = (1.0 + 0.3 * np.exp(-t / 20.0) * np.cos(0.7 * t)) * np.sin(2 * np.pi * t)
    doubled = np.sin(2 * np.pi * t) + 0.4 * np.sin(np.pi * t)  # maxima alternate: period 2
    tripled = np.sin(2 * np.pi * t) + 0.4 * np.sin(2 * np.pi * t / 3)
    x, amp = 0.3, []
    for _ in range(41):  # the logistic map at r = 3.9: chaotic amplitudes, one per cycle
        x = 3.9 * x * (1 - x)
        amp.append(x)
    chaotic = np.repeat(amp, 200)[: t.size] * np.sin(2 * np.pi * t)
    for q in (growing, decaying, doubled, tripled):
        assert _irregular_peaks(q) is None
    assert "maxima" in _irregular_peaks(chaotic)


def test_strongly_bent_stroke_closes_at_the_round_off_floor():
    """chi = 150 at N = 12: the stroke's curvatures reach ~100 and Newton's residual stalls
    near 4e-9, above the absolute 1e-10; the orbit is accepted at 1e-10 of the state's scale
    and closes under an independent simulation (it raised 'did not converge' before)."""
    g = fs.PAPER.groups.replace(chi=150.0)
    orb = periodic_orbit(g, n_segments=12)
    u0 = orb.u0
    scale = 1 + np.max(np.abs(u0))
    assert orb.residual < 1e-10 * scale
    run = simulate(g, orb.period, initial=InitialState.from_state(np.r_[0.0, 0.0, u0], 12), n_segments=12,
                   n_frames=2, rtol=1e-11, atol=1e-13)
    end = np.concatenate((run.theta[-1], run.kappa[-1]))
    assert np.max(np.abs(end - u0)) < 1e-6 * scale


@pytest.mark.slow
def test_irregular_onset_raises_a_clear_error():
    """chi = 220 at N = 12: the simulated onset never settles (the end angle's maxima wander
    over most of its swing); periodic_orbit says so instead of failing inside Radau steps."""
    from flutterswim.orbits.periodic import OrbitNotFound

    with pytest.raises(OrbitNotFound, match="irregular"):
        periodic_orbit(fs.PAPER.groups.replace(chi=220.0), n_segments=12)
