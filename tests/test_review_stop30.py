"""Review findings (stop 30): the CLI names the option the user typed (not the Python API
parameter), reproduce --out on a file, blank lines and headers of a waypoints CSV, numbers
given as strings to simulate(), and an output folder that cannot be created."""

import importlib
import os

import numpy as np
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


# ------------------------------------------------------------------------- waypoints CSV
def _waypoints(tmp_path, text):
    from flutterswim.steering.path import waypoints_csv

    (tmp_path / "w.csv").write_text(text)
    return waypoints_csv(tmp_path / "w.csv", L)


@pytest.mark.parametrize("text", ["0,0\n5,0\n5,5\n\n", "0,0\n\n5,0\n5,5\n", "\n0,0\n5,0\n \n5,5\n\n\n",
                                  "x,y\n\n0,0\n5,0\n5,5\n", "X,Y\n0,0\n5,0\n\n5,5\n"])
def test_waypoints_skip_blank_lines_and_a_header(tmp_path, text):
    p = _waypoints(tmp_path, text)
    # the waypoints (0,0), (5,0), (5,5) body lengths: one corner at (5,0), 10 body lengths long
    assert p.length == pytest.approx(10 * L)
    assert np.allclose(p.points[p.corners], [[5 * L, 0.0]])
    assert np.allclose(p.points[[0, -1]], [[0.0, 0.0], [5 * L, 5 * L]])


@pytest.mark.parametrize("text, line, value", [("1,abc\n0,0\n5,0\n", "line 1", "'abc'"),
                                               ("0,zz\n5,0\n5,5\n", "line 1", "'zz'"),
                                               ("0,0\n\n5,abc\n5,5\n", "line 3", "'abc'"),
                                               ("x,y\n0,0\n7\n5,5\n", "line 3", "'7'")])
def test_waypoints_first_row_with_a_number_is_data(tmp_path, text, line, value):
    with pytest.raises(ParameterError, match=f"{line}: {value}"):
        _waypoints(tmp_path, text)


def test_steer_refuses_a_bad_first_waypoint_row(tmp_path, capsys, no_computing):
    (tmp_path / "w.csv").write_text("1,abc\n0,0\n5,0\n")
    line = _error(["steer", "--path", "waypoints", "--waypoints", tmp_path / "w.csv", "--out", tmp_path / "s.nc",
                   "--metrics", tmp_path / "s.json", "--quiet"], capsys)
    assert "--waypoints=" in line and "line 1" in line and "'abc'" in line
    assert not (tmp_path / "s.nc").exists() and not (tmp_path / "s.json").exists()


# ------------------------------------------------------------- simulate(): numbers as numbers
@pytest.mark.parametrize("name, kw", [
    ("t_end", {"t_end": "0.01"}), ("t_end", {"t_end": True}), ("t_end", {"t_end": np.bool_(True)}),
    ("t_start", {"t_start": "0"}), ("rtol", {"rtol": "1e-3"}), ("atol", {"atol": True}),
    ("frame_dt", {"frame_dt": "0.001"}), ("max_step", {"max_step": "0.01"}), ("field", {"field": "0.5"}),
    ("field", {"field": False}),
])
def test_simulate_refuses_numbers_given_as_strings_or_bools(name, kw):
    kw = {"t_end": 0.01, **kw}
    with pytest.raises(ParameterError, match=rf"^{name}=.* not a number"):
        fs.simulate(fs.PAPER, kw.pop("t_end"), n_segments=6, **kw)


def test_simulate_takes_a_number_not_its_text():
    """t_end "0.01" is refused; the same number as numpy scalars (of every argument) is taken."""
    with pytest.raises(ParameterError, match="t_end='0.01'"):
        fs.simulate(fs.PAPER, "0.01", n_segments=6)
    run = fs.simulate(fs.PAPER, np.float64(0.01), n_segments=np.int64(6), rtol=np.float32(1e-4),
                      field=np.float64(0.1), frame_dt=0.005, max_step=1)
    assert run.ok and run.t[-1] == pytest.approx(0.01)


# ------------------------------------------------------------------ an output folder that cannot be made
@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs /proc")
@pytest.mark.parametrize("out, words", [
    ("/proc/x.nc", "the folder '/proc' is not writable; no file can be created in it"),
    ("/proc/new/x.nc", "the folder '/proc/new' does not exist; create it first"),  # (never created now)
])
def test_an_output_folder_that_cannot_be_written_is_named(capsys, no_computing, out, words):
    line = _error(["simulate", "--t-end", "1", "--out", out, "--quiet"], capsys)
    assert words in line and "No such file" not in line, line


def test_waypoints_header_units(tmp_path):
    """A header naming a unit (x_mm,y_mm; x [um]) gives the numbers in that unit; without one
    they are in ``scale`` (body lengths); two different units are refused; a name merely ending
    in m (item, xm) is not a unit."""
    from flutterswim.steering.path import waypoints_csv

    p = tmp_path / "w.csv"
    L = 3.7e-3
    for header, metres in (("x,y", L), ("x_mm,y_mm", 1e-3), ("x [um],y [um]", 1e-6), ("x (mm),y (mm)", 1e-3),
                           ("X_m,Y_m", 1.0), ("item,xm", L), ("x_cm,y_cm", 1e-2), ("x_bl,y_bl", L),
                           # words of the name, not units (refused for a while this stop)
                           ("pos_x,pos_y", L), ("x_pos,y_pos", L), ("x position,y position", L), ("X (-),Y (-)", L),
                           ("x (body lengths),y (body lengths)", L)):
        p.write_text(f"{header}\n0,0\n3,4\n")
        assert waypoints_csv(p, L).length == pytest.approx(5 * metres, rel=1e-6), header
    p.write_text("x_mm,y_um\n0,0\n3,4\n")
    with pytest.raises(ParameterError, match="different units"):
        waypoints_csv(p, L)
    # a unit not known is refused, not read as body lengths (x_furlong and x [in] were)
    for header in ("x_furlong,y_furlong", "x [in],y [in]", "x_km,y_km"):
        p.write_text(f"{header}\n0,0\n3,4\n")
        with pytest.raises(ParameterError, match=r"not allowed; allowed: m, cm, mm, um"):
            waypoints_csv(p, L)


def test_hopf_point_repr_is_short():
    """A notebook printing a HopfPoint shows its numbers, not its Jacobian (97 x 97 at N = 48)."""
    from flutterswim.orbits import hopf_point

    h = hopf_point(fs.PAPER, n_segments=12)
    r = repr(h)
    assert "value=" in r and "omega=" in r and "array(" not in r and len(r) < 1000
