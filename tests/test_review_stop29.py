"""Review findings (stop 29): units of a sweep store, the sweep's up-front checks, its lock
file, axis parsing, orbit branches that stop short or lie below the Hopf point, the
stability and fit commands' up-front checks, and the trial file's checks."""

import importlib
import warnings

import numpy as np
import pytest

from flutterswim import cli
from flutterswim._validate import ParameterError
from flutterswim.sweep import sweep
from flutterswim.sweep.point import VARIABLES
from flutterswim.sweep.spec import parse_axis
from flutterswim.sweep.store import variable_attrs


def fake(task):
    r = task["values"]["kappa_E_ratio"]
    return {"swimming": 1.0, "straight": 0.0, "self_intersecting": 0.0, "limit_cycle_reached": 1.0,
            "advance_per_cycle_bl": 0.1 * r, "period_s": 0.4 / r}


fake.variables = ["swimming", "straight", "self_intersecting", "limit_cycle_reached", "advance_per_cycle_bl",
                  "period_s"]


# ---------------------------------------------------------------------------------- sweep store
def test_speed_units_are_length_per_time():
    assert variable_attrs("speed_mm_s", "s")["units"] == "mm/s"
    assert variable_attrs("speed_bl_s", "s")["units"] == "1/s"
    assert variable_attrs("speed_bl_s", "tau")["scaled_units"] == "1/tau"
    assert variable_attrs("speed_mm_s", "tau")["scaled_units"] == "1e-3 l/tau"
    # only true times carry a time unit (in tau: units "1", the scale in scaled_units)
    times = {"t_simulated", "time_to_limit_cycle_s", "period_s", "wall_time_s"}
    for v in VARIABLES:
        a = variable_attrs(v, "s")
        u = a.get("scaled_units", a["units"])
        assert (u in ("s", "tau")) == (v in times), (v, u)


def test_lock_file_is_removed_when_the_run_ends(tmp_path):
    out = tmp_path / "s.zarr"
    sweep(["kappa_E_ratio=1,2"], out=str(out), backend="serial", point_fn=fake, progress=False)
    assert out.is_dir()
    assert not (tmp_path / ".s.zarr.lock").exists()
    # a lock file this run did not create is left alone
    (tmp_path / ".t.zarr.lock").write_text("")
    sweep(["kappa_E_ratio=1,2"], out=str(tmp_path / "t.zarr"), backend="serial", point_fn=fake, progress=False)
    assert (tmp_path / ".t.zarr.lock").exists()


@pytest.mark.parametrize("text", ["kappa_E_ratio=0.5:2:1", "kappa_E_ratio=0:inf:3"])
def test_parse_axis_refuses_one_point_and_non_finite_ranges(text):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ParameterError, match="kappa_E_ratio"):
            parse_axis(text)


@pytest.mark.parametrize("axis", ["B=-1", "tau=0", "eta_perp=-5", "tau=0.3,-1"])
def test_sweep_refuses_bad_axis_values_before_the_store_exists(tmp_path, axis, capsys):
    out = tmp_path / "w.zarr"
    assert cli.main(["sweep", axis, "--out", str(out), "--backend", "serial", "--no-progress"]) == 2
    assert not out.exists() and list(tmp_path.iterdir()) == []
    assert axis.split("=")[0] in capsys.readouterr().err


def test_sweep_plot_of_a_grid_is_refused_before_the_run(tmp_path, capsys):
    out = tmp_path / "g.zarr"
    rc = cli.main(["sweep", "kappa_E_ratio=0.5,0.6", "tau=0.3,0.4", "--out", str(out), "--plot",
                   str(tmp_path / "g.png"), "--backend", "serial", "--no-progress"])
    assert rc == 2 and list(tmp_path.iterdir()) == []
    assert "--plot" in capsys.readouterr().err


