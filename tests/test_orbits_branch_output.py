"""The branch dataset's swim direction, leading end, Hopf period and amplitude; periodic_orbit's
field direction (validation, a guess from another direction)."""

import math

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.orbits import continue_orbits, periodic_orbit

OPTS = {"n_points": 4, "n_segments": 8, "steps": 16}


@pytest.fixture(scope="module")
def mirrored():
    """The branch to kappa_E_ratio 1 in the paper's field and in the reversed one (chi < 0)."""
    g = fs.PAPER.groups
    return (continue_orbits(g, "kappa_E_ratio", 1.0, **OPTS),
            continue_orbits(g.replace(chi=-g.chi), "kappa_E_ratio", 1.0, **OPTS))


def test_swim_direction_turns_by_half_a_turn_in_the_mirrored_field(mirrored):
    pos, neg = (b.to_dataset() for b in mirrored)
    for ds in (pos, neg):
        assert ds.swim_direction.attrs["units"] == "degree"
    # the same stroke (period, advance), swimming the other way
    np.testing.assert_allclose(neg.period.values[-1], pos.period.values[-1], rtol=1e-9)
    # (the advance to the time discretisation: the mirror swaps the ends, and r(0)'s quadrature
    # over 16 steps is r(l)'s to ~1e-4)
    np.testing.assert_allclose(neg.advance.values[-1], pos.advance.values[-1], rtol=1e-3)
    turn = np.remainder(neg.swim_direction.values - pos.swim_direction.values[-1], 360.0)
    np.testing.assert_allclose(turn, 180.0, atol=1e-6)
    # in (-180, 180] as the attribute says, without flipping to -180 on a round-off (it did)
    np.testing.assert_allclose(neg.swim_direction.values, 180.0, atol=1e-6)
    from flutterswim.orbits.dataset import _half_open_degrees

    d = _half_open_degrees(np.radians([-180.0, -179.9999999, 180.0, 90.0, -90.0]))
    assert np.all((d > -180.0) & (d <= 180.0)) and d[3] == pytest.approx(90.0) and d[4] == pytest.approx(-90.0)


def _end_ahead(orb, direction_deg):
    """1 if the s = l end lies farther along the swim direction than the s = 0 end (mean over
    the stroke of the centreline's ends, from theta and r(0)), else 0."""
    e = np.array([math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg))])
    n = orb.theta.shape[1]
    tip = orb.r0 + np.stack((np.cos(orb.theta).sum(1), np.sin(orb.theta).sum(1)), 1) / n
    return int(np.mean((tip - orb.r0) @ e) > 0)


def test_leading_end_is_the_end_ahead_along_the_swim_direction(mirrored):
    seen = set()
    for br in mirrored:
        ds = br.to_dataset()
        le = ds.leading_end
        assert list(le.attrs["flag_values"]) == [0, 1] and len(le.attrs["flag_meanings"].split()) == 2
        assert le.attrs["units"] == "1"
        # every 0/1 variable (int8) says what its values mean (CF flags)
        for name, v in ds.data_vars.items():
            if v.dtype == np.int8:
                assert list(v.attrs.get("flag_values", [])) == [0, 1], name
                assert len(v.attrs["flag_meanings"].split()) == 2, name
        ahead = [_end_ahead(o, d) for o, d in zip(br.orbits, ds.swim_direction.values)]
        assert list(le.values) == ahead
        seen |= set(ahead)
    assert seen == {0, 1}  # the mirrored field's stroke is led by the other end


def test_hopf_period_is_that_of_the_hopf_points_own_time_scale():
    """Along tau the time unit itself changes: 2 pi / omega_c in tau units times tau_c (it
    was scaled by the first orbit's tau)."""
    br = continue_orbits(fs.PAPER, "tau", 0.9, n_points=3, n_segments=8, steps=16)
    ds = br.to_dataset()
    assert ds.attrs["hopf_period"] == pytest.approx(2 * math.pi / ds.attrs["hopf_omega_per_tau"] * ds.attrs["hopf_tau"],
                                                    rel=1e-12)
    assert ds.attrs["hopf_period_units"] == ds.period.attrs["units"] == "s"
    # groups: tau units (CF: a pure number, its scale in scaled_units)
    g = continue_orbits(fs.PAPER.groups, "chi", 60.0, n_points=3, n_segments=8, steps=16).to_dataset()
    assert g.attrs["hopf_period_units"] == g.period.attrs["units"] == "1"
    assert g.attrs["hopf_period_scaled_units"] == g.period.attrs["scaled_units"] == "tau"
    assert g.attrs["hopf_period"] == pytest.approx(2 * math.pi / g.attrs["hopf_omega_per_tau"], rel=1e-12)


