"""describe on a run whose field turns faster than the stroke can follow: the filament loses
its stroke and turns nearly in place, and describe gave a turning radius, a heading lag and a
heading that follows the field (17.99 against 18 deg/s) with no word that the swimmer had
stepped out (a review: 6 % of its speed). It now says so; below step-out it says nothing."""

import math

import pytest

import flutterswim as fs
from flutterswim.analysis import describe
from flutterswim.steering.schedules import rotation

OMEGA_MAX = 0.26  # rad/s: the paper's step-out rate (the steering model's; tests/test_steering.py)


@pytest.mark.parametrize("fraction, stepped", [(0.3, False), (1.3, True)])
def test_a_swimmer_that_stepped_out_is_said_to_have(fraction, stepped):
    om = fraction * OMEGA_MAX
    onset = 10.0
    run = fs.simulate(fs.PAPER, onset + 0.6 * 2 * math.pi / om, field=rotation(2 * math.pi / om, onset),
                      n_segments=24)
    d = describe(run)
    assert d.field_turn_rate_deg_s == pytest.approx(math.degrees(om), rel=0.02)
    assert ("stepped out" in d.note) is stepped
