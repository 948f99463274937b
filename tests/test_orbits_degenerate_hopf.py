"""Just past a nearly degenerate Hopf point (eta_perp = 4 eta_par: l1 = +1.9e-5, the branch
runs the other way to a fold at 0.988 of the onset's chi and back) the stroke from scratch is
the stroke at the point asked for. The continuation from the Hopf point used to run out of
orbits on its way back; settle took its last orbit (at another chi: period +1.2 %, advance
-10.9 %) and periodic_orbit started Newton from it and failed."""

import pytest

import flutterswim as fs
from flutterswim.orbits.periodic import periodic_orbit

EP = 41.49104790788428


def _groups(chi):
    return fs.Groups(EP, 4 * EP, chi)


@pytest.fixture(scope="module")
def hopf_chi():
    from flutterswim.orbits.linear import hopf_point

    return hopf_point(_groups(42.0), "chi", n_segments=24).value


def test_the_stroke_just_past_onset_is_the_one_at_that_point(hopf_chi):
    far = periodic_orbit(_groups(1.01 * hopf_chi), n_segments=24)  # an ordinary onset
    for ratio in (1.0004, 1.001):
        chi = ratio * hopf_chi
        # the reference: Newton from the neighbouring stroke, no continuation from the Hopf point
        ref = periodic_orbit(_groups(chi), guess=far)
        got = periodic_orbit(_groups(chi), n_segments=24)
        assert ref.stable and got.stable
        assert got.period == pytest.approx(ref.period, rel=1e-7)
        assert got.advance == pytest.approx(ref.advance, rel=1e-6)
    # settle (sweeps, run_to_limit_cycle): the onset is too slow to simulate, the orbit comes
    # from the continuation, and is the one at this chi
    run = fs.run_to_limit_cycle(_groups(chi), n_segments=24)
    orb = run.settings["orbit"]
    assert orb["period"] == pytest.approx(ref.period, rel=1e-6)
    assert orb["advance"] == pytest.approx(ref.advance, rel=1e-5)


def test_the_branch_back_into_the_range_keeps_its_orbits(hopf_chi):
    """The steps grow on the way out to the fold and shrink again on the way back: the range
    from the Hopf point to the target holds about n_points orbits (2 of 6 when the steps only
    grew)."""
    from flutterswim.orbits.continuation import continue_orbits

    chi = 1.001 * hopf_chi
    br = continue_orbits(_groups(chi), "chi", chi, n_points=6, n_segments=24, look_beyond=0.0)
    assert br.ends_at(chi)
    v = br.values
    assert v.min() < 0.99 * hopf_chi  # (out to the fold and back)
    assert int(((v >= hopf_chi) & (v <= chi)).sum()) >= 4
