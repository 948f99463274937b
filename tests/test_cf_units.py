"""Every written unit is one udunits (so CF) reads, checked with an independent parser
(cf-units, the UK Met Office's binding of udunits2). A quantity in the paper's scales is a pure
number: units "1", its scale in ``scaled_units``; that string is a true unit expression (the
dimensionless file times its scales equals the SI file)."""

import re

import numpy as np
import pytest
import xarray as xr

import flutterswim as fs

cf_units = pytest.importorskip("cf_units")
LITRE = cf_units.Unit("m3")


def _udunits(unit, where):
    try:
        u = cf_units.Unit(unit)
    except ValueError as e:  # pragma: no cover - the failure is the message
        raise AssertionError(f"{where}: units {unit!r} is not a udunits unit") from e
    assert not u.is_convertible(LITRE), f"{where}: units {unit!r} reads as a volume (l is the litre)"
    return u


def _check_cf(ds, what):
    for name, var in ds.variables.items():
        if var.dtype.kind in "fiuc":
            assert "units" in var.attrs, f"{what}: {name} has no units"
        if "units" in var.attrs:
            _udunits(var.attrs["units"], f"{what}: {name}")
            if "scaled_units" in var.attrs:
                assert var.attrs["units"] == "1"
    for key, value in ds.attrs.items():
        if key.endswith("_units") and not key.endswith("scaled_units"):
            _udunits(value, f"{what}: attribute {key}")


def _in_si(scaled, p):
    """The SI unit that the scaled unit string stands for at parameters p (tau -> p.tau s,
    l -> p.l m, B -> p.B N m2): an independent reading of the string."""
    sub = {"tau": f"({p.tau!r} s)", "l": f"({p.l!r} m)", "B": f"({p.B!r} N m2)"}
    text = re.sub(r"(?<![A-Za-z_])(tau|l|B)(?![A-Za-z_])", lambda m: sub[m.group(1)], scaled)
    return cf_units.Unit(text.replace("^", ""))


def test_dimensionless_run_reads_in_si_through_its_scaled_units(tmp_path):
    p = fs.PAPER
    run = fs.simulate(p, 0.3, n_segments=8, forces=True)
    run.save(tmp_path / "si.nc")
    run.dimensionless().save(tmp_path / "nd.nc")
    with xr.open_dataset(tmp_path / "si.nc") as si, xr.open_dataset(tmp_path / "nd.nc") as nd:
        _check_cf(si, "SI run")
        _check_cf(nd, "dimensionless run")
        scaled = [n for n in nd.variables if "scaled_units" in nd[n].attrs]
        assert {"t", "x", "y", "s", "kappa", "A", "M"} <= set(scaled)
        for name in scaled:
            factor = _in_si(nd[name].attrs["scaled_units"], p).convert(1.0, cf_units.Unit(si[name].attrs["units"]))
            np.testing.assert_allclose(nd[name].values * factor, si[name].values, rtol=1e-12, atol=1e-300,
                                       err_msg=name)
        assert nd.attrs["t_final_units"] == "1" and nd.attrs["t_final_scaled_units"] == "tau"


def test_sweep_variables_in_both_time_units():
    from flutterswim.sweep.point import VARIABLES
    from flutterswim.sweep.store import variable_attrs

    for tu in ("s", "tau"):
        for name in (*VARIABLES, "done", "failed", "reason", "wall_time_s", "state", "t_simulated"):
            a = variable_attrs(name, tu)
            _udunits(a["units"], f"sweep {name} ({tu})")
            if "scaled_units" in a:
                assert a["units"] == "1" and "in units of" in a["long_name"]
    # the simulated time is in tau whatever the base: said so, not "s"
    assert variable_attrs("t_simulated", "s")["scaled_units"] == "tau"


def test_branch_stability_map_and_neutral_curve():
    br = fs.continue_orbits(fs.PAPER.groups, "chi", to=fs.PAPER.groups.chi * 1.02, n_points=8,
                            n_segments=8)
    ds = br.to_dataset()
    _check_cf(ds, "branch over chi")
    assert ds.period.attrs["scaled_units"] == "tau" and ds.speed.attrs["scaled_units"] == "l tau-1"
    _check_cf(fs.stability_map(eta_perp=np.array([40.0, 70.0]), chi=np.array([60.0, 80.0])).to_dataset(), "stability map")
    _check_cf(fs.neutral_curve(np.array([40.0, 70.0])).to_dataset(), "neutral curve")


def test_coordinates_carry_no_fill_value(tmp_path):
    """CF: coordinate variables hold no missing data; xarray wrote _FillValue = NaN on every float
    coordinate (a review of the reproduce folder). Data variables keep theirs."""
    h5py = pytest.importorskip("h5py")
    import flutterswim as fs

    path = fs.simulate(fs.PAPER, 0.05, n_segments=8).save(tmp_path / "r.nc")
    with h5py.File(path, "r") as h:
        for name in ("t", "s"):
            assert "_FillValue" not in h[name].attrs, name
        assert "_FillValue" in h["x"].attrs