def test_amplitude_does_not_grow_with_the_resolution():
    """amplitude: the RMS over the shape components of the first harmonic (it was the sum,
    growing like sqrt(N): 1.4 times larger at N = 24 than at N = 12)."""
    a12, a24 = (continue_orbits(fs.PAPER.groups, "kappa_E_ratio", 1.5, n_points=4, n_segments=n, steps=16)
                .orbits[-1].amplitude for n in (12, 24))
    assert a24 == pytest.approx(a12, rel=0.04)


@pytest.mark.parametrize("phi", [float("nan"), float("inf"), "a", None])
def test_field_direction_must_be_a_finite_number(phi):
    with pytest.raises(fs.ParameterError, match=r"^phi=.*finite") as exc:
        periodic_orbit(fs.PAPER.groups, n_segments=8, phi=phi)
    assert "\n" not in str(exc.value)


def test_a_guess_from_another_field_direction_is_turned_to_this_one():
    """The model is invariant under turning the filament with the field, so the orbit at phi
    from a guess at phi = 0 is the phi = 0 orbit turned by phi: the same period, advance and
    leading end, the swim direction turned by phi (it failed in the stage equations)."""
    g = fs.PAPER.groups
    o0 = periodic_orbit(g, n_segments=12, steps=16)
    for phi in (math.pi / 2, math.pi):
        turned = periodic_orbit(g, guess=o0, phi=phi)
        scratch = periodic_orbit(g, n_segments=12, steps=16, phi=phi)
        assert turned.phi == phi
        assert turned.period == pytest.approx(scratch.period, rel=1e-9)
        assert turned.period == pytest.approx(o0.period, rel=1e-9)
        assert turned.advance == pytest.approx(o0.advance, rel=1e-8)
        assert turned.leading_end == o0.leading_end
        assert math.remainder(turned.swim_direction - o0.swim_direction - phi, 2 * math.pi) == pytest.approx(0, abs=1e-7)
    # and back: a guess at pi/2 for phi = 0
    back = periodic_orbit(g, guess=periodic_orbit(g, guess=o0, phi=math.pi / 2), phi=0.0)
    assert back.period == pytest.approx(o0.period, rel=1e-9)


def test_orbits_limited_by_the_time_discretisation_are_called_out():
    """Where the trivial multiplier is off 1 by more than the gauge (few steps per period, a
    strongly bent stroke) the branch warns and counts those orbits; where it is not, it is silent."""
    import warnings

    gauge = 1e-6  # continuation.ACCURACY_GAUGE
    for steps in (8, 32):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            br = continue_orbits(fs.PAPER.groups, "kappa_E_ratio", 1.3, n_points=3, n_segments=8, steps=steps)
        err = np.array([o.trivial_multiplier_error for o in br.orbits])
        ours = [w for w in caught if "trivial Floquet multiplier" in str(w.message)]
        assert len(ours) == int(np.any(err > gauge))
        assert br.to_dataset().attrs["n_inaccurate_orbits"] == np.count_nonzero(err > gauge)
        if ours:
            assert ours[0].filename == __file__  # points at the caller
            assert f"{np.count_nonzero(err > gauge)} of {err.size} orbits" in str(ours[0].message)
        assert steps == 32 or ours  # 8 steps per period do not resolve this stroke to the gauge


def test_to_result_of_a_turned_orbit_carries_its_field_direction():
    """to_result() built the field at 0 whatever the orbit's phi: describe then read a stroke
    turned by phi as swimming across its field. Rotation invariance: the turned orbit's run
    describes as the original's, with the field and the swim direction turned together."""
    from flutterswim.analysis import describe

    o0 = periodic_orbit(fs.PAPER, n_segments=12, steps=16)
    phi = 2.0
    turned = periodic_orbit(fs.PAPER, guess=o0, phi=phi)
    r0, r1 = o0.to_result(n_cycles=4), turned.to_result(n_cycles=4)
    assert np.all(r1.field_angle == pytest.approx(phi)) and np.all(r0.field_angle == 0.0)
    d0, d1 = describe(r0), describe(r1)
    assert d1.period_s == pytest.approx(d0.period_s, rel=1e-7)
    assert d1.advance_per_cycle_mm == pytest.approx(d0.advance_per_cycle_mm, rel=1e-6)
    for end in ("leading_lateral_p2p_mm", "trailing_lateral_p2p_mm"):
        assert getattr(d1, end) == pytest.approx(getattr(d0, end), rel=1e-6), end
    assert d1.leading_end == d0.leading_end and d1.towards_field == d0.towards_field
    assert d1.direction_to_field_deg == pytest.approx(d0.direction_to_field_deg, abs=1e-4)
