"""A sweep's records: in its base's units whatever the axes (an eta_par or eta_perp axis on a
physical base runs its points as dimensionless groups; their records were stored in tau and
1e-3 l under the names and units of s and mm), each with why the point ended as it did, and
the CLI's exit status when points are missing."""

from dataclasses import asdict

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.sweep.point import VARIABLES, run_point
from flutterswim.sweep.spec import PointSettings, _base_dict


@pytest.mark.parametrize("axis", ["eta_perp", "eta_par"])
def test_an_eta_axis_at_the_base_value_gives_the_base_point_in_its_units(axis):
    """The paper's own point reached as eta_perp (or eta_par) = its value and as kappa_E_ratio = 1:
    the same record, variable by variable (before: period 1.007 'units s' against 0.378 s)."""
    settings = asdict(PointSettings(n_segments=12))
    base = _base_dict(fs.PAPER)
    via_eta = run_point({"base": base, "values": {axis: getattr(fs.PAPER.groups, axis)}, "settings": settings})
    direct = run_point({"base": base, "values": {"kappa_E_ratio": 1.0}, "settings": settings})
    a, b = via_eta["values"], direct["values"]
    assert b["limit_cycle"] == 1.0 and np.isfinite(b["period_s"])
    for k in VARIABLES:  # (the same computation in other units: round-off apart)
        assert a[k] == pytest.approx(b[k], rel=1e-9, abs=1e-9, nan_ok=True), k


def test_the_cli_exits_1_when_points_were_not_computed(tmp_path, monkeypatch, capsys):
    """A worker lost with its point leaves it not computed (not failed): the summary said
    '39/40 points, 0 failed' and exit 0, so a script took the store for finished."""
    import importlib

    import xarray as xr

    from flutterswim.cli import main

    run = importlib.import_module("flutterswim.sweep.run")

    def partial(*a, **kw):
        return xr.Dataset(attrs={"n_done": 39, "n_points": 40, "n_failed": 0})

    monkeypatch.setattr(run, "sweep", partial)
    assert main(["sweep", "kappa_E_ratio=0.7:2:40", "--out", str(tmp_path / "k.zarr"), "--no-progress"]) == 1
    out = capsys.readouterr().out
    assert "39/40 points, 0 failed, 1 not computed" in out and "rerun" in out

    def complete(*a, **kw):
        return xr.Dataset(attrs={"n_done": 40, "n_points": 40, "n_failed": 0})

    monkeypatch.setattr(run, "sweep", complete)
    assert main(["sweep", "kappa_E_ratio=0.7:2:40", "--out", str(tmp_path / "k.zarr"), "--no-progress"]) == 0


def test_every_point_says_why_it_ended_as_it_did(tmp_path):
    """The store's reason holds what a point settled into (a capped point said nothing), and
    a failure's message where it failed."""
    import math

    from flutterswim.sweep import sweep

    def point(task):
        x = task["values"]["chi"]
        if x > 2:
            raise RuntimeError("boom")
        return {"values": {"a": math.sin(x)}, "reason": f"settled at chi={x:g}"}

    point.variables = ["a"]
    ds = sweep({"chi": [1.0, 2.0, 3.0]}, out=str(tmp_path / "r.zarr"), backend="serial", point_fn=point,
               progress=False)
    assert list(ds["reason"].values[:2]) == ["settled at chi=1", "settled at chi=2"]
    assert "boom" in ds["reason"].values[2] and ds["failed"].values.tolist() == [False, False, True]
