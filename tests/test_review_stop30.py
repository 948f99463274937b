"""Review findings (stop 30): the CLI names the option the user typed (not the Python API
parameter), reproduce --out on a file, blank lines and headers of a waypoints CSV, numbers
given as strings to simulate(), and an output folder that cannot be created."""

import importlib
import os

import pytest

import flutterswim as fs
from flutterswim import cli
from flutterswim._validate import ParameterError

L = fs.PAPER.l


@pytest.fixture()
def no_computing(monkeypatch):
    """A steer command must stop at its checks: identifying the swimmer (the first computation,
    ~20 s) fails the test."""
    def computed(*a, **kw):
        raise AssertionError("computed before the input was checked")

    monkeypatch.setattr(importlib.import_module("flutterswim.steering.reduced"), "identify", computed)


def _error(argv, capsys):
    status = cli.main([str(a) for a in argv])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert status == 2 and len(err) == 1, (status, err)
    return err[0]


# ------------------------------------------------------------------- the option the user typed
@pytest.mark.parametrize("argv, typed, api", [
    (["track", "{tmp}/m.tif", "--px-per-mm", "-3", "--fps", "50", "--out", "{tmp}/t.nc"], "--px-per-mm=-3", "px_per_mm"),
    (["reproduce", "--out", "{tmp}/rp", "--only", "bogus"], "--only=['bogus']", "targets="),
    (["simulate", "--segments", "1", "--t-end", "1", "--out", "{tmp}/r.nc", "--quiet"], "--segments=1", "n_segments"),
    (["steer", "--segments", "5", "--out", "{tmp}/s.txt", "--metrics", "{tmp}/s.json"], "--out=", " out="),
    (["sweep", "chi=60", "--out", "{tmp}/b.zarr", "--n-segments", "2", "--no-progress"], "--n-segments=2",
     "n_segments"),
    (["steer", "--path", "waypoints", "--waypoints", "{tmp}/missing.csv", "--out", "{tmp}/s.nc", "--metrics",
      "{tmp}/s.json"], "--waypoints=", " waypoints="),
])
def test_cli_names_the_option_typed(tmp_path, capsys, no_computing, argv, typed, api):
    line = _error([a.format(tmp=tmp_path) for a in argv], capsys)
    assert f": {typed}" in line and api not in line, line
    assert sorted(os.listdir(tmp_path)) == []  # nothing written


@pytest.mark.parametrize("option, value, typed", [("--last", "0", "--last=0 "), ("--period", "-1", "--period=-1")])
def test_describe_names_its_option_not_the_file(tmp_path, capsys, option, value, typed):
    """A bad option of describe is named as typed, not as an error of the run file."""
    fs.simulate(fs.PAPER, 0.3, n_segments=8).save(tmp_path / "r.nc")
    line = _error(["describe", tmp_path / "r.nc", option, value], capsys)
    assert f"describe: {typed}" in line and "r.nc" not in line, line


def test_api_messages_keep_their_parameter_names(tmp_path, capsys):
    """The same bad value: the API names its parameter, the CLI its option; where a command has
    no such option (animate's positional out) the name stays."""
    with pytest.raises(ParameterError, match=r"^n_segments=1 "):
        fs.simulate(fs.PAPER, 1.0, n_segments=1)
    line = _error(["simulate", "--segments", "1", "--t-end", "1", "--out", tmp_path / "r.nc"], capsys)
    assert "flutterswim simulate: --segments=1 " in line
    line = _error(["animate", tmp_path / "r.nc", tmp_path / "v.txt"], capsys)
    assert f"animate: out='{tmp_path / 'v.txt'}'" in line
    line = _error(["steer", "--out", tmp_path / "v.txt", "--metrics", tmp_path / "s.json"], capsys)
    assert f"steer: --out='{tmp_path / 'v.txt'}'" in line


# ---------------------------------------------------------------------- reproduce --out on a file
def test_reproduce_out_on_a_file_says_the_folder_is_a_file(tmp_path, capsys):
    f = tmp_path / "notes.txt"
    f.write_text("mine")
    line = _error(["reproduce", "--out", f, "--only", "table1"], capsys)
    assert "is an existing file, not an output folder" in line and "store" not in line, line
    assert f.read_text() == "mine"
    # the sweep's own message is unchanged
    line = _error(["sweep", "chi=60", "--out", f], capsys)
    assert "is an existing file, not a sweep store" in line and f.read_text() == "mine"
