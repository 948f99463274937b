"""The discrete model's linear stability, Hopf point and normal form against the continuum
theory and against the branch of periodic orbits."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.orbits import continue_orbits, hopf_point, leading_pair, normal_form, periodic_orbit
from flutterswim.orbits.parameter import Axis
from flutterswim.orbits.periodic import solve_orbit, orbit_from_flow
from flutterswim.orbits.system import ShapeSystem
from flutterswim.stability import critical_chi, leading_eigenvalue


def _slope(ns, errs):
    return np.polyfit(np.log(ns), np.log(errs), 1)[0]


def test_discrete_threshold_converges_at_second_order_to_the_characteristic_equation():
    g = fs.PAPER.groups
    chi_c, _ = critical_chi(g.eta_perp)
    ns = np.array([24, 48, 96])
    errs = [abs(hopf_point(g, "chi", n_segments=n).value - chi_c) for n in ns]
    assert -2.3 < _slope(ns, errs) < -1.8
    assert errs[-1] < 1e-3 * chi_c


def test_discrete_leading_eigenvalue_converges_to_the_continuum_root():
    g = fs.PAPER.groups
    ref = leading_eigenvalue(g.chi, g.eta_perp).omega
    ns = np.array([24, 48, 96])
    errs = [abs(leading_pair(g, n) - ref) for n in ns]
    assert -2.4 < _slope(ns, errs) < -1.8
    # and at fine resolution, where the spectrum's largest |lambda| (~ N^4) is 1e9: the flutter
    # pair is still found, and closer to the continuum root than at N = 128
    fine = [abs(leading_pair(g, n) - ref) for n in (128, 256)]
    assert fine[1] < 0.5 * fine[0]


def test_straight_state_has_the_bent_equilibrium_zero_mode():
    from flutterswim.orbits import discrete_spectrum

    lam = discrete_spectrum(fs.PAPER.groups, 16)
    assert np.min(np.abs(lam)) < 1e-9 * np.max(np.abs(lam))


@pytest.fixture(scope="module")
def near_onset():
    """Orbits a small distance above the Hopf point, N = 16."""
    g = fs.PAPER.groups
    hp = hopf_point(g, "chi", n_segments=16)
    nf = normal_form(hp)
    axis = Axis(g, "chi")
    out = []
    guess = None
    for rel in (0.0025, 0.005, 0.01, 0.02):
        d = rel * hp.value
        sysm = ShapeSystem.of(axis.at(hp.value + d), 16)
        if guess is None:
            u0 = sysm.straight() + np.sqrt(nf.amplitude2_slope * d) * hp.q.real
            T0 = 2 * np.pi / hp.omega
        else:
            u0, T0 = guess.u0, guess.period_dimensionless
        u, T, fl, res, it = solve_orbit(sysm, u0, T0, steps=32, max_newton=20)
        guess = orbit_from_flow(axis.at(hp.value + d), sysm, fl, res, it, 32)
        out.append((d, guess))
    return hp, nf, out


def test_lyapunov_coefficient_sign_and_amplitude_law(near_onset):
    hp, nf, orbits = near_onset
    d = np.array([o[0] for o in orbits])
    a2 = np.array([o[1].amplitude ** 2 for o in orbits])
    # supercritical (l1 < 0): the branch lies on the unstable side (above) and is stable
    assert nf.lyapunov_coefficient < 0 and nf.direction == 1
    assert all(o[1].stable for o in orbits)
    # amplitude^2 = s d + c d^2 near the Hopf point: s from the branch against the normal form
    s, c = np.linalg.lstsq(np.stack((d, d * d), 1), a2, rcond=None)[0]
    assert s == pytest.approx(nf.amplitude2_slope_rms, rel=0.05)
    # the period tends to the Hopf period
    T = np.array([o[1].period for o in orbits])
    T0 = np.polyfit(d, T, 2)[-1]
    assert T0 == pytest.approx(2 * np.pi / hp.omega, rel=1e-3)


def test_branch_starts_at_the_hopf_point(near_onset):
    """Extrapolating amplitude^2 of the orbits to zero recovers the discrete linear threshold
    (to the truncation of a quadratic fit through orbits 0.25-1% above it)."""
    hp, nf, orbits = near_onset
    d = np.array([o[0] for o in orbits[:3]])
    a2 = np.array([o[1].amplitude ** 2 for o in orbits[:3]])
    roots = np.roots(np.polyfit(d, a2, 2))
    d0 = roots[np.argmin(np.abs(roots))].real
    assert abs(d0) < 2e-5 * hp.value


def test_hopf_point_is_that_of_the_simulators_own_linearisation():
    """The threshold from the exact Jacobian equals the one from central differences of the
    simulator's rhs at the straight state, to 1e-6."""
    from scipy.optimize import brentq

    from flutterswim.filament import Filament

    g, n = fs.PAPER.groups, 16
    hp = hopf_point(g, "chi", n_segments=n)

    def growth(chi):
        fil = Filament(n, g.eta_par, g.eta_perp, chi)
        y0 = np.zeros(fil.size)
        jac = np.empty((fil.size, fil.size))
        for i in range(fil.size):
            e = np.zeros(fil.size)
            e[i] = 1e-6
            jac[:, i] = (fil.rhs(y0 + e, 0.0, 1.0) - fil.rhs(y0 - e, 0.0, 1.0)) / 2e-6
        lam = np.linalg.eigvals(jac[2:, 2:])
        return lam[lam.imag > 1e-6].real.max()

    chi_fd = brentq(growth, 0.9 * hp.value, 1.1 * hp.value, xtol=1e-12)
    assert abs(chi_fd - hp.value) < 1e-6 * hp.value


