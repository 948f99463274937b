"""Sweep definition: grid parsing, point parameters, refusal of a changed definition."""

import numpy as np
import pytest

from flutterswim._validate import ParameterError
from flutterswim.params import PAPER, Groups
from flutterswim.sweep import SweepDefinitionError, SweepSpec, parse_axis, sweep
from flutterswim.sweep.spec import point_params


def test_parse_axis_forms():
    a = parse_axis("kappa_E_ratio=0:2:101")
    assert a.name == "kappa_E_ratio" and len(a.values) == 101
    assert a.values[0] == 0.0 and a.values[-1] == 2.0 and a.values[50] == 1.0
    assert parse_axis("chi=60,70.5,80").values == (60.0, 70.5, 80.0)
    assert parse_axis("tau=0.3").values == (0.3,)
    for bad in ("kappa_E_ratio", "kappa_E_ratio=0:2", "kappa_E_ratio=a:b:3", "nope=1,2", "chi=1,nan"):
        with pytest.raises(ParameterError):
            parse_axis(bad)


def test_point_params():
    p = point_params(PAPER, {"kappa_E_ratio": 0.5})
    assert p.kappa_E == pytest.approx(0.5 * PAPER.kappa_E)
    p = point_params(PAPER, {"chi": 30.0, "tau": 0.5})
    assert p.kappa_E == pytest.approx(30.0 / PAPER.l) and p.tau == 0.5
    g = point_params(PAPER, {"eta_perp": 100.0})
    assert isinstance(g, Groups) and g.eta_perp == 100.0 and g.eta_par == pytest.approx(PAPER.eta_par)
    g = point_params(Groups(40.0, 70.0, 50.0), {"kappa_E_ratio": 2.0})
    assert g.chi == 100.0
    with pytest.raises(ParameterError, match="physical"):
        point_params(Groups(40.0, 70.0, 50.0), {"tau": 1.0})


def test_grid_and_list_and_continuation_order():
    s = SweepSpec.build(["kappa_E_ratio=0:1:3", "tau=0.3,0.4"])
    assert s.shape == (3, 2) and s.n_points == 6
    assert s.values(1) == {"kappa_E_ratio": 0.0, "tau": 0.4}
    s = SweepSpec.build({"chi": [1, 2, 3], "tau": [0.1, 0.2, 0.3]}, mode="list")
    assert s.shape == (3,) and s.values(2) == {"chi": 3.0, "tau": 0.3}
    with pytest.raises(ParameterError, match="equal lengths"):
        SweepSpec.build({"chi": [1, 2, 3], "tau": [0.1]}, mode="list")
    s = SweepSpec.build(["kappa_E_ratio=0:1:3"], continuation=True)
    seq = [s.point(k)[:2] for k in range(s.n_points)]
    assert seq == [("up", 0), ("up", 1), ("up", 2), ("down", 2), ("down", 1), ("down", 0)]
    # a descending (or unordered) axis: "up" still runs in increasing value (it had run from the
    # largest, so the branches' labels read backwards)
    s = SweepSpec.build(["kappa_E_ratio=2.3,2.05,1.95,1.85"], continuation=True)
    up = [s.point(k)[2]["kappa_E_ratio"] for k in range(s.n_values)]
    down = [s.point(k)[2]["kappa_E_ratio"] for k in range(s.n_values, s.n_points)]
    assert up == sorted(up) and down == sorted(down, reverse=True) and up[-1] == down[0]
    assert [s.point(k)[1] for k in range(s.n_values)] == [3, 2, 1, 0]  # stored at the values' own places
    with pytest.raises(ParameterError, match="repeat"):
        SweepSpec.build(["chi=1,2", "chi=3"])


def _const(task):
    return {"a": task["values"]["x_dummy"] if "x_dummy" in task["values"] else task["values"]["chi"]}


_const.variables = ["a"]


