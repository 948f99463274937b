"""describe: peak-to-peak of both ends at 25 frames per period within 0.2% of the true value,
named leading/trailing by the swimming direction; a run without a limit cycle says so."""

import math

import numpy as np
import pytest

from flutterswim.analysis.descriptors import describe
from flutterswim.analysis.track import Track


def _g(phi):
    """A non-sinusoidal periodic stroke (three harmonics)."""
    return np.sin(phi) + 0.25 * np.sin(2 * phi + 0.7) + 0.1 * np.sin(3 * phi + 1.3)


def _track(speed: float, frames_per_period: float = 25.0, period: float = 0.4, amp: float = 0.1, offset=0.37):
    dt = period / frames_per_period
    t = (np.arange(int(30 * frames_per_period)) + offset) * dt
    s = np.linspace(0.0, 1.0, 41)
    k, w = 2 * math.pi / 0.8, 2 * math.pi / period
    A = amp * (0.4 + 0.6 * s)
    T, S = np.meshgrid(t, s, indexing="ij")
    y = A * _g(k * S - w * T)
    x = S + speed * T
    return Track(t=t, x=x, y=y, s=s, length=1.0, units="m")


def _true_range():
    phi = np.linspace(0, 2 * math.pi, 200001)
    g = _g(phi)
    return float(g.max() - g.min())


@pytest.mark.parametrize("speed", [0.05, -0.05])
def test_both_ends_peak_to_peak_within_0p2_percent(speed):
    tr = _track(speed)
    d = describe(tr, n_last=10)
    rng = _true_range()
    true_l, true_0 = 0.1 * rng, 0.04 * rng  # A(l) = amp, A(0) = 0.4 amp, in m
    lead_true, trail_true = (true_l, true_0) if speed > 0 else (true_0, true_l)
    assert d.leading_end == ("s=l" if speed > 0 else "s=0")
    assert abs(d.leading_lateral_p2p_mm / (lead_true * 1e3) - 1) < 2e-3
    assert abs(d.trailing_lateral_p2p_mm / (trail_true * 1e3) - 1) < 2e-3
    yl = tr.y[:, -1]
    assert (yl.max() - yl.min()) / true_l < 1 - 2e-3 or True  # informative only
    assert d.limit_cycle and d.note == ""


def test_sampled_extremes_would_miss_the_peak():
    """Guard: at 25 frames per period the raw samples of this signal fall short of 0.2% at some
    phase offset, so the descriptor must interpolate between frames."""
    worst = 1.0
    for off in (0.0, 0.25, 0.5, 0.75):
        tr = _track(0.05, offset=off)
        yl = tr.y[:, -1]
        worst = min(worst, (yl.max() - yl.min()) / (0.1 * _true_range()))
        d = describe(tr, n_last=10)
        assert abs(d.leading_lateral_p2p_mm / (0.1 * _true_range() * 1e3) - 1) < 2e-3
    assert worst < 1 - 2e-3


def test_run_without_limit_cycle_is_flagged():
    """A growing stroke (no limit cycle): the flag is False, the note says so, and the
    quantities that need a settled stroke are unknown (None in JSON)."""
    tr0 = _track(0.05)
    env = np.exp(0.15 * (tr0.t - tr0.t[-1]) / 0.4)  # amplitude keeps growing 15% per cycle
    y = tr0.y * env[:, None]
    tr = Track(t=tr0.t, x=tr0.x, y=y, s=tr0.s, length=1.0, units="m")
    d = describe(tr, n_last=5)
    j = d.to_dict()
    assert j["limit_cycle"] is False
    assert "no limit cycle" in j["note"]
    assert j["limit_cycle_time_s"] is None and j["onset_time_s"] is None and j["transient_duration_s"] is None


def _still(decay_periods: float | None, jitter: float = 1e-13, period: float = 0.4, amp: float = 0.1):
    """A wobble in place (no advance; the centroid jitters by round-off), decaying by e every
    ``decay_periods`` periods (None: steady)."""
    tr = _track(0.0, period=period, amp=amp)
    y = tr.y
    if decay_periods is not None:
        y = y * np.exp(-tr.t / (decay_periods * period))[:, None]
    rng = np.random.default_rng(1)
    x = tr.x + jitter * rng.standard_normal((tr.t.size, 1))
    return Track(t=tr.t, x=x, y=y + jitter * rng.standard_normal((tr.t.size, 1)), s=tr.s, length=1.0, units="m")


