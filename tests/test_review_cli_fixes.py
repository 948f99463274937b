"""Review findings on the command line (branch cli-fixes); each section names its finding."""

import importlib
import json
import os

import pytest

import flutterswim as fs
from flutterswim import cli


def _error(argv, capsys):
    status = cli.main([str(a) for a in argv])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert status == 2 and len(err) == 1, (status, err)
    return err[0]


@pytest.fixture()
def no_computing(monkeypatch):
    """The commands below must stop at their checks: a simulation fails the test."""
    def computed(*a, **kw):
        raise AssertionError("computed before the output path was checked")

    for module, name in (("flutterswim.simulate", "simulate"), ("flutterswim.limit_cycle", "run_to_limit_cycle"),
                         ("flutterswim.demo", "run_to_limit_cycle"), ("flutterswim.sweep.run", "_run"),
                         ("flutterswim.stability.figures", "_figures")):
        monkeypatch.setattr(importlib.import_module(module), name, computed)


# ------------------------------------------------------------ 1. no missing folder is created
@pytest.mark.parametrize("argv, option", [
    (["simulate", "--t-end", "1", "--quiet", "--out", "{new}/dir/a.nc"], "--out"),
    (["simulate", "--quiet", "--out", "{new}/a.nc"], "--out"),
    (["plot", "{tmp}/run.nc", "--out", "{new}/y/fig.png"], "--out"),
    (["sweep", "chi=60", "--out", "{new}/s.zarr", "--no-progress"], "--out"),
    (["reproduce", "--out", "{new}/rp"], "--out"),
    (["stability", "--out", "{new}/st", "--quiet"], "--out"),
])
def test_an_output_in_a_missing_folder_is_refused_and_nothing_is_created(tmp_path, capsys, no_computing, argv,
                                                                         option):
    new = tmp_path / "newdir"
    line = _error([a.format(tmp=tmp_path, new=new) for a in argv], capsys)
    assert f"{option}=" in line and f"the folder {str(new)!r} does not exist" in line, line
    assert not new.exists() and os.listdir(tmp_path) == []


def test_the_api_creates_no_folder_for_a_file(tmp_path):
    from flutterswim._paths import atomic_path

    run = fs.simulate(fs.PAPER, 0.05, n_segments=6)
    with pytest.raises(fs.ParameterError, match="does not exist"):
        run.save(tmp_path / "a" / "b" / "run.nc")
    with pytest.raises(FileNotFoundError):
        with atomic_path(tmp_path / "a" / "x.txt") as tmp:
            tmp.write_text("x")
    assert os.listdir(tmp_path) == []


