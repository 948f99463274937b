"""Beyond the paper's region another pair of eigenvalues can lead, and root following (the
paper's algorithm) does not see it. A review found, with no warning:
- neutral_curve([500, 700, 1000, 2000, 5000]) = [126.7, -513.8, -301.4, 84.4, 59.5], where
  critical_chi gives 53.66, 51.50, 49.36, 50.68, 59.50;
- bifurcation(chi 1..130 at eta_perp 1000) reporting the second eigenvalue at chi ~ 12;
- stability_map(eta_perp 990..1000, chi 1..30): 144 of 180 cells the second eigenvalue.
Each is checked here against the eigenvalue solved from scratch at every point."""

import warnings

import numpy as np
import pytest

from flutterswim.stability import bifurcation, critical_chi, leading_eigenvalue, neutral_curve, stability_map


@pytest.mark.parametrize("etas", [[500.0, 700.0, 1000.0, 2000.0, 5000.0], [500.0, 700.0, 1000.0, 2000.0],
                                  [40.0, 71.5, 300.0, 1200.0]])
def test_a_coarse_neutral_curve_is_the_onset_at_every_point(etas):
    nc = neutral_curve(np.array(etas))
    for e, c, b in zip(etas, nc.chi_cr, nc.beta):
        ref, ref_b = critical_chi(e)  # (a scan up in chi, bisection and Newton: no continuation)
        assert c == pytest.approx(ref, rel=1e-9) and b == pytest.approx(ref_b, rel=1e-9)
        # the leading pair crosses there: stable just below, unstable just above
        assert leading_eigenvalue(c * (1 - 1e-4), e).omega.real < 0 < leading_eigenvalue(c * (1 + 1e-4), e).omega.real


def test_the_neutral_curve_past_the_paper_range_on_a_fine_grid():
    nc = neutral_curve(eta_range=(300.0, 2000.0), step=1.0)
    assert np.all(np.isfinite(nc.chi_cr)) and np.all(nc.chi_cr > 0)
    for k in range(0, nc.eta_perp.size, 170):
        assert nc.chi_cr[k] == pytest.approx(critical_chi(nc.eta_perp[k])[0], rel=1e-9)


def test_critical_chi_beyond_chi_max_is_nan():
    """The docstring's NaN beyond chi_max (it returned 10595.8 at chi_max = 1e4)."""
    c, _ = critical_chi(1e-3)
    assert np.isnan(c)
    c2, _ = critical_chi(1e-3, chi_max=3e4)
    assert 1e4 < c2 < 3e4
    assert leading_eigenvalue(c2 * (1 - 1e-4), 1e-3).omega.real < 0 < leading_eigenvalue(c2 * (1 + 1e-4), 1e-3).omega.real


@pytest.mark.parametrize("parameter,values,fixed", [("chi", np.arange(1.0, 131.0, 1.0), 1000.0),
                                                    ("chi", np.arange(0.5, 130.01, 2.5), 71.5),
                                                    ("eta_perp", np.arange(300.0, 1400.0, 20.0), 12.0)])
def test_bifurcation_is_the_leading_eigenvalue_at_every_value(parameter, values, fixed):
    b = bifurcation(parameter=parameter, values=values, fixed=fixed)
    ref = np.array([leading_eigenvalue(v, fixed, n=48).omega if parameter == "chi"
                    else leading_eigenvalue(fixed, v, n=48).omega for v in values])
    np.testing.assert_allclose(b.omega, ref, rtol=1e-7, atol=1e-7)


def test_a_map_whose_followed_root_is_not_the_leading_one_says_so():
    with pytest.warns(RuntimeWarning, match=r"followed root is not the leading eigenvalue"):
        m = stability_map(eta_perp=np.arange(990.0, 1001.0, 2.0), chi=np.arange(1.0, 31.0, 1.0))
    assert m.check_points > 0 and m.check_max_rel_diff > 1e-3
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p = stability_map(eta_perp=np.arange(10.0, 351.0, 10.0), chi=np.arange(-130.0, 131.0, 5.0))
    assert p.check_points > 30 and p.check_max_rel_diff < 1e-8  # the paper's region: the leading root


def test_the_eigenmode_panels_do_not_overlap():
    """A review: eigenmodes.png's second panel's y label ran into the first panel."""
    from flutterswim.stability import eigenmodes
    from flutterswim.stability.plots import plot_modes

    fig = plot_modes(eigenmodes(70.7, 71.5))
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    a0, a1 = fig.axes[:2]
    label = a1.yaxis.label.get_window_extent(r)
    assert label.x0 > a0.get_tightbbox(r).x1  # the label lies right of everything of the first panel


@pytest.mark.parametrize("args,kw,match", [((1e300, 71.5), {}, r"chi=1e\+300 must be in"),
                                           ((70.0, 1e300), {}, r"eta_perp=1e\+300 must be in"),
                                           ((1e6, 71.5), {}, r"chi=1000000.0 must be in"),
                                           ((70.0, 71.5), {"n": 10**5}, r"n=100000 must be an integer in")])
def test_inputs_beyond_the_checked_range_are_refused_by_name(args, kw, match):
    """chi = 1e300 ended in an IndexError, eta_perp = 1e300 in omega = -1 without a word, n = 1e5
    in a 75 GiB allocation."""
    from flutterswim._validate import ParameterError

    with pytest.raises(ParameterError, match=match):
        leading_eigenvalue(*args, **kw)


def test_sizes_and_physical_parameters_are_named():
    import flutterswim as fs
    from flutterswim._validate import ParameterError
    from flutterswim.stability import physical_stability

    with pytest.raises(ParameterError, match=r"MAX_MAP_POINTS"):
        neutral_curve(eta_range=(0.0, 1e9))
    with pytest.raises(ParameterError, match=r"kappa_E=1000000000000.0.*chi="):
        physical_stability(fs.PAPER.replace(kappa_E=1e12))
    # the checked range itself still answers, confirmed by Newton, without a warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert leading_eigenvalue(1e4, 71.5).polished and leading_eigenvalue(70.0, 1e6).polished


def test_chi_max_just_below_the_onset_is_nan():
    """A review: chi_max between the bisection's bracket and the onset raised 'did not converge'."""
    c, _ = critical_chi(71.5)
    for f in (0.9999, 0.9995, 0.99):
        assert np.isnan(critical_chi(71.5, chi_max=c * f)[0])
    assert critical_chi(71.5, chi_max=c * 1.0001)[0] == pytest.approx(c, rel=1e-12)
