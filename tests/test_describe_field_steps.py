"""describe over the last stretch of one field strength. A review: a field switched off at
10 s of a 30 s run was described over the cycles the switch cut (period 0.361 s against 0.377,
advance 20 % low, "no limit cycle ... simulate longer")."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.analysis import describe
from flutterswim.field import Field, Piecewise


@pytest.fixture(scope="module")
def steady():
    return describe(fs.simulate(fs.PAPER, 16.0, n_segments=16), n_last=5)


def test_a_field_switched_off_is_described_before_the_switch(steady):
    run = fs.simulate(fs.PAPER, 22.0, n_segments=16, field=Field(strength=Piecewise((0.0, 12.0), (1.0, 0.0))))
    d = describe(run, n_last=5)
    assert d.limit_cycle and "switched off at t = 12 s" in d.note and "simulate longer" not in d.note
    assert d.window_end_s <= 12.0
    assert d.period_s == pytest.approx(steady.period_s, rel=2e-3)
    assert d.advance_per_cycle_mm == pytest.approx(steady.advance_per_cycle_mm, rel=1e-2)
    assert d.trailing_lateral_p2p_mm == pytest.approx(steady.trailing_lateral_p2p_mm, rel=1e-2)


def test_a_stronger_field_is_described_after_the_step():
    """A step from 1 to 1.3 x kappa_E at 8 s: the cycles after it, as in a run at 1.3 x from the start."""
    p = fs.PAPER
    run = fs.simulate(p, 26.0, n_segments=16, field=Field(strength=Piecewise((0.0, 8.0), (1.0, 1.3))))
    d = describe(run, n_last=5)
    ref = describe(fs.simulate(p.replace(kappa_E=1.3 * p.kappa_E), 20.0, n_segments=16), n_last=5)
    assert d.window_start_s >= 8.0 and "steps 1 time(s)" in d.note
    assert d.period_s == pytest.approx(ref.period_s, rel=2e-3)
    assert d.advance_per_cycle_mm == pytest.approx(ref.advance_per_cycle_mm, rel=1e-2)


def test_a_constant_field_is_described_as_before(steady):
    assert "field's strength" not in steady.note and "switched off" not in steady.note
    from flutterswim.analysis.track import as_track

    run = fs.simulate(fs.PAPER, 16.0, n_segments=16)
    tr = as_track(run)
    assert tr.field_strength is not None and np.all(tr.field_strength == 1.0)
    assert tr.slice(3, 10).field_strength.shape == (7,)


def test_a_step_too_close_to_the_end_is_named():
    """A review: a step 0.1 s before the end raised 'signal of duration 0.09748 s ... holds fewer
    than two periods', without a word of the step."""
    from flutterswim._validate import ParameterError

    run = fs.simulate(fs.PAPER, 14.0, n_segments=16, field=Field(strength=Piecewise((0.0, 13.9), (1.0, 1.3))))
    with pytest.raises(ParameterError, match=r"steps 1 time\(s\).*t = 13\.9.*too short to describe.*simulate longer"):
        describe(run)