def test_changed_definition_is_refused(tmp_path):
    out = tmp_path / "s.zarr"
    ds = sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=_const, progress=False)
    np.testing.assert_array_equal(ds["a"].values, [1.0, 2.0])
    # the same definition resumes (nothing to do) and gives the same data
    ds2 = sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=_const, progress=False)
    np.testing.assert_array_equal(ds2["a"].values, ds["a"].values)
    with pytest.raises(SweepDefinitionError, match=r"axes\.0\.values"):
        sweep({"chi": [1.0, 3.0]}, out=str(out), backend="serial", point_fn=_const, progress=False)
    with pytest.raises(SweepDefinitionError, match="settings.t_cap"):
        sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=_const, progress=False,
              settings={"t_cap": 10.0})
    ds3 = sweep({"chi": [1.0, 3.0]}, out=str(out), backend="serial", point_fn=_const, progress=False,
                overwrite=True)
    np.testing.assert_array_equal(ds3["a"].values, [1.0, 3.0])


def test_second_writer_is_refused(tmp_path):
    from flutterswim.sweep import SweepSpec, SweepStore

    spec = SweepSpec.build({"chi": [1.0, 2.0]})
    out = tmp_path / "l.zarr"
    first = SweepStore.open(out, spec, ["a"], 3)
    try:
        with pytest.raises(SweepDefinitionError, match="another sweep process"):
            sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=_const, progress=False)
    finally:
        first.close()
    ds = sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=_const, progress=False)
    assert ds["done"].all()


def test_a_grid_axis_with_a_repeated_value_is_refused():
    """A grid's axis is a coordinate of the store: kappa_E_ratio=1,1 gave two rows labelled 1.0
    (xarray's sel returned both). It is refused, naming the axis and the value; a list sweep,
    which pairs values, may repeat them."""
    with pytest.raises(ParameterError, match=r"'kappa_E_ratio' repeats the values \[1.0\]"):
        SweepSpec.build(["kappa_E_ratio=1,1"])
    with pytest.raises(ParameterError, match="repeats"):
        SweepSpec.build(["tau=0.3,0.4,0.3", "chi=1,2"])
    s = SweepSpec.build({"chi": [1, 1], "tau": [0.1, 0.2]}, mode="list")
    assert s.n_points == 2


def _toy(task):
    """A chain that records the value it continued from (prev) and fails at (down, 3.0)."""
    import math

    v = task["values"]["chi"]
    prev = float(task["initial"][0]) if task["initial"] is not None else math.nan
    if v == 3.0 and task["branch"] == "down":
        raise RuntimeError("boom")
    swim = v >= 3 or (v >= 2 and not math.isnan(prev) and prev >= 2)
    return {"values": {"limit_cycle": float(swim), "prev": prev, "tag": v},
            "final_state": np.full(2 * task["settings"]["n_segments"] + 3, v)}


_toy.variables = ["limit_cycle", "prev", "tag"]
_toy.required = ["limit_cycle", "tag"]


def test_a_descending_continuation_resumes_and_reports_the_right_points(tmp_path, capsys):
    """The store's point positions had kept "up" in the order given while the points ran in
    increasing value: a descending axis resumed into undone points forever, and its failure was
    reported at chi = 2.0 for the one at 3.0 (a review)."""
    from flutterswim.params import Groups

    args = dict(base=Groups(41.5, 71.5, 70.0), continuation=True, point_fn=_toy, backend="serial",
                out=str(tmp_path / "a.zarr"), progress=False)
    sweep({"chi": [4.0, 3.0, 2.5, 2.0, 1.0]}, max_points=3, **args)
    ds = sweep({"chi": [4.0, 3.0, 2.5, 2.0, 1.0]}, **args)
    assert bool(ds["done"].all())
    up = ds["prev"].sel(branch="up").to_series()
    assert np.isnan(up[1.0]) and up[2.0] == 1.0 and up[2.5] == 2.0 and up[3.0] == 2.5 and up[4.0] == 3.0
    down = ds["prev"].sel(branch="down").to_series()
    assert down[4.0] == 4.0  # the down branch continues from the up branch's last point
    failed = ds["failed"].sel(branch="down").to_series()
    assert failed[3.0] and not failed.drop(3.0).any()
    assert "{'chi': 3.0}" in capsys.readouterr().err