def test_plot_sweep_branch_is_checked(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    cont = tmp_path / "c.zarr"
    sweep(["kappa_E_ratio=1,2"], out=str(cont), backend="serial", point_fn=fake, progress=False,
          continuation=True)
    png = tmp_path / "c.png"
    assert cli.main(["plot-sweep", str(cont), "--branch", "sideways", "--out", str(png)]) == 2
    err = capsys.readouterr().err
    assert "sideways" in err and "up" in err and "down" in err and not png.exists()
    plain = tmp_path / "p.zarr"
    sweep(["kappa_E_ratio=1,2"], out=str(plain), backend="serial", point_fn=fake, progress=False)
    assert cli.main(["plot-sweep", str(plain), "--branch", "down", "--out", str(png)]) == 2
    assert "branch" in capsys.readouterr().err and not png.exists()


# ---------------------------------------------------------------------------------- orbit branches
@pytest.fixture(scope="module")
def tau_branch(tmp_path_factory):
    """A branch below its Hopf point (the stroke exists for tau below tau_Hopf ~ 1.2)."""
    pytest.importorskip("matplotlib")
    d = tmp_path_factory.mktemp("tau")
    out, png = d / "tau.nc", d / "tau.png"
    rc = cli.main(["branch", "tau=0.1:2", "--segments", "8", "--steps", "16", "--points", "5", "--quiet",
                   "--out", str(out), "--plot", str(png)])
    return rc, out, png


def _straight_line(fig):
    ax = fig.axes[0]
    return [ln for ln in ax.lines if ln.get_color() == "0.5"][0]


def test_branch_below_the_hopf_point_is_drawn_on_the_requested_range(tau_branch):
    import xarray as xr

    from flutterswim.orbits.plot import plot_branch

    rc, out, png = tau_branch
    assert rc == 0 and png.is_file()
    ds = xr.open_dataset(out, engine="h5netcdf")
    x, hopf = ds["tau"].values, ds.attrs["hopf_tau"]
    assert np.all(x < hopf) and x.min() == pytest.approx(0.1)
    for fig in (plot_branch(ds, x_range=(0.1, 2.0)), plot_branch(ds)):  # the CLI's range, the file's
        lo, hi = fig.axes[0].get_xlim()
        assert lo <= 0.1 and hi >= 2.0 and lo < hopf < hi
        # the straight state is stable above the Hopf point (supercritical, branch below)
        xs = sorted(_straight_line(fig).get_xdata())
        assert xs[0] == pytest.approx(hopf) and xs[1] == pytest.approx(2.0)


def test_plot_branch_of_a_file_with_range_end_runs_forwards(tau_branch, tmp_path):
    import xarray as xr

    from flutterswim.orbits.plot import plot_branch

    _, out, _ = tau_branch
    ds = xr.open_dataset(out, engine="h5netcdf").load()
    ds.attrs["range_end"] = 3.0
    ds = ds.isel(orbit=slice(0, 6))  # a short branch: far from its end of the range
    fig = plot_branch(ds)
    lo, hi = fig.axes[0].get_xlim()
    assert lo < hi and lo <= float(ds["tau"].min()) and hi >= 3.0
    png = tmp_path / "b.png"
    src = tmp_path / "b.nc"
    ds.to_netcdf(src, engine="h5netcdf")
    assert cli.main(["plot-branch", str(src), "--out", str(png)]) == 0 and png.is_file()


def test_branch_stopping_short_exits_1_and_keeps_the_file(tmp_path, monkeypatch, capsys):
    from flutterswim.orbits import continuation

    real = continuation.continue_orbits
    monkeypatch.setattr(continuation, "continue_orbits", lambda *a, **kw: real(*a, **kw, max_points=3))
    out = tmp_path / "s.nc"
    rc = cli.main(["branch", "kappa_E_ratio=0.6:2", "--segments", "8", "--steps", "16", "--points", "5",
                   "--quiet", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 1 and out.is_file()
    assert err.count("\n") == 1 and "max_points=3" in err and str(out) in err


def test_branch_at_large_eta_perp_reaches_the_end(tmp_path):
    """The closing tolerance is relative to the state's scale: at N = 8 the absolute 1e-10 was
    below the round-off floor near eta_perp = 163 and the branch stopped there."""
    import xarray as xr

    out = tmp_path / "eta.nc"
    rc = cli.main(["branch", "eta_perp=10:300", "--segments", "8", "--steps", "16", "--points", "5", "--quiet",
                   "--out", str(out)])
    assert rc == 0
    assert xr.open_dataset(out, engine="h5netcdf")["eta_perp"].values[-1] == 300.0


# ---------------------------------------------------------------------------------- stability, fit
def test_stability_step_too_large_is_refused_before_any_file(tmp_path, capsys):
    out = tmp_path / "st"
    assert cli.main(["stability", "--out", str(out), "--step", "1000", "--quiet"]) == 2
    assert not out.exists() and "step" in capsys.readouterr().err


HEADER = "voltage_V,sample,period_s,advance_mm,lateral_mm\n"


def _no_fit(*a, **kw):
    raise AssertionError("the fit ran")


def test_fit_bootstrap_negative_is_refused_before_fitting(tmp_path, monkeypatch, capsys):
    fit_module = importlib.import_module("flutterswim.fitting.fit")

    csv = tmp_path / "t.csv"
    csv.write_text(HEADER + "3,a,0.5,0.30,1.0\n3,b,0.6,0.32,1.1\n3,c,0.55,0.28,0.9\n")
    monkeypatch.setattr(fit_module, "fit", _no_fit)
    out = tmp_path / "f.json"
    assert cli.main(["fit", str(csv), "--bootstrap", "-3", "--no-extrapolate", "--out", str(out)]) == 2
    assert "--bootstrap=-3" in capsys.readouterr().err and not out.exists()
    monkeypatch.undo()

    class Model:  # any use of the model means the fit started
        def __getattr__(self, name):
            raise AssertionError("the fit ran")

    with pytest.raises(ParameterError, match="bootstrap=-3"):
        fit_module.fit([0.5, 0.3, 1.0], [0.01, 0.01, 0.01], model=Model(), bootstrap=-3)


def test_trials_with_a_nan_voltage_name_the_file_and_row(tmp_path):
    from flutterswim.fitting.data import read_trials

    csv = tmp_path / "t.csv"
    csv.write_text(HEADER + "3,a,0.5,0.3,1.0\nnan,b,0.6,0.3,1.1\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ParameterError, match=r"t\.csv.*row 3.*voltage_V"):
            read_trials(csv)


def test_identical_trials_are_named_with_their_voltage_and_rows(tmp_path, monkeypatch, capsys):
    fit_module = importlib.import_module("flutterswim.fitting.fit")
    from flutterswim.fitting.data import read_trials, summarise

    csv = tmp_path / "same.csv"
    csv.write_text(HEADER + "2,x,0.4,0.2,0.8\n3,a,0.5,0.3,1.0\n3,a,0.5,0.3,1.0\n3,a,0.5,0.3,1.0\n")
    with pytest.warns(UserWarning, match="rows 3, 4, 5"):
        trials = read_trials(csv)
    # no spread: the standard error is exactly zero (std of equal numbers), not round-off
    assert np.all(summarise(trials).at(3.0)[1] == 0.0)
    monkeypatch.setattr(fit_module, "fit", _no_fit)
    out = tmp_path / "f.json"
    assert cli.main(["fit", str(csv), "--no-extrapolate", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "same.csv" in err and "3 V" in err and "rows 3, 4, 5" in err and "identical" in err
    assert not out.exists()


def test_trials_with_a_bad_descriptor_name_the_row_and_column(tmp_path):
    from flutterswim.fitting.data import read_trials

    csv = tmp_path / "t.csv"
    csv.write_text(HEADER + "3,a,0.5,0.3,1.0\n3,b,nan,0.3,1.1\n")
    with pytest.raises(ParameterError, match=r"t\.csv.*row 3.*period_s='nan'"):
        read_trials(csv)
    csv.write_text(HEADER + "3,a,0.5,-0.3,1.0\n")
    with pytest.raises(ParameterError, match=r"row 2.*advance_mm='-0.3'"):
        read_trials(csv)


def test_periods_in_milliseconds_are_questioned(tmp_path):
    from flutterswim.fitting.data import read_trials

    csv = tmp_path / "t.csv"
    csv.write_text(HEADER + "3,a,377,0.3,1.0\n3,b,380,0.31,1.1\n")
    with pytest.warns(UserWarning, match="not ms"):
        read_trials(csv)
    csv.write_text(HEADER + "3,a,0.377,0.3,1.0\n3,b,0.380,0.31,1.1\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_trials(csv)


def test_a_run_shorter_than_its_frame_interval_saves_its_end():
    """frame_dt longer than the run saved only the initial state (the run's end was lost)."""
    import flutterswim as fs

    short = fs.simulate(fs.preset("paper"), 0.5, n_segments=8, frame_dt=5.0)
    fine = fs.simulate(fs.preset("paper"), 0.5, n_segments=8, frame_dt=0.1)
    assert short.t.size == 2 and short.t[-1] == pytest.approx(fine.t[-1])
    np.testing.assert_allclose(short.x[-1], fine.x[-1], rtol=0, atol=1e-12)
