"""settle's linear rate (leading_mode) at many segments: the zero mode is left out by its
round-off bound, not by a cut relative to the largest |lambda| (which grows like N^4 / eta_perp
and dropped the flutter pair itself)."""

import math
import warnings

import pytest

from flutterswim.orbits.linear import leading_mode, leading_pair
from flutterswim.params import Groups


def test_the_flutter_pair_is_kept_where_the_spectrum_is_wide():
    """eta_perp = 8 at N = 256: leading_mode had returned -63.3 (a real bending mode). It must
    agree with leading_pair within round-off (||A|| is 1e10 here) and with the converged value
    at N = 96."""
    g = Groups(eta_par=41.49, eta_perp=8.0, chi=70.67)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lp = leading_pair(g, 256)
    lm = leading_mode(g, 256)
    assert abs(lm - lp) < 1e-4 * abs(lp)  # (within the round-off that leading_pair would warn of)
    assert abs(lm - leading_mode(g, 96)) < 1e-3 * abs(lp)


@pytest.mark.parametrize("n", [24, 96])
def test_no_field_leaves_the_passive_relaxation(n):
    """chi = 0: the spontaneous curvature relaxes at 1/tau and the bending modes faster, so the
    straight state's leading rate is -1 exactly (real). At eta_perp = 0.5, N = 96 the relative
    cut had dropped it and returned -1000."""
    lm = leading_mode(Groups(eta_par=41.49, eta_perp=0.5, chi=0.0), n)
    assert math.isclose(lm.real, -1.0, rel_tol=1e-6) and lm.imag == 0.0


def test_the_zero_mode_moved_by_round_off_is_still_left_out():
    """eta_perp = 0.1, chi = 100, N = 256: round-off moved the bent-equilibrium zero mode to
    +2.81 (its bound 0.28), and a cut at 10 times the bound kept it as an unstable mode, where
    the continuum's leading pair is -0.991 + 11.13i: stable. Whatever round-off leaves, the
    straight state must not read unstable, and the result must warn."""
    from flutterswim.orbits.linear import RoundoffWarning

    with pytest.warns(RoundoffWarning):
        lm = leading_mode(Groups(eta_par=0.1 / 1.5, eta_perp=0.1, chi=100.0), 256)
    assert lm.real < 0


@pytest.mark.parametrize("eta_perp, chi, n, want", [(0.3, 100.0, 384, -0.973 + 11.13j),
                                                    (0.3, 1000.0, 512, 1.655 + 111.1j)])
def test_the_zero_mode_is_deflated_not_searched_for(eta_perp, chi, n, want):
    """Round-off split the zero mode into 2.2 +- 3.4i (N = 384), or moved it to +33.7 while a -1
    mode lay closer to the null vector (N = 512): removing one computed eigenvalue kept it, a
    false unstable verdict. Deflated, the leader is the continuum's (its reference to 0.2 %)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lm = leading_mode(Groups(eta_par=41.49, eta_perp=eta_perp, chi=chi), n)
    assert abs(lm - want) < 2e-3 * abs(want)


@pytest.mark.parametrize("chi", [1.0, -1.0])
def test_far_below_threshold_the_pair_is_not_lost_to_the_deflations_round_off(chi):
    """eta_perp = 1, chi = +-1, N = 24: deflating split the relaxation's defective cluster at -1
    into a real -0.99998, taken, silently, for the pair -0.99999093 + 0.1115i that A's own
    spectrum gives (to 1e-8): the frequency read 0, and chi and -chi disagreed."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lm = leading_mode(Groups(eta_par=41.49, eta_perp=1.0, chi=chi), 24)
    assert lm.imag == pytest.approx(0.11145353, rel=1e-4) and lm.real == pytest.approx(-0.99999093, abs=1e-7)
