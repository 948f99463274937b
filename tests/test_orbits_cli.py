"""``flutterswim branch`` and ``flutterswim plot-branch``: data, units and the figure's data."""

import numpy as np
import pytest

from flutterswim.cli import main


def test_branch_and_plot(tmp_path, capsys):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("matplotlib")
    out = tmp_path / "branch.nc"
    code = main(["branch", "kappa_E_ratio=0.6:0.9", "--out", str(out), "--points", "6", "--segments", "16",
                 "--steps", "16", "--quiet"])
    assert code == 0
    ds = xr.open_dataset(out, engine="h5netcdf")
    x = ds["kappa_E_ratio"].values
    assert x[0] > ds.attrs["hopf_kappa_E_ratio"] and x[-1] == pytest.approx(0.9)
    assert ds.attrs["bifurcation"] == "supercritical" and ds.attrs["lyapunov_coefficient"] < 0
    assert ds["advance"].attrs["units"] == "m" and ds.attrs["Conventions"].startswith("CF")
    # the square-root law: advance grows with the distance to the Hopf point, from zero
    assert np.all(np.diff(ds["advance"].values) > 0)
    png = tmp_path / "branch.png"
    assert main(["plot-branch", str(out), "--out", str(png)]) == 0
    from flutterswim.orbits.plot import plot_branch

    fig = plot_branch(ds)
    ys = [line.get_ydata() for line in fig.axes[0].lines if len(line.get_xdata()) == x.size + 1]
    assert any(np.allclose(np.asarray(y)[1:], ds["advance"].values * 1e3, equal_nan=True) for y in ys)
    # the legend lists what the branch draws: no red entry for a branch that never self-intersects
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert ("self-intersecting stroke" in labels) == bool(ds["self_intersecting"].values.any())
    assert ("unstable orbit" in " ".join(labels)) == (not ds["stable"].values.all())
    red = ds.copy()
    red["self_intersecting"] = red["self_intersecting"] | (red["kappa_E_ratio"] > 0.85)
    assert "self-intersecting stroke" in [t.get_text() for t in plot_branch(red).legends[0].get_texts()]


def test_branch_of_negative_fields_is_the_mirror_branch(tmp_path):
    """chi -> -chi is the filament turned by pi: the stroke exists for kappa_E_ratio below the
    mirror Hopf point, and a range there is continued from it (it was refused, naming the
    positive Hopf point, or failed on chi = 0, which has no oscillatory mode)."""
    xr = pytest.importorskip("xarray")
    opts = ["--points", "6", "--segments", "8", "--steps", "16", "--quiet"]
    paths = {}
    for rng in ("kappa_E_ratio=0.7:1", "kappa_E_ratio=-1:-0.7"):
        paths[rng] = tmp_path / f"b{len(paths)}.nc"
        assert main(["branch", rng, "--out", str(paths[rng]), *opts]) == 0
    pos, neg = (xr.open_dataset(p, engine="h5netcdf") for p in paths.values())
    assert neg.attrs["hopf_kappa_E_ratio"] == pytest.approx(-pos.attrs["hopf_kappa_E_ratio"], rel=1e-9)
    assert neg["kappa_E_ratio"].values[-1] == pytest.approx(-1.0)
    # the mirror stroke: the same period and advance at the mirrored field
    np.testing.assert_allclose(np.interp(0.9, pos["kappa_E_ratio"], pos["period"]),
                               np.interp(0.9, -neg["kappa_E_ratio"].values, neg["period"].values), rtol=1e-3)
    from flutterswim.orbits.linear import hopf_bracket
    from flutterswim.orbits.parameter import Axis
    import flutterswim as fs

    lo, hi = hopf_bracket(Axis(fs.PAPER, "kappa_E_ratio"), 8, -1.0, 1.0)  # its grid holds chi = 0
    assert lo < neg.attrs["hopf_kappa_E_ratio"] < hi
    # a range holding both Hopf points: the one nearer the base value (1), whose branch the
    # CLI then continues to the far end, 1.2 (it continued the mirror branch to -1)
    lo, hi = hopf_bracket(Axis(fs.PAPER, "kappa_E_ratio"), 8, -1.0, 1.2, prefer=1.0)
    assert lo < pos.attrs["hopf_kappa_E_ratio"] < hi


def test_branch_cli_rejects_bad_input_with_one_line(tmp_path, capsys):
    assert main(["branch", "zeta=0:1", "--out", str(tmp_path / "b.nc")]) == 2
    err = capsys.readouterr().err
    assert "zeta" in err and "Traceback" not in err and err.count("\n") == 1
    assert main(["branch", "kappa_E_ratio=0.6", "--out", str(tmp_path / "b.nc")]) == 2
    assert main(["plot-branch", str(tmp_path / "missing.nc")]) == 2



