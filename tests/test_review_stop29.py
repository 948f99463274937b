"""Review findings (stop 29): units of a sweep store, the sweep's up-front checks, its lock
file, axis parsing, orbit branches that stop short or lie below the Hopf point, the
stability and fit commands' up-front checks, and the trial file's checks."""

import math
import warnings

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
    assert variable_attrs("speed_bl_s", "tau")["units"] == "1/tau"
    assert variable_attrs("speed_mm_s", "tau")["units"] == "1e-3 l/tau"
    # only true times carry a time unit
    times = {"t_simulated", "time_to_limit_cycle_s", "period_s", "wall_time_s"}
    for v in VARIABLES:
        u = variable_attrs(v, "s")["units"]
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