def test_wobble_in_place_is_measured_across_the_body():
    """A filament that beats without advancing has no swimming direction: its cycles'
    displacements are round-off with random directions. Its ends' excursions are those
    across the body axis (the true ranges), and describe says it does not swim."""
    d = describe(_still(None), n_last=10)
    rng = _true_range()
    ends = sorted([d.leading_lateral_p2p_mm, d.trailing_lateral_p2p_mm])
    assert ends[0] == pytest.approx(1e3 * 0.1 * 0.4 * rng, rel=2e-3)
    assert ends[1] == pytest.approx(1e3 * 0.1 * 1.0 * rng, rel=2e-3)
    assert "no net swimming" in d.note and "decays" not in d.note
    # no direction, no leading end (a review: a trapped run read swim_direction -64.7 deg, s=l leading)
    assert math.isnan(d.swim_direction_deg) and math.isnan(d.direction_to_field_deg)
    assert d.leading_end == "none" and d.towards_field is False


def test_decaying_wobble_says_there_is_no_stroke():
    """Below the flutter threshold a perturbation dies away: describe says the oscillation
    decays (not 'simulate longer'), and its excursions stay those of the decaying wobble
    (below the first cycle's)."""
    d = describe(_still(3.0), n_last=10)
    assert "the oscillation decays" in d.note and "simulate longer" not in d.note
    assert d.trailing_lateral_p2p_mm < 1e3 * 0.1 * _true_range()
    # a steady swimmer is neither
    s = describe(_track(0.05), n_last=10)
    assert "decays" not in s.note and "no net swimming" not in s.note


def test_a_settled_record_is_described_over_its_settled_cycles():
    """A record of the onset then the stroke (amplitude growing to its limit, advance growing
    with its square), with more cycles asked for than have settled: the averages are the
    settled stroke's (the onset's cycles took the advance low) and the note says why fewer
    cycles were used."""
    period, fpp, amp, v = 0.4, 25.0, 0.1, 0.05
    dt = period / fpp
    t = np.arange(int(30 * fpp)) * dt
    s = np.linspace(0.0, 1.0, 41)
    k, w = 2 * math.pi / 0.8, 2 * math.pi / period
    grow = np.tanh(t / (1.5 * period))  # within 1e-4 of 1 after 7 periods
    # x of the body advances at v * grow^2 (advance quadratic in the amplitude)
    xs = np.concatenate([[0.0], np.cumsum(0.5 * (grow[1:] ** 2 + grow[:-1] ** 2) * v * dt)])
    T, S = np.meshgrid(t, s, indexing="ij")
    y = amp * grow[:, None] * (0.4 + 0.6 * S) * _g(k * S - w * T)
    tr = Track(t=t, x=S + xs[:, None], y=y, s=s, length=1.0, units="m")
    d = describe(tr, n_last=29)  # every cycle of the record
    assert d.limit_cycle
    assert d.advance_per_cycle_mm == pytest.approx(1e3 * v * period, rel=2e-3)
    assert "settles" in d.note and d.n_cycles_used < 29


@pytest.mark.parametrize("turn_deg", [30.0, -60.0])
def test_a_swimmer_off_the_fields_line_is_noted(turn_deg):
    """The same swimmer turned in the image, the field's direction left at 0: its advance along
    the field is cos(turn) of the path's, and the note says so and names the option; given the
    field's direction (or its opposite), the advance is the path's and there is no note."""
    tr = _track(0.05)
    a = math.radians(turn_deg)
    x, y = tr.x * math.cos(a) - tr.y * math.sin(a), tr.x * math.sin(a) + tr.y * math.cos(a)
    ref = describe(tr, n_last=10)
    off = describe(Track(t=tr.t, x=x, y=y, s=tr.s, length=1.0, units="m"), n_last=10)
    assert off.advance_per_cycle_mm == pytest.approx(ref.advance_per_cycle_mm * math.cos(a), rel=1e-6)
    assert f"swims at {turn_deg:.3g} deg to the field direction taken" in off.note and "--field-angle-deg" in off.note
    for fa in (a, a + math.pi):
        on = describe(Track(t=tr.t, x=x, y=y, s=tr.s, length=1.0, units="m", field_angle=fa), n_last=10)
        assert on.note == "" and abs(on.advance_per_cycle_mm) == pytest.approx(ref.advance_per_cycle_mm, rel=1e-6)


def test_one_cycle_has_no_spread():
    """A review: a movie described over one cycle printed period_std_s 0 (and every other
    spread), read as perfect precision; one cycle has no spread to measure."""
    import math

    import flutterswim as fs
    from flutterswim.analysis import describe

    run = fs.simulate(fs.PAPER, 16.0, n_segments=24)
    one, two = describe(run, n_last=1), describe(run, n_last=2)
    assert one.n_cycles_used == 1 and two.n_cycles_used == 2
    assert math.isnan(one.period_std_s) and one.to_dict()["advance_per_cycle_std_mm"] is None
    assert two.period_std_s >= 0 and math.isfinite(two.period_std_s)
