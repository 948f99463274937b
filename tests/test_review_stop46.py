"""Stop 46: items left at stop 45 (bad brackets, reasons in CSV files)."""

import pytest

import flutterswim as fs
from flutterswim._validate import ParameterError
from flutterswim.orbits.linear import hopf_point


@pytest.mark.parametrize("bracket", [(float("nan"), 1.0), (1.0,), "ab", (0.5, 0.5), (0.5, float("inf"))])
def test_a_bad_bracket_names_the_bracket(bracket):
    """(nan, 1) had been reported as kappa_E_ratio=nan, a value the user never gave."""
    with pytest.raises(ParameterError, match=r"^bracket="):
        hopf_point(fs.PAPER, bracket=bracket, n_segments=12)


def test_continuing_across_zero_field_names_the_mirror_branch():
    """From chi = -70.67 towards +100 the branch from -48 cannot get there; the error named only
    that Hopf point, although the mirror branch from +48 holds chi = 100."""
    from flutterswim.orbits.continuation import continue_orbits
    from flutterswim.orbits.linear import hopf_point
    from flutterswim.params import Groups

    g = Groups(eta_par=41.49, eta_perp=71.52, chi=-70.67)
    hp = hopf_point(g, "chi", n_segments=16)
    with pytest.raises(ParameterError) as e:
        continue_orbits(g, "chi", 100.0, n_points=3, n_segments=16)
    assert f"mirror branch from {-hp.value:.6g}" in str(e.value)
    with pytest.raises(ParameterError) as e:  # on its own side: no mirror to name
        continue_orbits(g, "chi", -10.0, n_points=3, n_segments=16)
    assert "mirror" not in str(e.value)