def test_demo_creates_its_folder_only_inside_an_existing_one(tmp_path, capsys, no_computing):
    from flutterswim import demo

    assert demo.main(["--out", str(tmp_path / "x" / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--out=" in err[0] and f"{str(tmp_path / 'x')!r} does not exist" in err[0], err
    assert os.listdir(tmp_path) == []
    (tmp_path / "x").mkdir()
    with pytest.raises(AssertionError, match="computed"):  # past the checks, the folder made
        demo.main(["--out", str(tmp_path / "x" / "out")])
    assert (tmp_path / "x" / "out").is_dir()


# ------------------------------------------------------------ 4. a new sweep store is *.zarr
def _double(task):
    return {"a": 2.0 * task["values"]["chi"]}


_double.variables = ["a"]


def test_a_new_sweep_store_must_be_named_zarr(tmp_path, capsys, no_computing):
    line = _error(["sweep", "chi=60", "--out", tmp_path / "s.txt", "--no-progress"], capsys)
    assert line.startswith("flutterswim sweep: --out=") and "*.zarr" in line and "s.zarr" in line, line
    empty = tmp_path / "empty"
    empty.mkdir()  # an empty folder is no store either
    assert "*.zarr" in _error(["sweep", "chi=60", "--out", empty, "--no-progress"], capsys)
    assert sorted(os.listdir(tmp_path)) == ["empty"] and os.listdir(empty) == []


def test_our_sweep_store_resumes_whatever_its_name(tmp_path):
    from flutterswim.sweep import sweep

    first = sweep({"chi": [1.0, 2.0]}, out=str(tmp_path / "s.zarr"), backend="serial", point_fn=_double,
                  progress=False, max_points=1)
    assert int(first.attrs["n_done"]) == 1
    os.rename(tmp_path / "s.zarr", tmp_path / "renamed")  # ours (marker): resumed under any name
    ds = sweep({"chi": [1.0, 2.0]}, out=str(tmp_path / "renamed"), backend="serial", point_fn=_double,
               progress=False)
    assert ds["a"].values.tolist() == [2.0, 4.0]


# ------------------------------------------------- 5. plot-sweep draws each store to its own figure
def test_plot_sweep_default_figure_is_named_after_the_store(tmp_path, capsys, monkeypatch):
    """Two stores in one folder: each figure beside its store, named after it (it was sweep.png
    in the current folder for both, the second replacing the first)."""
    from test_sweep_plot_cli import fake  # swims above kappa_E_ratio 0.7

    from flutterswim.sweep import sweep

    pytest.importorskip("matplotlib")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "runs").mkdir()
    figures = []
    for name, values in (("resume3.zarr", [0.8, 1.0, 1.2]), ("other.zarr", [0.5, 1.0, 1.6, 2.0])):
        store = tmp_path / "runs" / name
        sweep({"kappa_E_ratio": values}, out=str(store), backend="serial", point_fn=fake, progress=False)
        assert cli.main(["plot-sweep", str(store)]) == 0
        figures.append(tmp_path / "runs" / name.replace(".zarr", ".png"))
        assert f"figure: {figures[-1]}" in capsys.readouterr().out
    assert all(f.stat().st_size > 1000 for f in figures) and not (tmp_path / "sweep.png").exists()
    assert figures[0].read_bytes() != figures[1].read_bytes()


def test_stability_default_folder_works_in_a_fresh_folder(tmp_path, monkeypatch, capsys, no_computing):
    """Its default was out/stability: with no folder made for a missing parent, it failed
    wherever out/ did not exist."""
    monkeypatch.chdir(tmp_path)
    assert cli.main(["stability", "--quiet"]) == 1
    assert "AssertionError: computed" in capsys.readouterr().err  # past the checks
    assert os.listdir(tmp_path) == ["stability"]


# ------------------------------------------------------------------- 6. one line, once
@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    p = tmp_path_factory.mktemp("runs") / "short.nc"
    fs.simulate(fs.PAPER, 0.3, n_segments=8).save(p)
    return p


@pytest.mark.parametrize("value", ["0", "0.0", "-0", "nan"])
def test_describe_bad_period_is_the_only_line(short_run, capsys, value):
    """--period 0 printed numpy's 'invalid value encountered in divide' warning first."""
    line = _error(["describe", short_run, "--period", value], capsys)
    assert line.startswith("flutterswim describe: --period=") and "warning" not in line, line


def test_describe_note_is_printed_once_on_stderr_in_both_modes(tmp_path, capsys):
    """The table printed the note on stdout and again on stderr; JSON mode has it in the JSON
    and once on stderr."""
    run = fs.simulate(fs.PAPER, 3.0, n_segments=8)  # still growing: not settled
    run.save(tmp_path / "mid.nc")
    note = fs.describe(run, n_last=2).note
    assert note
    for mode in ([], ["--json"]):
        assert cli.main(["describe", str(tmp_path / "mid.nc"), "--last", "2", *mode]) == 0
        out, err = capsys.readouterr()
        assert err.splitlines() == [f"flutterswim describe: note: {note}"]
        assert note not in out if not mode else json.loads(out)["note"] == note


# --------------------------------------------------- 7. the CLI names options, not API arguments
def test_branch_warning_names_the_steps_option(tmp_path, capsys):
    """8 steps per period are too few for the gauge: the API warns "(steps=)", the CLI "--steps"."""
    rc = cli.main(["branch", "kappa_E_ratio=0.7:0.8", "--points", "3", "--segments", "8", "--steps", "8",
                   "--out", str(tmp_path / "b.nc"), "--quiet"])
    err = capsys.readouterr().err
    warned = [ln for ln in err.splitlines() if "warning" in ln]
    assert rc == 0 and len(warned) == 1 and "8 steps per period" in warned[0], err
    assert "(--steps)" in warned[0] and "steps=" not in warned[0]


def test_fit_names_segments_once(tmp_path, capsys):
    trials = tmp_path / "t.csv"
    trials.write_text("voltage_V,sample,period_s,advance_mm,lateral_mm\n85,1,0.5,0.4,1.1\n85,2,0.52,0.41,1.12\n")
    line = _error(["fit", trials, "--segments", "1", "--out", tmp_path / "f.json"], capsys)
    assert "--segments=1 must be an integer in [8, 512]" in line and line.count("--segments") == 1, line


def test_reproduce_into_a_folder_of_other_files_names_a_reproduce_folder(tmp_path, capsys):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("mine")
    line = _error(["reproduce", "--out", tmp_path / "mine", "--only", "table1"], capsys)
    assert "not a flutterswim reproduce folder" in line and "flutterswim store" not in line, line
    assert "store name" not in line, line
    assert "the name of a new reproduce folder" in line and os.listdir(tmp_path / "mine") == ["notes.txt"]


def test_track_and_track_batch_say_fps_and_pattern_as_options(tmp_path, capsys):
    """A TIFF stack records no frame rate: track said "give fps", track-batch's failure too; a
    trial whose name the pattern misses said "or give a pattern"."""
    pytest.importorskip("skimage")
    tifffile = pytest.importorskip("tifffile")
    import csv

    import numpy as np

    frames = np.random.default_rng(0).poisson(100, (6, 24, 24)).astype(np.uint16)
    (tmp_path / "trials").mkdir()
    for name in ("85V_sample1.tif", "trialA.tif"):
        tifffile.imwrite(tmp_path / "trials" / name, frames, photometric="minisblack")
    line = _error(["track", tmp_path / "trials" / "trialA.tif", "--px-per-mm", "70", "--out", tmp_path / "t.nc",
                   "--quiet"], capsys)
    assert "give --fps (frames per second)" in line, line
    out = tmp_path / "trials.csv"
    assert cli.main(["track-batch", str(tmp_path / "trials"), "--px-per-mm", "70", "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    with open(tmp_path / "trials_failed.csv") as f:
        reasons = {os.path.basename(r["trial"]): r["reason"] for r in csv.DictReader(f)}
    assert "give --fps, or fps or times in the trial's sidecar" in reasons["85V_sample1.tif"]
    assert "or give --pattern" in reasons["trialA.tif"]
    assert all(r in err for r in reasons.values()) and "give fps" not in err and "a pattern;" not in err


# ------------------------------------------------------------ 8. subpackages without an import
def test_subpackages_resolve_lazily_and_sweep_keeps_its_meaning():
    """``import flutterswim as fs; fs.tracking.render`` raised AttributeError until
    ``import flutterswim.tracking``; fs.sweep stays what it was (no attribute until the
    subpackage is imported; the function is fs.run_sweep)."""
    import subprocess
    import sys

    code = """
import sys
import flutterswim as fs
assert "flutterswim.tracking" not in sys.modules
got = fs.tracking.render
from flutterswim.tracking.render import render
assert got is render
assert fs.steering.steer.__module__.startswith("flutterswim.steering")
assert callable(fs.fitting.read_trials) and callable(fs.orbits.hopf_point) and callable(fs.plotting.plot_ghosts)
assert fs.stability.__name__ == "flutterswim.stability" and fs.analysis.describe is fs.describe
try:
    fs.sweep
except AttributeError:
    pass
else:
    raise AssertionError("fs.sweep resolved before flutterswim.sweep was imported")
import flutterswim.sweep
assert fs.sweep is sys.modules["flutterswim.sweep"] and fs.run_sweep is flutterswim.sweep.sweep
try:
    fs.nonexistent
except AttributeError as exc:
    assert "nonexistent" in str(exc)
print("ok")
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                       env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr


# ----------------------------------------------------------- 9. the README says what the API does
def test_readme_numbers_match_the_api_defaults():
    """The orbit example's timing was quoted at N = 24 while it runs at the default N = 48; the
    README said describe averages 15 cycles while describe(run) averages n_last=5."""
    import inspect
    import re
    from pathlib import Path

    from flutterswim.analysis.descriptors import describe
    from flutterswim.orbits.periodic import DEFAULT_SEGMENTS

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    line = next(ln for ln in readme.splitlines() if "periodic_orbit(PAPER.replace(" in ln)
    assert re.search(r"ms at N = (\d+)", line).group(1) == str(DEFAULT_SEGMENTS), line
    said = re.search(r"`describe\(run\)` averages the last `n_last=(\d+)` cycles", " ".join(readme.split()))
    assert said and int(said.group(1)) == inspect.signature(describe).parameters["n_last"].default


def test_a_switch_is_advised_as_typed():
    """A review: an all-noise movie's error ended "give --dark-line=True (--dark-line)", which
    argparse refuses ("ignored explicit argument 'True'"): --dark-line is a switch."""
    from flutterswim.cli import _as_typed, build_parser

    args = build_parser().parse_args(["track", "x.tif", "--px-per-mm", "70"])
    msg = _as_typed("too noisy a movie, or if the filament is darker than its background, give dark_line=True "
                    "(--dark-line)", args.command_parser)
    assert msg.endswith("give --dark-line") and "True" not in msg
    # the advice, typed, parses
    build_parser().parse_args(["track", "x.tif", "--px-per-mm", "70", msg.rsplit(" ", 1)[1]])