@pytest.mark.parametrize("rng, words", [("tau=-1:1", "tau=-1 is not allowed"), ("tau=0:1", "tau=0 is not allowed"),
                                         ("B=-1e-13:1e-14", "B=-1e-13"), ("eta_perp=-50:100", "eta_perp=-50"),
                                         ("l=0.004:-0.005", "l=-0.005")])
def test_branch_cli_refuses_ends_outside_the_parameters_domain(tmp_path, capsys, rng, words):
    """A range reaching values a parameter cannot take (tau <= 0) was continued from the Hopf
    point to its valid end, exit 0: now one line naming the end, exit 2, nothing written."""
    out = tmp_path / "b.nc"
    assert main(["branch", rng, "--out", str(out), "--points", "4", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and not out.exists(), err


@pytest.mark.parametrize("argv, words", [
    (["kappa_E_ratio=nan:2"], "nan"), (["kappa_E_ratio=0.6:-inf"], "-inf"),
    (["kappa_E_ratio=0.6:0.9", "--segments", "2"], "--segments=2"),
    (["kappa_E_ratio=0.6:0.9", "--segments", "-1"], "--segments=-1")])
def test_branch_cli_refuses_non_finite_ranges_and_too_few_segments(tmp_path, capsys, argv, words):
    """A NaN end ran a whole branch (and stored range_start = NaN); N = 2 said "no Hopf point
    found", N = -1 failed with an IndexError (exit 1). Each is bad input: one line, exit 2,
    and nothing written."""
    out = tmp_path / "b.nc"
    assert main(["branch", *argv, "--out", str(out), "--points", "4", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err and err.count("\n") == 1
    assert not out.exists()

def test_readme_orbits_block_runs(tmp_path):
    """The README's periodic-orbit block, at small sizes, saved as a script."""
    import re
    import subprocess
    import sys
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    block = next(b for b in re.findall(r"```python\n(.*?)```", text, flags=re.S) if "continue_orbits" in b)
    small = {
        "periodic_orbit(PAPER)": "periodic_orbit(PAPER, n_segments=16, steps=16)",
        'continue_orbits(PAPER, "kappa_E_ratio", 2.0)': 'continue_orbits(PAPER, "kappa_E_ratio", 0.8, n_points=4, n_segments=16, steps=16)',
        'hopf_point(PAPER, "kappa_E_ratio")': 'hopf_point(PAPER, "kappa_E_ratio", n_segments=16)',
    }
    for big, sm in small.items():
        assert big in block, big
        block = block.replace(big, sm)
    block += "\nassert orb.stable and nf.supercritical and orb.period > 0\nprint('ok')\n"
    script = tmp_path / "orbits_example.py"
    script.write_text(block)
    r = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip().endswith("ok") and (tmp_path / "branch.nc").exists()


def test_plot_of_a_subcritical_branch_folding_back_past_the_hopf_point():
    """A subcritical branch leaves the Hopf point towards smaller values (unstable orbits),
    folds, and comes back past it (stable orbits, most of its points): the straight state is
    stable on the side the branch leaves to, below the Hopf point (it was drawn from the Hopf
    point up, where the straight state is unstable), and the unstable orbits are marked."""
    import matplotlib

    matplotlib.use("Agg")
    import xarray as xr

    from flutterswim.orbits.plot import plot_branch

    hopf = 0.58
    u = np.linspace(0.0, 1.0, 40)
    x = np.r_[hopf - 0.05 * np.sin(np.pi * u[:12] / 0.6), np.linspace(0.55, 1.2, 28)]  # out, fold, back
    stable = np.r_[np.zeros(10, bool), np.ones(30, bool)]
    amp = np.r_[np.linspace(0.01, 0.5, 12), np.linspace(0.55, 0.8, 28)]
    ds = xr.Dataset({"advance": ("kappa_E_ratio", amp * 1e-3), "period": ("kappa_E_ratio", 0.5 + 0 * amp, {"units": "s"}),
                     "lateral_leading": ("kappa_E_ratio", amp * 1e-3), "lateral_trailing": ("kappa_E_ratio", amp * 2e-3),
                     "self_intersecting": ("kappa_E_ratio", np.zeros(40)), "stable": ("kappa_E_ratio", stable)},
                    coords={"kappa_E_ratio": ("kappa_E_ratio", x, {"units": "1"})},
                    attrs={"parameter": "kappa_E_ratio", "hopf_kappa_E_ratio": hopf, "hopf_period": 0.5,
                           "bifurcation": "subcritical", "lyapunov_coefficient": 3e-4, "range_end": 1.2})
    fig = plot_branch(ds)
    ax = fig.axes[0]
    grey = [ln for ln in ax.lines if ln.get_label() == "straight, stable (linear theory)"]
    assert grey and max(grey[0].get_xdata()) == pytest.approx(hopf) and min(grey[0].get_xdata()) < hopf
    rings = [ln for ln in ax.lines if ln.get_marker() == "o" and ln.get_color() == "tab:orange"]
    assert rings and np.allclose(np.sort(rings[0].get_xdata()), np.sort(x[~stable]))


def test_hopf_search_stays_within_the_values_the_model_takes(tmp_path, capsys, recwarn):
    """Along b the straight state is unstable down to tiny widths and the search scanned up to
    50 b: `branch b=0.0001:0.0002` was refused for b = 0.00185 m (>= l/2), a value nobody
    typed, with slenderness warnings for it. Now the search ends where the model does, and says
    there is no Hopf point, naming the parameter and the valid values scanned."""
    from flutterswim import PAPER

    code = main(["branch", "b=0.0001:0.0002", "--out", str(tmp_path / "b.nc"), "--segments", "8", "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "no Hopf point found for b between" in err[0] and "unstable throughout" in err[0]
    hi = float(err[0].split(" and ")[1].split()[0])
    assert hi < PAPER.l / 2  # only values the model takes
    assert not [w for w in recwarn if "not slender" in str(w.message)]
    assert not (tmp_path / "b.nc").exists()


def test_a_hopf_point_outside_the_range_is_named(tmp_path, capsys):
    """No Hopf point in the range typed: the branch starts at the nearest one, and says so."""
    code = main(["branch", "kappa_E_ratio=0.9:1", "--out", str(tmp_path / "k.nc"), "--points", "4",
                 "--segments", "8", "--steps", "16", "--quiet"])
    err = capsys.readouterr().err
    assert code == 0
    assert "note: no Hopf point in kappa_E_ratio=0.9:1; the branch starts at the nearest one" in err
    hopf = float(err.split("kappa_E_ratio=")[2].split(",")[0])
    assert hopf < 0.9
    capsys.readouterr()
    assert main(["branch", "kappa_E_ratio=0.6:1", "--out", str(tmp_path / "k2.nc"), "--points", "4",
                 "--segments", "8", "--steps", "16", "--quiet"]) == 0
    assert "note:" not in capsys.readouterr().err  # inside the range: no note


def test_an_error_stands_alone_without_the_note(tmp_path, capsys):
    """kappa_E_ratio=0.1:0.3 has no Hopf point and no stroke: one line, the error (the note about
    the Hopf point outside the range came first, two lines)."""
    code = main(["branch", "kappa_E_ratio=0.1:0.3", "--out", str(tmp_path / "k.nc"), "--segments", "8", "--quiet"])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert code == 2 and len(err) == 1 and "note" not in err[0], err


def test_a_range_of_negative_fields_without_a_branch_names_the_mirror_hopf_point(tmp_path, capsys):
    """kappa_E_ratio=-0.3:-0.1 lies between zero and the mirror branch's Hopf point: no stroke.
    The error named the positive Hopf point (the only one between the range and the base value
    1) and said the branch exists above it; the branch nearest the range is the mirror one, below
    minus that value."""
    import re

    import flutterswim as fs
    from flutterswim.orbits.linear import hopf_point

    positive = hopf_point(fs.PAPER, "kappa_E_ratio", n_segments=8).value
    code = main(["branch", "kappa_E_ratio=-0.3:-0.1", "--out", str(tmp_path / "k.nc"), "--segments", "8", "--quiet"])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert code == 2 and len(err) == 1, err
    named = float(re.findall(r"-?\d+\.\d+", err[0])[-1])
    assert named == pytest.approx(-positive, rel=1e-6) and "below" in err[0], err[0]
    assert "-0.3:-0.1" in err[0] and not (tmp_path / "k.nc").exists()


def test_a_typed_value_that_is_not_slender_is_warned_about_once(tmp_path, capsys, monkeypatch):
    """The range's end b=0.0009 m (b/l = 0.24) is not slender: the warning came twice, once
    when the end was checked and again when the Hopf search met it, whenever the warning
    filters changed in between (Python then forgets the warnings it showed): a first compile
    or a lazy import does, as the search's growth rates here."""
    import warnings

    from flutterswim.orbits import linear

    real = linear.flutter_growth

    def growth(*a, **kw):
        with warnings.catch_warnings():  # what a compile or a lazy import does to the filters
            pass
        return real(*a, **kw)

    monkeypatch.setattr(linear, "flutter_growth", growth)
    main(["branch", "b=0.0002:0.0009", "--out", str(tmp_path / "a.nc"), "--segments", "8", "--steps", "16",
          "--points", "4", "--quiet"])
    err = capsys.readouterr().err.splitlines()
    typed = [ln for ln in err if "warning" in ln and "b=0.0009 m" in ln and "not slender" in ln]
    assert len(typed) == 1, err
    assert len(set(err)) == len(err), err  # no line said twice


def test_a_branch_stopped_just_short_of_its_end_says_where_in_digits_that_differ(tmp_path, capsys, monkeypatch):
    """The corrector at the range's end fails (injected): the arclength steps close in on the
    end until the step is too small, and the message read "stopped short of kappa_E_ratio=0.7
    (continuation stopped at kappa_E_ratio=0.7: ...)"."""
    import re

    from flutterswim.orbits import continuation
    from flutterswim.orbits.periodic import OrbitNotFound

    def fails(*a, **kw):
        raise OrbitNotFound("no convergence (injected)")

    monkeypatch.setattr(continuation, "_newton_natural", fails)
    out = tmp_path / "s.nc"
    code = main(["branch", "kappa_E_ratio=0.6:0.7", "--segments", "8", "--steps", "16", "--points", "50",
                 "--look-beyond", "0", "--quiet", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 1 and "stopped short of kappa_E_ratio=0.7 " in err, err
    for where in re.findall(r"(?:stopped at|up to) kappa_E_ratio=([-\d.e]+)", err):
        assert float(where) < 0.7, err  # said as it is: short of 0.7
    xr = pytest.importorskip("xarray")
    last = float(xr.open_dataset(out, engine="h5netcdf")["kappa_E_ratio"].values[-1])
    assert float(where) == pytest.approx(last, rel=1e-6)  # the last "up to": the branch's last orbit


def test_the_branch_files_inaccurate_orbits_comment_names_the_steps_option(tmp_path, capsys):
    """The NetCDF's n_inaccurate_orbits_comment said "(steps=)", the Python parameter, in a file
    written by the command; it names --steps there, as the command's warning does (the API's
    own dataset keeps steps=)."""
    xr = pytest.importorskip("xarray")
    out = tmp_path / "b.nc"
    assert main(["branch", "kappa_E_ratio=0.7:0.8", "--points", "3", "--segments", "8", "--steps", "8",
                 "--out", str(out), "--quiet"]) == 0
    ds = xr.open_dataset(out, engine="h5netcdf")
    comment = ds.attrs["n_inaccurate_orbits_comment"]
    assert ds.attrs["n_inaccurate_orbits"] > 0 and "(--steps)" in comment and "steps=" not in comment, comment
    warned = [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]
    assert len(warned) == 1 and "(--steps)" in warned[0] and "steps=" not in warned[0], warned
    from flutterswim import PAPER
    from flutterswim.orbits import continue_orbits

    api = continue_orbits(PAPER, "kappa_E_ratio", 0.8, n_points=3, n_segments=8, steps=32).to_dataset()
    assert "(steps=)" in api.attrs["n_inaccurate_orbits_comment"]


def test_a_range_typed_downwards_bounds_the_same_branch(tmp_path, capsys):
    """kappa_E_ratio=0.9:0.6 was refused as holding no branch 'above the Hopf point 0.68', which
    lies inside it: the branch starts at the Hopf point either way, the range only bounds it."""
    import xarray as xr

    opts = ["--points", "4", "--segments", "12", "--quiet"]
    up, down = tmp_path / "up.nc", tmp_path / "down.nc"
    assert main(["branch", "kappa_E_ratio=0.6:0.9", "--out", str(up), *opts]) == 0
    assert main(["branch", "kappa_E_ratio=0.9:0.6", "--out", str(down), *opts]) == 0
    a, b = xr.open_dataset(up, engine="h5netcdf"), xr.open_dataset(down, engine="h5netcdf")
    np.testing.assert_array_equal(a["kappa_E_ratio"].values, b["kappa_E_ratio"].values)
    np.testing.assert_array_equal(a["period"].values, b["period"].values)
    assert main(["branch", "kappa_E_ratio=0.7:0.7", "--out", str(tmp_path / "z.nc"), *opts]) == 2
    assert "equal" in capsys.readouterr().err
