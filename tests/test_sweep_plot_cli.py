"""Sweep figure (self-intersecting parts red, linear onset marked) and the CLI subcommands."""

import argparse
import math

import numpy as np
import pytest

from flutterswim.params import PAPER
from flutterswim.stability import physical_stability
from flutterswim.sweep import sweep
from flutterswim.sweep.cli import register
from flutterswim.sweep.plot import critical_ratio, plot_sweep

VARS = ["swimming", "straight", "self_intersecting", "limit_cycle_reached", "advance_per_cycle_bl", "period_s"]


def fake(task):
    r = task["values"]["kappa_E_ratio"]
    swim = r > 0.7
    return {"swimming": float(swim), "straight": float(not swim), "self_intersecting": float(r > 1.5),
            "limit_cycle_reached": float(swim), "advance_per_cycle_bl": 0.1 * r if swim else math.nan,
            "period_s": 0.4 / r if swim else math.nan}


fake.variables = VARS
fake.required = ["swimming", "straight"]


def test_plot_marks_self_intersection_red_and_onset(tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    ds = sweep(["kappa_E_ratio=0:2:21"], backend="serial", point_fn=fake, progress=False)
    rc = critical_ratio(ds)
    assert rc == pytest.approx(physical_stability(PAPER).critical_kappa_E / PAPER.kappa_E, rel=1e-9)
    fig = plot_sweep(ds, str(tmp_path / "f.png"))
    assert (tmp_path / "f.png").stat().st_size > 1000
    ax = fig.axes[0]
    red = [l for l in ax.lines if l.get_color() == "tab:red"]
    black = [l for l in ax.lines if l.get_color() == "k"]
    # segments touching a self-intersecting point (r > 1.5: 1.6 ... 2.0, and 1.5-1.6) are red
    xs_red = sorted({float(v) for l in red for v in l.get_xdata()})
    assert xs_red and min(xs_red) == pytest.approx(1.5) and max(xs_red) == pytest.approx(2.0)
    assert all(max(l.get_xdata()) <= 1.6 + 1e-9 for l in black)
    # the onset of the model the points ran with (N segments: 0.6835 at 24 against the
    # continuum's 0.6865, where a point at 0.685 swam left of the mark), the continuum's dotted
    from flutterswim.orbits.linear import hopf_point
    from flutterswim.sweep.spec import PointSettings

    n = PointSettings().n_segments
    rd = hopf_point(PAPER, "kappa_E_ratio", n_segments=n).value
    assert rd < rc and abs(rd / rc - 1) < 0.02
    vlines = [l for l in ax.lines if l.get_color() == "tab:blue"]
    assert vlines and np.allclose(vlines[0].get_xdata(), rd)
    dotted = [l for l in ax.lines if l.get_color() == "0.6" and l.get_linestyle() == ":"]
    assert dotted and np.allclose(dotted[0].get_xdata(), rc)
    # below the onset the advancement is drawn as zero (straight), above it positive
    y = {round(float(v[0]), 6): float(v[1]) for l in ax.lines if l.get_color() in ("k", "tab:red")
         for v in zip(l.get_xdata(), l.get_ydata())}
    assert y[0.2] == 0.0 and y[1.0] == pytest.approx(0.1)
    # and no line joins the last straight point (0.7, drawn at 0) to the first swimming one:
    # it would draw advances that no point has between them
    spans = [tuple(np.round(l.get_xdata(), 6)) for l in ax.lines if l.get_color() in ("k", "tab:red")]
    assert (0.7, 0.8) not in spans and (0.6, 0.7) in spans and (0.8, 0.9) in spans


def test_cli_sweep_and_plot(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    register(sub)
    out = tmp_path / "s.zarr"
    args = ap.parse_args(["sweep", "kappa_E_ratio=0,0.3", "--out", str(out), "--backend", "serial",
                          "--n-segments", "8", "--t-cap", "4", "--no-progress"])
    assert args.func(args) == 0
    assert "2/2 points, 0 failed" in capsys.readouterr().out
    args = ap.parse_args(["plot-sweep", str(out), "--out", str(tmp_path / "p.png")])
    assert args.func(args) == 0 and (tmp_path / "p.png").exists()
    # a changed definition on the same store is refused with a clear message
    args = ap.parse_args(["sweep", "kappa_E_ratio=0,0.4", "--out", str(out), "--backend", "serial",
                          "--n-segments", "8", "--t-cap", "4", "--no-progress"])
    with pytest.raises(Exception, match="different sweep"):
        args.func(args)


OUT_VARS = ["straight", "limit_cycle", "not_periodic", "capped", "bent_equilibrium", "self_intersecting",
            "reached_limit_cycle", "advance_per_cycle_bl", "period_s"]


def fake_outcomes(task):
    """Straight below 0.7, strokes to 1.2, then no stroke: not periodic, capped, bent."""
    r = task["values"]["kappa_E_ratio"]
    kind = ("straight" if r < 0.7 else "limit_cycle" if r <= 1.2 else "not_periodic" if r <= 1.5
            else "capped" if r <= 1.7 else "bent_equilibrium")
    out = {k: float(kind == k) for k in OUT_VARS[:5]}
    swim = kind == "limit_cycle"
    out.update({"self_intersecting": 0.0 if swim else math.nan, "reached_limit_cycle": float(swim),
                "advance_per_cycle_bl": 0.1 * r if swim else math.nan, "period_s": 0.4 / r if swim else math.nan})
    return out


fake_outcomes.variables = OUT_VARS
fake_outcomes.required = ["straight", "limit_cycle"]


def _drawn_x(ax):
    return {round(float(v), 6) for l in ax.lines for v in np.atleast_1d(l.get_xdata())}


def test_every_point_is_drawn_by_its_outcome(tmp_path):
    """A review: points that ended neither straight nor swimming (not periodic, capped, bent)
    were not drawn, and the axis shrank to the last straight point, as if the sweep ended there;
    straight points (self_intersecting NaN) were coloured as self-intersecting."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    ds = sweep(["kappa_E_ratio=0:2:21"], backend="serial", point_fn=fake_outcomes, progress=False)
    fig = plot_sweep(ds)
    ax = fig.axes[0]
    xs = {round(float(v), 6) for v in ds.kappa_E_ratio.values}
    assert xs <= _drawn_x(ax)  # each of the 21 points has an artist
    lo, hi = ax.get_xlim()
    assert lo < 0.0 and hi > 2.0
    labels = " ".join(t.get_text() for t in ax.get_legend().get_texts())
    for word in ("not periodic", "capped", "bent equilibrium"):
        assert word in labels
    assert not [l for l in ax.lines if l.get_color() == "tab:red"]  # nothing self-intersects
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_a_continuation_sweep_draws_both_branches_and_its_jumps():
    """A review: only the "up" branch was drawn, with a solid line across its jump to the other
    stroke, so the hysteresis did not show."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import xarray as xr

    from flutterswim.sweep.plot import _jumps

    ds = sweep(["kappa_E_ratio=0:2:21"], backend="serial", point_fn=fake, progress=False)
    down = ds.copy(deep=True)
    # the down branch stays on another stroke (twice the period) above 1.3
    down["period_s"] = xr.where(ds.kappa_E_ratio > 1.25, ds.period_s * 2.0, ds.period_s)
    both = xr.concat([ds, down], dim=xr.DataArray(["up", "down"], dims="branch", name="branch"))
    jumps = _jumps(down.period_s.values)
    assert np.count_nonzero(jumps) == 1 and jumps[12]  # between 1.2 and 1.3 only
    assert not _jumps(ds.period_s.values).any()
    both["failed"] = xr.where(both.kappa_E_ratio == 2.0, True, both["failed"])  # failed on either branch
    fig = plot_sweep(both)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels.count("failed") == 1 and len(labels) == len(set(labels))
    ax = fig.axes[1]
    dashed = [l for l in ax.lines if l.get_linestyle() == "--"]
    dotted = [l for l in ax.lines if l.get_linestyle() == ":" and np.ptp(l.get_xdata()) > 0]  # (not the onset)
    assert dashed and len(dotted) == 1 and np.allclose(dotted[0].get_xdata(), [1.2, 1.3])
    import matplotlib.pyplot as plt

    plt.close(fig)


OUT_VARS_DIR = [*OUT_VARS, "swim_direction_deg"]


def fake_reversal(task):
    """Strokes from 0.7 on; past 1.5 they swim against the field (180 degrees); those at 0.9
    and 1.0 are orbits by continuation (the run had not settled)."""
    r = task["values"]["kappa_E_ratio"]
    swim = r >= 0.7
    out = {k: 0.0 for k in OUT_VARS[:5]}
    out["straight" if not swim else "limit_cycle"] = 1.0
    out.update({"self_intersecting": 0.0 if swim else math.nan,
                "reached_limit_cycle": float(swim and not 0.85 < r < 1.05),
                "advance_per_cycle_bl": 0.1 * r if swim else math.nan, "period_s": 0.4 / r if swim else math.nan,
                "swim_direction_deg": (180.0 if r > 1.5 else 0.0) if swim else math.nan})
    return out


fake_reversal.variables = OUT_VARS_DIR
fake_reversal.required = ["straight", "limit_cycle"]


def test_reversed_and_unsettled_strokes_are_marked_where_they_are():
    """A held-out review: past the fold of the kappa_E branch the stroke swims the other way and
    the figure did not show it; and the markers of orbits by continuation were placed by the
    int8 flags used as positions (x[0], x[1], where the period is NaN: never visible)."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ds = sweep(["kappa_E_ratio=0.5:2:16"], backend="serial", point_fn=fake_reversal, progress=False)
    ds["failed"] = ds["failed"].astype("int8")  # as xarray.open_zarr gives it from the store (plot-sweep)
    fig = plot_sweep(ds)
    x = ds.kappa_E_ratio.values
    back = [l for l in fig.axes[0].lines if "against the field" in l.get_label()]
    assert len(back) == 1
    np.testing.assert_allclose(back[0].get_xdata(), x[x > 1.5])
    circles = [l for l in fig.axes[1].lines if "continuation" in l.get_label()]
    assert len(circles) == 1
    np.testing.assert_allclose(circles[0].get_xdata(), x[(x > 0.85) & (x < 1.05)])
    np.testing.assert_allclose(circles[0].get_ydata(), 0.4 / x[(x > 0.85) & (x < 1.05)])
    plt.close(fig)


def test_plot_sweep_of_a_grid_names_the_store_and_its_axes(tmp_path, capsys):
    """A 2-d store: the error named an internal function ('plot_sweep needs a 1-d sweep;
    advance_per_cycle_bl has dims [...]') (a review)."""
    from flutterswim.cli import main

    out = tmp_path / "g.zarr"
    sweep({"kappa_E_ratio": [0.8, 1.0], "eta_perp": [3.0, 4.0]}, out=str(out), backend="serial", point_fn=fake,
          progress=False)
    capsys.readouterr()
    assert main(["plot-sweep", str(out)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and "store=" in err[0] and "2 axes (kappa_E_ratio, eta_perp)" in err[0] and "needs a 1-d sweep" not in err[0]
    assert not (tmp_path / "g.png").exists()


def test_sweep_takes_the_option_names_of_the_other_commands():
    from flutterswim.cli import build_parser

    a = build_parser().parse_args(["sweep", "chi=1,2", "--out", "s.zarr", "--segments", "16", "--cycles", "3",
                                   "--quiet"])
    assert (a.n_segments, a.n_cycles, a.no_progress) == (16, 3, True)