def test_a_store_made_before_keeps_its_order_and_is_not_resumed_as_a_new_one():
    """A descending continuation made before stop 46 ran "up" in the order given: read so; a new
    sweep of the same axis is a different definition (refused on resume, not mis-assigned)."""
    import json

    new = SweepSpec.build(["kappa_E_ratio=2.3,2.05,1.95,1.85"], continuation=True)
    d = json.loads(new.to_json())
    assert d["up"] == "increasing"
    old = SweepSpec.from_dict({k: v for k, v in d.items() if k != "up"})
    assert [old.point(k)[1] for k in range(old.n_values)] == [0, 1, 2, 3]
    assert old.diff(new) and SweepSpec.from_dict(d).diff(new) == []
    asc = SweepSpec.build(["kappa_E_ratio=1.85,1.95"], continuation=True)
    assert "up" not in json.loads(asc.to_json())  # ascending stores keep their definition


def test_resuming_an_old_descending_store_says_why_it_is_refused(tmp_path):
    """A continuation store made before, with a descending axis, has no "up" key: refused on
    resume with the reason, not only 'up: stored <absent>'."""
    import json

    import zarr

    from flutterswim.params import Groups

    args = dict(base=Groups(41.5, 71.5, 70.0), continuation=True, point_fn=_toy, backend="serial",
                out=str(tmp_path / "a.zarr"), progress=False)
    sweep({"chi": [4.0, 3.0]}, max_points=1, **args)
    g = zarr.open_group(str(tmp_path / "a.zarr"), mode="r+")
    d = json.loads(g.attrs["sweep_spec"])
    d.pop("up")
    g.attrs["sweep_spec"] = json.dumps(d, sort_keys=True, separators=(",", ":"))
    with pytest.raises(SweepDefinitionError, match="made by an earlier flutterswim"):
        sweep({"chi": [4.0, 3.0]}, **args)


def test_an_old_descending_stores_figure_says_the_order_it_ran_in(tmp_path):
    """A store made before stop 46 with a descending axis ran "up" in the order given; its figure
    labelled that branch "increasing" (helper-110). A new store's label is unchanged."""
    import json

    import zarr

    from flutterswim.params import Groups
    from flutterswim.sweep import open_sweep
    from flutterswim.sweep.plot import plot_sweep

    args = dict(base=Groups(41.5, 71.5, 70.0), continuation=True, point_fn=_stroke, backend="serial", progress=False)
    for name, legacy in (("old.zarr", True), ("new.zarr", False)):
        sweep({"chi": [4.0, 3.0, 2.0]}, out=str(tmp_path / name), **args)
        if legacy:
            g = zarr.open_group(str(tmp_path / name), mode="r+")
            d = json.loads(g.attrs["sweep_spec"])
            d.pop("up")
            g.attrs["sweep_spec"] = json.dumps(d, sort_keys=True, separators=(",", ":"))
        ds = open_sweep(str(tmp_path / name))
        labels = [t.get_text() for t in plot_sweep(ds).axes[0].get_legend().get_texts()]
        up = next(lb for lb in labels if lb.startswith("up:"))
        assert ("in the order given" in up) == legacy and ("increasing" in up) == (not legacy), labels


def _stroke(task):
    """A stroke at every point (what the sweep figure draws)."""
    v = task["values"]["chi"]
    return {"values": {"limit_cycle": 1.0, "straight": 0.0, "self_intersecting": 0.0, "advance_per_cycle_bl": 0.1 * v,
                       "period_s": 0.3, "reached_limit_cycle": 1.0},
            "final_state": np.full(2 * task["settings"]["n_segments"] + 3, v)}


_stroke.variables = ["limit_cycle", "straight", "self_intersecting", "advance_per_cycle_bl", "period_s",
                     "reached_limit_cycle"]
