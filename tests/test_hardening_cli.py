"""The CLI: one line, no traceback, exit 2 for bad input; --version, python -m flutterswim,
negative numbers after options, --cycles with --t-end, output paths checked before computing."""

import subprocess
import sys

import numpy as np
import pytest

import flutterswim as fs


def _cli(*args, cwd=None, timeout=120):
    return subprocess.run([sys.executable, "-m", "flutterswim", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout)


def _one_line_error(out, status=2):
    assert out.returncode == status, (out.returncode, out.stderr)
    assert "Traceback" not in out.stderr
    lines = [ln for ln in out.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, out.stderr
    return lines[0]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    rng = np.random.default_rng(1)
    (d / "random.nc").write_bytes(rng.bytes(5000))
    (d / "empty.nc").write_bytes(b"")
    import xarray as xr

    xr.Dataset({"a": ("x", np.arange(3.0), {"units": "1"})}).to_netcdf(d / "other.nc", engine="h5netcdf")
    run = fs.simulate(fs.PAPER, 0.3, n_segments=8)
    run.save(d / "run.nc")
    (d / "truncated.nc").write_bytes((d / "run.nc").read_bytes()[:3000])
    return d


BAD_FILES = [("missing.nc", "does not exist"), ("random.nc", "not a NetCDF"),
             ("other.nc", "not a flutterswim run"), ("empty.nc", "is empty"), ("truncated.nc", "cannot be read")]


@pytest.mark.parametrize("name, words", BAD_FILES)
@pytest.mark.parametrize("command", ["describe", "plot"])
def test_bad_run_files_give_one_line_and_status_2(files, name, words, command, capsys):
    from flutterswim.cli import main

    status = main([command, str(files / name)])  # in process: main must not raise
    err = capsys.readouterr().err
    assert status == 2 and "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and name in lines[0] and words in lines[0]


def test_bad_run_file_in_a_real_process(files):
    line = _one_line_error(_cli("describe", files / "random.nc", cwd=files))
    assert "random.nc" in line and "not a NetCDF" in line


def test_directory_as_run_and_as_out(files):
    assert "directory" in _one_line_error(_cli("describe", files))
    line = _one_line_error(_cli("simulate", "--t-end", "0.1", "--out", files, "--quiet"))
    assert "is a directory" in line


def test_version_and_module_entry():
    a = _cli("--version")
    assert a.returncode == 0 and a.stdout.strip() == f"flutterswim {fs.__version__}"
    b = subprocess.run([sys.executable, "-m", "flutterswim", "--help"], capture_output=True, text=True)
    assert b.returncode == 0 and "simulate" in b.stdout


def test_negative_number_after_option_is_a_value(tmp_path):
    line = _one_line_error(_cli("simulate", "--rtol", "-1e-4", "--t-end", "1", "--out", tmp_path / "r.nc",
                                "--quiet"))
    assert "rtol=-0.0001" in line and "> 0" in line
    assert not (tmp_path / "r.nc").exists()


def test_cycles_with_t_end_is_refused(tmp_path):
    line = _one_line_error(_cli("simulate", "--cycles", "3", "--t-end", "1", "--out", tmp_path / "r.nc"))
    assert "--cycles" in line and "--t-end" in line


@pytest.mark.parametrize("out, words", [("/proc/run.nc", "not writable"), ("run.txt", "suffix")])
def test_output_checked_before_computing(tmp_path, out, words):
    # t_end long enough that a computation before the check would take minutes
    r = _cli("simulate", "--t-end", "1000", "--out", out, "--quiet", cwd=tmp_path, timeout=30)
    assert words in _one_line_error(r)


def test_unknown_option_is_one_line():
    line = _one_line_error(_cli("simulate", "--bogus"))
    assert "--bogus" in line


def test_debug_shows_the_traceback(files):
    r = _cli("--debug", "describe", files / "random.nc")
    assert r.returncode == 2 and "Traceback" in r.stderr


def test_describe_without_limit_cycle_says_so(tmp_path):
    fs.simulate(fs.PAPER, 4.0, n_segments=12).save(tmp_path / "onset.nc")  # still in onset at 4 s
    r = _cli("describe", tmp_path / "onset.nc")
    assert r.returncode == 0 and "describe: note: no limit cycle" in r.stderr  # once, on stderr (as --json)
    j = _cli("describe", tmp_path / "onset.nc", "--json")
    import json

    d = json.loads(j.stdout)
    assert d["limit_cycle"] is False and "no limit cycle" in d["note"]
    assert d["limit_cycle_time_s"] is None and d["onset_time_s"] is None


def test_a_missing_optional_package_names_its_extra(tmp_path, monkeypatch, capsys):
    """A command whose optional package is absent says, in one line, which extra brings it, and
    every extra named is one of pyproject.toml's that lists that package."""
    import re
    import tomllib
    from pathlib import Path

    from flutterswim import cli

    pyproject = Path(__file__).resolve().parents[1] / "pyproject.toml"
    extras = tomllib.loads(pyproject.read_text())["project"]["optional-dependencies"]
    pip_name = {"skimage": "scikit-image", "imageio_ffmpeg": "imageio-ffmpeg", "distributed": "dask"}
    for module, extra in cli._EXTRA_OF.items():
        wanted = pip_name.get(module, module)
        names = [re.split(r"[\[<>=!~ ]", req)[0] for req in extras[extra]]
        assert wanted in names, (module, extra, extras[extra])

    # the progress bars' tqdm is a core dependency (the default bars needed the cli extra)
    core = [re.split(r"[\[<>=!~ ]", req)[0] for req in tomllib.loads(pyproject.read_text())["project"]["dependencies"]]
    assert "tqdm" in core and "tqdm" not in cli._EXTRA_OF
    monkeypatch.setitem(sys.modules, "numba", None)  # import numba now raises ModuleNotFoundError
    exc = ModuleNotFoundError("No module named 'numba'", name="numba")
    status, msg = cli._describe_error(exc)
    assert status == 1 and "'numba'" in msg and "flutterswim[fast]" in msg, msg


def test_saving_a_run_without_xarray_names_the_extra(tmp_path, monkeypatch):
    """The API's save and load, without xarray: a ModuleNotFoundError that names the extra (and
    keeps the module's name, which the CLI turns into its one line)."""
    r = fs.simulate(fs.PAPER, 0.05, n_segments=12)
    monkeypatch.setitem(sys.modules, "xarray", None)
    for call in (lambda: r.save(tmp_path / "r.nc"), lambda: fs.load(tmp_path / "r.nc")):
        with pytest.raises(ModuleNotFoundError, match=r"flutterswim\[io\]") as info:
            call()
        assert info.value.name == "xarray"


def test_interrupt_inside_a_compiled_kernel_exits_130(monkeypatch, capsys):
    """Ctrl-C inside a numba kernel surfaces as a SystemError whose context is the interrupt:
    exit 130 and 'interrupted', not 'failed: SystemError' with status 1."""
    from flutterswim import cli

    def kernel_interrupted(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise SystemError("CPUDispatcher(<function jacobian>) returned a result with an exception set")  # noqa: B904 - the implicit context, as numba leaves it

    monkeypatch.setattr(cli, "_describe", kernel_interrupted)
    assert cli.main(["describe", "x.nc"]) == 130
    assert "interrupted" in capsys.readouterr().err
    from flutterswim._interrupt import interrupted

    assert not interrupted(SystemError("no interrupt here"))


def test_negative_roi_is_a_value_not_an_option():
    from flutterswim.cli import build_parser

    a = build_parser().parse_args(["track", "m.tif", "--px-per-mm", "70", "--roi", "-5,0,100,100", "--out", "o.nc"])
    assert a.roi == "-5,0,100,100"


def test_tracked_movie_animates_and_a_too_short_one_is_named(tmp_path):
    """``animate`` takes a tracked movie as ``plot`` and ``describe`` do; describing a track of
    three frames names the file in its one line."""
    from types import SimpleNamespace

    from flutterswim.tracking import render, track
    from flutterswim.tracking.netcdf import save_track

    run = fs.simulate(fs.PAPER, 0.3, n_segments=8, frame_dt=0.02)
    mv = render(SimpleNamespace(t=run.t, x=run.x, y=run.y), um_per_px=14.0, snr=10.0, seed=0)
    save_track(track(mv, px_per_mm=mv.px_per_mm, fps=50.0, periodic=False), tmp_path / "t.nc")
    out = _cli("animate", tmp_path / "t.nc", tmp_path / "t.gif", "--quiet")
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "t.gif").stat().st_size > 0
    save_track(track(mv.frames[:3], px_per_mm=mv.px_per_mm, fps=50.0, periodic=False), tmp_path / "t3.nc")
    line = _one_line_error(_cli("describe", tmp_path / "t3.nc"))
    assert "t3.nc" in line


@pytest.mark.parametrize("delay", [0.15, 0.35, 0.6])
def test_ctrl_c_while_the_command_starts_is_one_line_and_130(tmp_path, delay):
    """A review: a Ctrl-C in the first half second (numpy, scipy and the subcommands loading)
    printed a Python traceback. The entry point imports the package inside its own handler."""
    import signal
    import subprocess
    import sys
    import time

    code = "import sys, flutterswim_entry; sys.argv[0] = 'flutterswim'; sys.exit(flutterswim_entry.main())"
    # (SIGINT's default restored: a test run in a background job inherits it ignored, and Python
    # then never raises KeyboardInterrupt)
    proc = subprocess.Popen([sys.executable, "-c", code, "reproduce", "--out", str(tmp_path / "r"), "--only", "table1"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    if proc.returncode == 0:  # finished before the signal (a fast machine): nothing to test
        pytest.skip("the command finished before the interrupt")
    assert proc.returncode == 130, err
    # (on a quiet machine the command may have started its build, whose progress line comes first)
    said = [ln for ln in err.strip().splitlines() if not ln.startswith("reproduce: ")]
    assert "Traceback" not in err and len(said) == 1 and "interrupted" in said[0]


def test_ctrl_c_while_a_compiled_module_initialises_is_one_line_and_130(monkeypatch, capsys):
    """A Ctrl-C that lands while a compiled extension initialises (scipy's HiGHS, met in a CI
    run of the test above) surfaces as "ImportError: initialization failed" with the interrupt
    as its cause: it printed a traceback and exited 1. An ImportError of another cause is not
    an interrupt."""
    import flutterswim_entry
    from flutterswim import cli

    def interrupted_import():
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as ki:
            raise ImportError("initialization failed") from ki

    monkeypatch.setattr(cli, "build_parser", interrupted_import)
    assert cli.main(["simulate"]) == 130
    err = capsys.readouterr().err
    assert err == "flutterswim: interrupted\n"
    with pytest.raises(ImportError):
        monkeypatch.setattr(cli, "build_parser", lambda: (_ for _ in ()).throw(ImportError("no module")))
        cli.main(["simulate"])
    try:
        interrupted_import()
    except ImportError as exc:
        assert flutterswim_entry.interrupted(exc)
    assert not flutterswim_entry.interrupted(ImportError("no module"))


def test_the_field_angle_is_spelt_alike_in_every_command():
    """simulate had --field-angle, track --field-angle-deg (a review): both take both."""
    from flutterswim.cli import build_parser

    ap = build_parser()
    for opt in ("--field-angle", "--field-angle-deg"):
        assert ap.parse_args(["track", "x.tif", "--px-per-mm", "70", opt, "30"]).field_angle_deg == 30.0
        assert ap.parse_args(["track-batch", "d", opt, "30"]).field_angle_deg == 30.0
        assert ap.parse_args(["simulate", "--t-end", "3", opt, "30"]).field_angle == 30.0


def test_an_interrupt_is_one_line_even_when_objects_finalise_with_errors(tmp_path):
    """Ctrl-C during a NetCDF save left h5netcdf's file half-closed; its finaliser's error was
    printed as 'Exception ignored in ...' (26 lines) after the one-line message."""
    import subprocess
    import sys

    script = tmp_path / "s.py"
    script.write_text(
        "import sys, importlib\n"
        "cli = importlib.import_module('flutterswim.cli')\n"
        "class HalfClosed:\n"
        "    def __del__(self):\n"
        "        raise KeyError('Unable to synchronously open object')\n"
        "def interrupted_save(*a, **k):\n"
        "    h = HalfClosed(); h.me = h  # a cycle: finalised by the collector, at exit\n"
        "    raise KeyboardInterrupt\n"
        "sim = importlib.import_module('flutterswim.simulate')\n"
        "sim.simulate = interrupted_save\n"
        "sys.argv = ['flutterswim', 'simulate', '--t-end', '0.1', '--quiet', '--out', sys.argv[1]]\n"
        "raise SystemExit(cli.main())  # as the command runs it\n")
    r = subprocess.run([sys.executable, str(script), str(tmp_path / "x.nc")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 130, r.stderr
    assert r.stderr.strip().splitlines() == ["flutterswim simulate: interrupted"], r.stderr
    # called in a process that goes on (a notebook, a test), the hook is left as it was
    import importlib

    cli = importlib.import_module("flutterswim.cli")
    hook = sys.unraisablehook

    def interrupted(args):
        raise KeyboardInterrupt

    import pytest as _pytest

    with _pytest.MonkeyPatch.context() as mp:
        mp.setattr(importlib.import_module("flutterswim.simulate"), "simulate", lambda *a, **k: interrupted(None))
        assert cli.main(["simulate", "--t-end", "0.1", "--quiet", "--out", str(tmp_path / "y.nc")]) == 130
    assert sys.unraisablehook is hook


def test_an_interrupt_names_the_files_already_replaced(tmp_path):
    """A command writing several files (stability: map, figures, modes), interrupted half way,
    left new files beside old ones and said only 'interrupted'. It now names those it wrote."""
    import subprocess
    import sys

    script = tmp_path / "s.py"
    script.write_text(
        "import sys, importlib\n"
        "cli = importlib.import_module('flutterswim.cli')\n"
        "from flutterswim._paths import atomic_write_text\n"
        "def half_done(*a, **k):\n"
        "    atomic_write_text(sys.argv[1], 'new map')\n"
        "    raise KeyboardInterrupt\n"
        "sim = importlib.import_module('flutterswim.simulate')\n"
        "sim.simulate = half_done\n"
        "raise SystemExit(cli.main(['simulate', '--t-end', '0.1', '--quiet', '--out', sys.argv[2]]))\n")
    first = tmp_path / "map.txt"
    r = subprocess.run([sys.executable, str(script), str(first), str(tmp_path / "x.nc")], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 130 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert f"interrupted; written before the interrupt: {first}" in r.stderr, r.stderr
    assert first.read_text() == "new map" and not (tmp_path / "x.nc").exists()
