"""A filament trapped in a bent equilibrium by a sudden turn of the field has no stroke: the
integrator's noise leaves cycles of a millionth of the stroke, which describe read as a limit
cycle (a review: `limit_cycle: true`, 15 cycles of period 0.47 s, tip excursion 6e-7 mm, and
no note)."""

import math

import numpy as np

import flutterswim as fs
from flutterswim.analysis import describe
from flutterswim.steering.schedules import step


def test_a_trapped_filament_is_described_as_no_stroke():
    p = fs.PAPER
    # a 15 degree step at this phase of the established stroke traps it (settle engine and
    # the independent check below agree)
    run = fs.simulate(p, 40.0, n_segments=24, field=step(math.radians(15.0), 20.0944))
    # independent: the end's tangent angle swings by under 1e-4 rad over the last 5 s
    last = run.t > run.t[-1] - 5.0
    th = np.unwrap(np.arctan2(run.y[last, -1] - run.y[last, -2], run.x[last, -1] - run.x[last, -2]))
    assert np.ptp(th) < 1e-4
    d = describe(run)
    assert not d.limit_cycle and math.isnan(d.limit_cycle_time_s)
    assert "stroke stopped" in d.note
    assert "no net swimming" in d.note and d.leading_end == "none" and math.isnan(d.swim_direction_deg)


def test_a_swimming_filament_is_still_a_limit_cycle():
    run = fs.simulate(fs.PAPER, 16.0, n_segments=24)
    d = describe(run)
    assert d.limit_cycle and "stroke stopped" not in d.note
    assert d.leading_end == "s=l" and abs(d.direction_to_field_deg) < 1.0 and d.towards_field
