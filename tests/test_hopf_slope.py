"""The Hopf point's growth slope d Re(lambda) / d parameter, which sets the normal form's
amplitude-squared slope and the branch's first step.

It was a central difference of the eigenvalue over a step of 1e-6 of the value, where the
eigensolver's round-off (7e-8 at N = 96) made it 4-6 % off, and different for every start of
the search; it is now the first-order perturbation conj(p) . (dA / dv) q.
"""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.orbits import hopf_point, leading_pair


@pytest.mark.parametrize("start", [43.0, 50.0])
def test_growth_slope_agrees_with_a_smooth_fit_of_the_growth_rate(start):
    n = 96
    g0 = fs.Groups(70, 120, start)
    hp = hopf_point(g0, "chi", n_segments=n)
    v = hp.value
    # independent: a cubic through the growth rate over +-0.05 (its round-off averages out
    # there; the cubic's truncation is below 1e-6 relative)
    x = np.linspace(-0.05, 0.05, 11)
    y = np.array([leading_pair(g0.replace(chi=v + d), n).real for d in x])
    fit = np.polyfit(x, y, 3)
    assert abs(np.polyval(fit, 0.0)) < 1e-6  # the Hopf point: Re lambda = 0
    assert hp.growth_slope == pytest.approx(fit[-2], rel=3e-4)


def test_growth_slope_does_not_depend_on_where_the_search_starts():
    slopes = [hopf_point(fs.Groups(70, 120, s), "chi", n_segments=96).growth_slope for s in (43.0, 45.0, 50.0)]
    assert max(slopes) - min(slopes) < 1e-6 * abs(slopes[0])
