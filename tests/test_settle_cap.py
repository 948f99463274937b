"""What a sweep point is at its time cap near the onset, where time stepping cannot decide:
the linearly stable side is straight (its oscillation ends at the integrator's noise), and
just above the Hopf point of the discrete model the stroke comes from continuation (the
growth over the whole run is less than a factor e). Both were left "capped"."""

from dataclasses import asdict

import pytest

import flutterswim as fs
from flutterswim.orbits.linear import hopf_point
from flutterswim.sweep.point import run_point
from flutterswim.sweep.spec import PointSettings, _base_dict

SETTINGS = asdict(PointSettings())
R_H = hopf_point(fs.PAPER, "kappa_E_ratio", n_segments=SETTINGS["n_segments"]).value


def _point(r):
    return run_point({"base": _base_dict(fs.PAPER), "values": {"kappa_E_ratio": r}, "settings": SETTINGS})


@pytest.mark.parametrize("below", [0.88, 0.91, 0.94])
def test_linearly_stable_points_near_the_onset_are_straight(below):
    out = _point(below * R_H)
    v = out["values"]
    assert v["growth_rate_linear_per_s"] < 0
    assert v["straight"] == 1.0 and v["capped"] == 0.0, out["reason"]


def test_just_above_the_hopf_point_the_stroke_follows_the_normal_form():
    """Two points 0.05 % and 0.2 % above the Hopf point: strokes (not capped) whose advance, of
    second order in the amplitude, grows in proportion to the distance from the Hopf point."""
    d = (5e-4, 2e-3)
    pts = [_point(R_H * (1 + e)) for e in d]
    for p in pts:
        assert p["values"]["limit_cycle"] == 1.0 and p["values"]["growth_rate_linear_per_s"] > 0, p["reason"]
    a = [p["values"]["advance_per_cycle_mm"] for p in pts]
    assert a[1] / a[0] == pytest.approx(d[1] / d[0], rel=0.05)