def _state_scale(o):
    """max|u| of an orbit's states (theta, kappa l; r0/l is O(1)), an upper bound over the orbit."""
    return max(float(np.max(np.abs(o.theta))), float(np.max(np.abs(o.kappa))), float(np.max(np.abs(o.r0))))


def test_continuation_branch_dataset():
    br = continue_orbits(fs.PAPER, "kappa_E_ratio", 1.2, n_points=8, n_segments=12, steps=16)
    ds = br.to_dataset()
    assert "kappa_E_ratio" in ds.coords and ds.kappa_E_ratio.attrs["units"] == "1"
    assert ds.kappa_E_ratio.values[-1] == pytest.approx(1.2)
    assert np.all(np.diff(ds.kappa_E_ratio.values) > 0)
    assert len(ds.kappa_E_ratio) >= 8
    assert any("hopf" in k for k in ds.attrs) and any("lyapunov" in k for k in ds.attrs)
    for v in ds.data_vars.values():
        assert "units" in v.attrs and "long_name" in v.attrs
    assert ds.period.attrs["units"] == "s" and ds.advance.attrs["units"] == "m"
    # the first orbit of the branch lies just above the threshold, at small amplitude
    assert ds.kappa_E_ratio.values[0] > ds.attrs["hopf_kappa_E_ratio"]
    assert ds.advance.values[0] < 0.2 * ds.advance.values.max()
    # every orbit on the branch is a converged, accurate orbit
    # (16 steps per period here: the trivial multiplier is 1 to the time-discretisation error)
    # (closing residual to 1e-10 relative to the state's scale 1 + max|u|: continue_orbits' tol)
    assert all(o.residual < 1e-10 * (1 + _state_scale(o)) for o in br.orbits)
    assert np.all(ds.trivial_multiplier_error.values < 1e-5)


def test_continuation_is_direction_independent():
    """Continuing in chi from the Hopf point and solving directly at the end agree."""
    g = fs.PAPER.groups
    br = continue_orbits(g, "chi", 60.0, n_points=5, n_segments=16, steps=16)
    direct = periodic_orbit(g.replace(chi=60.0), n_segments=16, steps=16)
    assert br.values[-1] == 60.0
    assert br.orbits[-1].period == pytest.approx(direct.period, rel=1e-9)
    assert br.orbits[-1].advance == pytest.approx(direct.advance, rel=1e-8)


