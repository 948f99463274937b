import numpy as np
import pytest

import flutterswim as fs
from flutterswim.field import Piecewise


def test_profiles_from_numbers_callables_and_samples():
    n = 20
    s_mid = (np.arange(n) + 0.5) / n
    s_nodes = np.arange(n + 1) / n
    linear = fs.InitialState(theta=np.linspace(0.0, 2.0, 11), kappa=lambda s: s**2, position=(1.0, 2.0))
    y = linear.state(n)
    np.testing.assert_allclose(y[:2], [1.0, 2.0])
    np.testing.assert_allclose(y[2 : n + 2], 2.0 * s_mid, rtol=1e-14)  # exact for a linear profile
    np.testing.assert_allclose(y[n + 2 :], s_nodes**2, rtol=1e-14)
    on_grid = fs.InitialState(theta=np.cos(s_mid)).state(n)
    np.testing.assert_array_equal(on_grid[2 : n + 2], np.cos(s_mid))


@pytest.mark.parametrize("bad, name", [({"theta": [[1.0, 2.0]]}, "theta"), ({"kappa": [0.0, np.nan]}, "kappa"),
                                       ({"position": (0.0, np.inf)}, "position")])
def test_bad_profiles_are_named(bad, name):
    with pytest.raises(fs.ParameterError, match=name):
        fs.InitialState(**bad).state(8)


def test_piecewise_schedules():
    hold = Piecewise([0.0, 1.0, 2.0], [0.0, 1.0, 3.0])
    lin = Piecewise([0.0, 1.0, 2.0], [0.0, 1.0, 3.0], kind="linear")
    assert [hold(t) for t in (-1.0, 0.5, 1.0, 1.5, 9.0)] == [0.0, 0.0, 1.0, 1.0, 3.0]
    assert lin(1.5) == pytest.approx(2.0)
    assert hold.scaled(2.0).breakpoints == (0.0, 0.5, 1.0)
    with pytest.raises(fs.ParameterError, match="increasing"):
        Piecewise([0.0, 0.0], [1.0, 2.0])


def test_a_piecewise_hold_field_needs_no_time_derivative(paper_groups):
    """Between breakpoints a held field does not depend on time: the run must equal one
    restarted at the breakpoint, and use no extra right-hand side per step."""
    from flutterswim.field import Field

    field = Field(direction=Piecewise([0.0, 1.0], [0.0, 0.2]))
    opts = dict(n_segments=12, rtol=1e-8, atol=1e-10, initial=fs.InitialState.straight(3.0))
    held = fs.simulate(paper_groups, 2.0, field=field, n_frames=3, **opts)
    first = fs.simulate(paper_groups, 1.0, n_frames=2, **opts)
    second = fs.simulate(paper_groups, 2.0, t_start=1.0, field=Field(direction=0.2), n_frames=2,
                         **{**opts, "initial": first.final_state()})
    np.testing.assert_allclose(held.theta[-1], second.theta[-1], atol=1e-6)
    # the constant-field runs evaluate f once per stage; so does the held one
    per_step = held.stats.n_rhs / (held.stats.n_steps + held.stats.n_rejected)
    assert per_step < 4.5


def test_a_run_records_the_method_that_ran():
    """A review: a field turning between breakpoints is stepped by another method than the one
    asked for; the run's settings said "ndf" and its stats "ros34pw2"."""
    import flutterswim as fs
    from flutterswim.field import Field

    turning = fs.simulate(fs.PAPER, 0.2, n_segments=8, field=Field(direction=lambda t: 0.1 * t))
    steady = fs.simulate(fs.PAPER, 0.2, n_segments=8)
    for r in (turning, steady):
        assert r.settings["method_used"] == r.stats.method
    assert steady.settings["method_used"] == steady.settings["method"]
