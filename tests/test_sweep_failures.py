"""A point that raises or returns non-finite values is recorded as failed; the others complete."""

import math

import numpy as np
import pytest

from flutterswim._validate import ParameterError
from flutterswim.sweep import open_sweep, sweep


def flaky(task):
    x = task["values"]["chi"]
    if x == 2.0:
        raise RuntimeError("boom at chi=2")
    if x == 3.0:
        return {"a": math.nan, "b": 1.0}
    if x == 4.0:
        return {"a": 1.0, "b": math.inf}
    return {"a": 10 * x, "b": x + 0.5}


flaky.variables = ["a", "b"]


@pytest.mark.parametrize("backend", ["serial", "processes"])
def test_failures_are_recorded_and_do_not_stop(tmp_path, backend, capsys):
    out = tmp_path / "f.zarr"
    ds = sweep({"chi": [1.0, 2.0, 3.0, 4.0, 5.0]}, out=str(out), backend=backend, workers=2,
               point_fn=flaky, progress=True)
    assert ds["done"].all()
    np.testing.assert_array_equal(ds["failed"].values, [False, True, True, True, False])
    reason = ds["reason"].values
    assert reason[0] == "" and reason[4] == ""
    assert "RuntimeError" in reason[1] and "boom at chi=2" in reason[1]
    assert "non-finite" in reason[2] and "a=nan" in reason[2]
    assert "non-finite" in reason[3] and "b=inf" in reason[3]
    np.testing.assert_array_equal(ds["a"].values[[0, 4]], [10.0, 50.0])
    assert np.all(np.isnan(ds["a"].values[1:4]))
    assert ds.attrs["n_failed"] == 3
    err = capsys.readouterr().err
    assert "3 of 5 points failed" in err and "boom at chi=2" in err
    # the store holds the same (reopened without running)
    again = open_sweep(str(out))
    np.testing.assert_array_equal(again["failed"].values, ds["failed"].values)
    assert list(again["reason"].values) == list(reason)


def test_real_point_with_a_bad_parameter_is_refused_up_front():
    """A sweep with an invalid parameter value is refused before any point runs, with the
    parameter's message (the checks a point makes); a valid point runs (and is the straight
    state at zero field)."""
    kw = dict(base=__import__("flutterswim").PAPER.replace(kappa_E=0.0), backend="serial", progress=False,
              settings={"n_segments": 8, "t_cap": 2.0, "chunk": 1.0, "rtol": 1e-3, "atol": 1e-5, "n_cycles": 1})
    with pytest.raises(ParameterError, match=r"tau=-1.0 must be > 0"):
        sweep({"tau": [0.375, -1.0]}, **kw)
    ds = sweep({"tau": [0.375]}, **kw)
    assert ds["done"].all() and not ds["failed"].any()
    assert bool(ds["straight"].values[0])


def test_a_solver_failure_names_its_time_once_in_seconds():
    """A review: 'the solver failed at t=19.2331: step size collapsed at t=51.2882', the same
    moment in s and in tau, neither named."""
    from flutterswim.simulate import _message_in_seconds

    tau = 0.375
    assert _message_in_seconds("step size collapsed to 1e-12 at t=51.2882", tau) == \
        f"step size collapsed to 1e-12 at t={51.2882 * tau:.6g} s"
    assert _message_in_seconds("reached t_end", tau) == "reached t_end"


def test_a_stop_reason_keeps_its_own_time():
    """The stop on self-intersection says its time in s already: converting every integrator
    message put it at t * tau (0.60 s for a stop at 1.60 s)."""
    import flutterswim as fs

    p = fs.PAPER.replace(kappa_E=2.5 * fs.PAPER.kappa_E)
    r = fs.simulate(p, 20.0, n_segments=16, stop_on_self_intersection=True)
    assert r.status == "stopped" and "self-intersection" in r.message
    said = float(r.message.split("t=")[1].split()[0])
    assert said == pytest.approx(r.t_final, rel=1e-5)


_TRANSIENT = {"fail": {2.0, 4.0}, "calls": []}


def transient(task):
    x = task["values"]["chi"]
    _TRANSIENT["calls"].append(x)
    if x in _TRANSIENT["fail"]:
        raise MemoryError(f"out of memory at chi={x}")
    return {"a": 10 * x}


transient.variables = ["a"]


@pytest.mark.parametrize("continuation", [False, True])
def test_a_rerun_keeps_failed_points_unless_asked_to_retry_them(tmp_path, continuation, capsys):
    """A rerun resumes without recomputing anything recorded, failures included; with
    retry_failed only the failed points run again, and a transient failure then succeeds."""
    out = str(tmp_path / "t.zarr")
    kw = dict(out=out, backend="serial", point_fn=transient, progress=False, continuation=continuation)
    _TRANSIENT.update(fail={2.0, 4.0}, calls=[])
    ds = sweep({"chi": [1.0, 2.0, 3.0, 4.0]}, **kw)
    assert int(ds.attrs["n_failed"]) == (4 if continuation else 2)
    assert "--retry-failed" in capsys.readouterr().err
    _TRANSIENT.update(fail=set(), calls=[])
    again = sweep({"chi": [1.0, 2.0, 3.0, 4.0]}, **kw)
    assert _TRANSIENT["calls"] == [] and int(again.attrs["n_failed"]) == int(ds.attrs["n_failed"])
    fixed = sweep({"chi": [1.0, 2.0, 3.0, 4.0]}, retry_failed=True, **kw)
    assert sorted(_TRANSIENT["calls"]) == sorted([2.0, 4.0] * (2 if continuation else 1))
    assert int(fixed.attrs["n_failed"]) == 0 and bool(fixed["done"].all())
    np.testing.assert_array_equal(fixed["a"].values.ravel(), np.tile([10.0, 20.0, 30.0, 40.0],
                                                                     2 if continuation else 1))
    assert not any(fixed["reason"].values.ravel())


def test_the_command_line_retries_failed_points(tmp_path, monkeypatch):
    import importlib

    from flutterswim.cli import main

    run = importlib.import_module("flutterswim.sweep.run")
    seen = {}

    def fake(*a, **kw):
        seen.update(kw)
        raise ParameterError("stop here")

    monkeypatch.setattr(run, "sweep", fake)
    assert main(["sweep", "chi=1,2", "--out", str(tmp_path / "s.zarr"), "--retry-failed"]) == 2
    assert seen["retry_failed"] is True
    assert main(["sweep", "chi=1,2", "--out", str(tmp_path / "s.zarr")]) == 2
    assert seen["retry_failed"] is False