def test_bad_parameter_is_named():
    with pytest.raises(fs.ParameterError, match="parameter='zeta'"):
        continue_orbits(fs.PAPER, "zeta", 2.0)
    with pytest.raises(fs.ParameterError, match="above the Hopf point"):
        continue_orbits(fs.PAPER, "kappa_E_ratio", 0.5, n_segments=12)


def test_multiplier_crossings_along_the_paper_branch_are_reported():
    """Along kappa_E/kappa_E,fit in [Hopf, 2] every orbit is stable and no non-trivial
    multiplier crosses the unit circle; the dataset says so (N = 16, coarse but complete)."""
    br = continue_orbits(fs.PAPER, "kappa_E_ratio", 2.0, n_points=25, n_segments=16, steps=16)
    ds = br.to_dataset()
    assert ds.kappa_E_ratio.values[-1] == pytest.approx(2.0)
    crossings = br.multiplier_crossings()
    assert (ds.attrs["multiplier_crossings"] == "none") == (not crossings)
    assert bool(ds.stable.all()) == (not crossings)
    assert np.all(ds.max_multiplier.values < 1.0) == bool(ds.stable.all())


def test_physical_parameters_of_any_scale_and_similarity():
    """B (~1e-14 N m^2) and mu enter only through eta = mu l^4 / (B tau): their Hopf points
    satisfy mu_c / mu_0 = B_0 / B_c, and a branch in B reaches its end."""
    p = fs.PAPER
    b_c = hopf_point(p, "B", n_segments=16).value
    mu_c = hopf_point(p, "mu", n_segments=16).value
    assert mu_c / p.mu == pytest.approx(p.B / b_c, rel=1e-9)
    br = continue_orbits(p, "B", 1.0e-14, n_points=5, n_segments=16, steps=16)
    assert br.values[-1] == pytest.approx(1.0e-14) and br.values[0] < b_c
    assert all(o.stable for o in br.orbits)


def test_periodic_orbit_near_onset_without_a_guess():
    """0.5 % above the Hopf point (growth rate / frequency ~ 1e-3) the onset would take
    hundreds of tau to simulate; the orbit comes from the Hopf eigenvector instead, with the
    normal form's amplitude."""
    hp = hopf_point(fs.PAPER.groups, "chi", n_segments=16)
    nf = normal_form(hp)
    d = 0.005 * hp.value
    orb = periodic_orbit(fs.PAPER.groups.replace(chi=hp.value + d), n_segments=16, steps=16)
    assert orb.stable and orb.residual < 1e-10
    assert orb.amplitude ** 2 == pytest.approx(nf.amplitude2_slope_rms * d, rel=0.05)


def test_continuation_starts_at_a_nearly_degenerate_hopf_point():
    """At twice the paper's viscosity the first Lyapunov coefficient is ~500x smaller than at
    the paper's (a degenerate Hopf point is near): the square-root seed is far too large there.
    The branch still starts at the Hopf point (fixed-amplitude start), its orbits close to 1e-10
    (relative to the state's scale) with the trivial multiplier 1 to 1e-8, and their amplitude grows from zero."""
    p = fs.PAPER.replace(mu=2 * fs.PAPER.mu)
    nf = normal_form(hopf_point(p, "kappa_E_ratio", n_segments=24))
    nf0 = normal_form(hopf_point(fs.PAPER, "kappa_E_ratio", n_segments=24))
    assert abs(nf.lyapunov_coefficient) < 0.05 * abs(nf0.lyapunov_coefficient)
    br = continue_orbits(p, "kappa_E_ratio", 1.0, n_points=6, n_segments=24, max_points=12)
    assert len(br.orbits) >= 6
    assert abs(br.values[0] / br.hopf_value - 1) < 1e-3
    assert all(o.residual < 1e-10 * (1 + _state_scale(o)) and o.trivial_multiplier_error < 1e-8
               for o in br.orbits)
    amp = [o.amplitude for o in br.orbits]
    assert np.all(np.diff(amp) > 0) and amp[0] < 0.5 * amp[-1]
