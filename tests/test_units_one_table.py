"""A parameter carries one unit spelling in every file that labels it: a run's attributes, a
sweep store's axis, a branch's axis and reproduce's Table 1 (kappa_E was '1/m' in runs and sweeps
but 'm-1' in branches and reproduce's files)."""

import xarray as xr

import flutterswim as fs
from flutterswim.orbits.parameter import Axis
from flutterswim.reproduce.datasets import table1_dataset
from flutterswim.sweep import sweep


def _point(task):
    return {"a": float(task["values"]["kappa_E"])}


_point.variables = ["a"]


def test_each_parameter_has_one_unit_everywhere(tmp_path):
    run = fs.simulate(fs.PAPER, 0.01, n_segments=8)
    attrs = xr.open_dataset(run.save(tmp_path / "r.nc"), engine="h5netcdf").attrs
    sweep({"kappa_E": [1.0e4, 2.0e4]}, out=str(tmp_path / "s.zarr"), backend="serial", point_fn=_point,
          progress=False)
    store = xr.open_zarr(tmp_path / "s.zarr")
    table = table1_dataset(fs.PAPER, {"semi-axis": fs.PAPER})
    for name in ("l", "a", "b", "B", "tau", "kappa_E", "mu"):
        unit = attrs[f"parameter_{name}_units"]
        if name != "a":  # (a is no continuation parameter: it does not enter the dynamics)
            assert Axis(fs.PAPER, name).units == unit, name
        assert table[name].attrs["units"] == unit, name
    assert store["kappa_E"].attrs["units"] == attrs["parameter_kappa_E_units"]
    for name in ("l", "B", "kappa_E", "mu"):  # the base point as numeric attributes, as a run's
        assert store.attrs[f"base_{name}"] == getattr(fs.PAPER, name)
        assert store.attrs[f"base_{name}_units"] == attrs[f"parameter_{name}_units"]
    assert store["kappa_E"].attrs["long_name"] == Axis(fs.PAPER, "kappa_E").long_name
    assert store.attrs["flutterswim_version"] == attrs["flutterswim_version"] == fs.__version__
