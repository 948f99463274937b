"""Stop 47: items left at stop 46."""

import pytest

import flutterswim as fs
from flutterswim.orbits.linear import hopf_point


@pytest.mark.parametrize("factor", [60.0, 1 / 60.0])
def test_the_hopf_search_finds_the_point_from_far_away(factor):
    """From a sweep point far past onset (kappa_E 60 times the paper's, chi = 4242) the search
    said there was no Hopf point for chi between 84.8 and 212010; the one at 48.3 lies a sixtieth
    below. The Hopf point does not depend on where the search starts."""
    near = hopf_point(fs.PAPER, "chi", n_segments=12).value
    far = hopf_point(fs.PAPER.replace(kappa_E=factor * fs.PAPER.kappa_E), "chi", n_segments=12).value
    assert far == pytest.approx(near, rel=1e-9)
