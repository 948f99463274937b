"""Edges of the simulator found by a held-out review (stop 44): a tolerance below round-off, a
span within round-off, a failed run that said nothing, and which stepper ran."""

import math
import warnings

import numpy as np
import pytest

import flutterswim as fs
from flutterswim._validate import MIN_TOLERANCE, ParameterError
from flutterswim.field import Field

G = fs.PAPER.groups


def test_tolerances_below_round_off_are_refused_at_once():
    """rtol 1e-13 with atol 1e-15 ran 24 s (1.9 million steps) and failed at t = 32 tau; now one
    clear error. The smallest allowed tolerance completes a run, and a tiny rtol with a sizeable
    atol (an absolute error norm) stays allowed."""
    with pytest.raises(ParameterError, match=r"rtol=1e-13 and atol=1e-15 are both below 1e-12"):
        fs.simulate(G, 40.0, n_segments=24, rtol=1e-13, atol=1e-15)
    r = fs.simulate(G, 2.0, n_segments=12, rtol=MIN_TOLERANCE, atol=1e-14)
    assert r.status == "completed"
    assert fs.simulate(G, 0.5, n_segments=12, rtol=1e-14, atol=1e-7).status == "completed"


@pytest.mark.parametrize("t_start,t_end", [(0.0, 1e-12), (1e6, 1e6 + 1e-9)])
def test_a_span_within_round_off_is_refused(t_start, t_end):
    """Such a run said 'reached t_end' with t_final = t_start: no step was taken."""
    with pytest.raises(ParameterError, match="within round-off of t_start"):
        fs.simulate(G, t_end, t_start=t_start, n_segments=12)
    # just above it, the end is reached
    r = fs.simulate(G, 1e-6, n_segments=12)
    assert r.status == "completed" and r.t_final == pytest.approx(1e-6, rel=1e-9)


def test_a_failed_run_warns_and_describe_says_so(monkeypatch):
    """A run that ends on a solver failure returned status 'failed' without a word, and describe
    gave a limit cycle of its frames with no note. The stepper's result is replaced by a failure
    at 60 % of the run (a true collapse takes a stiff case and minutes)."""
    import importlib

    sim = importlib.import_module("flutterswim.simulate")
    real = sim.integrate_filament

    def failing(*a, **k):
        sol = real(*a, **k)
        from dataclasses import replace

        keep = sol.t <= 0.6 * sol.t[-1]
        return replace(sol, t=sol.t[keep], y=sol.y[keep], status="failed", t_final=float(sol.t[keep][-1]),
                       y_final=sol.y[keep][-1], message=f"step size collapsed at t={sol.t[keep][-1]:.6g}")

    monkeypatch.setattr(sim, "integrate_filament", failing)
    with pytest.warns(RuntimeWarning, match="the run failed: step size collapsed"):
        run = fs.simulate(fs.PAPER, 12.0, n_segments=24, frame_dt=0.01)
    assert run.status == "failed"
    assert run.t_final == pytest.approx(run.t[-1]) and run.t[-1] < 0.61 * 12.0
    d = fs.describe(run)
    assert "the simulation failed (step size collapsed" in d.note
    monkeypatch.undo()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ok = fs.simulate(fs.PAPER, 0.5, n_segments=12)  # a run that completes warns nothing
    assert ok.status == "completed" and "failed" not in fs.describe(fs.simulate(fs.PAPER, 12.0, n_segments=24,
                                                                              frame_dt=0.01)).note


def test_the_python_stepped_rosenbrock_is_named_as_such():
    """method='ros34pw2' with a field turning between breakpoints, and 'ros34pw2-wave1' with any
    field, ran the Python-stepped wave-1 ROS34PW2 and reported 'ros34pw2', the compiled method's
    name."""
    turning = fs.simulate(G, 0.5, n_segments=12, method="ros34pw2", field=Field(direction=lambda t: 0.0))
    wave1 = fs.simulate(G, 0.5, n_segments=12, method="ros34pw2-wave1")
    compiled = fs.simulate(G, 0.5, n_segments=12, method="ros34pw2")
    assert turning.settings["method_used"] == wave1.settings["method_used"] == "ros34pw2-wave1"
    assert compiled.settings["method_used"] == "ros34pw2"
    assert math.isclose(turning.t_final, 0.5) and np.all(np.isfinite(turning.theta))
