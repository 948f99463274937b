"""NetCDF round trip of a run, and the CLI against the Python API."""

import json
import subprocess
import sys

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.analysis.descriptors import describe
from flutterswim.defaults import N_CYCLES
from flutterswim.field import Field, Piecewise


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    field = Field(direction=Piecewise([0.0, 11.0], [0.0, 0.1]))
    run = fs.simulate(fs.PAPER, 12.0, n_segments=16, rtol=1e-4, field=field, forces=True, n_frames=1201)
    path = run.save(tmp_path_factory.mktemp("io") / "run.nc")
    return run, path


def test_netcdf_round_trip_is_exact(short_run):
    run, path = short_run
    back = fs.load(path)
    for name in ("t", "s", "s_mid", "x", "y", "theta", "kappa", "r0", "field_angle",
                 "field_strength", "A", "V", "M", "state_final"):
        np.testing.assert_array_equal(getattr(back, name), getattr(run, name), err_msg=name)
    assert back.params == run.params and back.groups == run.groups
    assert back.stats == run.stats and back.settings == run.settings
    assert (back.status, back.message, back.t_final, back.units) == (run.status, run.message, run.t_final, run.units)
    import xarray as xr

    with xr.open_dataset(path, engine="h5netcdf") as ds:
        assert ds.attrs["flutterswim_version"] == fs.__version__
        assert json.loads(ds.attrs["params"])["kappa_E"] == fs.PAPER.kappa_E


def test_field_schedule_is_followed(short_run):
    run, _ = short_run
    assert np.all(run.field_angle[run.t < 11.0] == 0.0) and np.all(run.field_angle[run.t >= 11.0] == 0.1)


def test_cli_json_matches_python_api(short_run, capsys):
    """The CLI in a process of its own (once), then in this one (main(): the same code, without
    a Python start per call)."""
    from flutterswim.cli import main

    run, path = short_run
    out = subprocess.run([sys.executable, "-m", "flutterswim.cli", "describe", str(path), "--json", "--last", "3"],
                         capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == json.loads(json.dumps(describe(fs.load(path), n_last=3).to_dict()))
    # an approximate period (10 % off) is refined from the data: the same cycles, as in Python
    rough = 1.1 * json.loads(out.stdout)["period_s"]
    capsys.readouterr()
    assert main(["describe", str(path), "--json", "--last", "3", "--period", repr(rough)]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d == json.loads(json.dumps(describe(fs.load(path), n_last=3, period=rough).to_dict()))
    assert d["period_s"] == pytest.approx(json.loads(out.stdout)["period_s"], rel=1e-3)
    # without --last a run is described over defaults.N_CYCLES cycles (a tracked movie over 5)
    assert main(["describe", str(path), "--json"]) == 0
    dflt = json.loads(capsys.readouterr().out)
    assert dflt == json.loads(json.dumps(describe(fs.load(path), n_last=N_CYCLES).to_dict()))
    assert main(["describe", str(path), "--period", "-1"]) == 2
    err = capsys.readouterr().err
    assert "period=-1" in err and len(err.strip().splitlines()) == 1


def test_cli_reports_bad_input_by_name(tmp_path):
    out = subprocess.run([sys.executable, "-m", "flutterswim.cli", "simulate", "--segments", "2", "--t-end", "1",
                          "--out", str(tmp_path / "x.nc"), "--quiet"], capture_output=True, text=True)
    assert out.returncode == 2 and "--segments=2" in out.stderr


def test_a_fixed_time_run_that_ends_still_and_bent_is_named():
    """simulate --t-end after a field step can end trapped in a bent equilibrium; it printed
    'completed' alone. The note names it; a swimming run and a straight still one get none."""
    from types import SimpleNamespace

    from flutterswim.cli import _still_and_bent

    t = np.linspace(0.0, 25.0, 1001)
    s = np.linspace(0.0, 1.0, 25)
    field = np.full(t.size, np.pi / 2)
    bent = np.pi / 2 + np.outer(np.ones(t.size), -np.pi * (1 - s))  # a hairpin, still
    swim = np.pi / 2 + 0.8 * np.sin(2 * np.pi * t / 0.38)[:, None] * (s - 0.5)[None]
    straight = np.pi / 2 + 1e-6 * np.sin(2 * np.pi * t / 0.38)[:, None] * np.ones(s.size)
    note = _still_and_bent(SimpleNamespace(t=t, theta=bent, field_angle=field))
    assert "trapped in a bent equilibrium" in note and "180 degrees" in note
    assert _still_and_bent(SimpleNamespace(t=t, theta=swim, field_angle=field)) == ""
    assert _still_and_bent(SimpleNamespace(t=t, theta=straight, field_angle=field)) == ""
