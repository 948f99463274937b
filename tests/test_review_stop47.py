"""Stop 47: items left at stop 46."""

import pytest

import flutterswim as fs
from flutterswim.orbits.linear import hopf_point


@pytest.mark.parametrize("factor", [60.0, 1 / 60.0])
def test_the_hopf_search_finds_the_point_from_far_away(factor):
    """From a sweep point far past onset (kappa_E 60 times the paper's, chi = 4242) the search
    said there was no Hopf point for chi between 84.8 and 212010; the one at 48.3 lies a sixtieth
    below. The Hopf point does not depend on where the search starts."""
    near = hopf_point(fs.PAPER, "chi", n_segments=12).value
    far = hopf_point(fs.PAPER.replace(kappa_E=factor * fs.PAPER.kappa_E), "chi", n_segments=12).value
    assert far == pytest.approx(near, rel=1e-9)


def test_a_file_size_limit_while_saving_is_a_failure_not_a_crash(tmp_path):
    """HDF5 writing onto a full disk or past a file size limit (ulimit -f, a quota) crashed
    Python with a segmentation fault (exit 139) after the OSError: in a notebook the kernel and
    everything in it was lost. The file is now built in memory and written by Python: exit 1,
    one line, no partial file, and the error is an OSError in the API."""
    import resource
    import subprocess
    import sys

    cmd = [sys.executable, "-m", "flutterswim", "simulate", "--t-end", "3", "--segments", "12", "--quiet"]
    full = subprocess.run([*cmd, "--out", str(tmp_path / "full.nc")], capture_output=True, text=True, timeout=300)
    assert full.returncode == 0, full.stderr
    size = (tmp_path / "full.nc").stat().st_size
    (tmp_path / "limited").mkdir()

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (size // 2, size // 2))

    r = subprocess.run([*cmd, "--out", str(tmp_path / "limited" / "r.nc")], capture_output=True, text=True,
                       timeout=300, preexec_fn=limit)
    assert r.returncode == 1, (r.returncode, r.stderr)
    assert len(r.stderr.strip().splitlines()) == 1 and "File too large" in r.stderr
    assert list((tmp_path / "limited").iterdir()) == []


@pytest.mark.parametrize("lost", [45, 70])
def test_tracking_picks_the_body_up_after_a_long_loss(lost):
    """After about 0.9 s of lost frames (blank, or contrast faded away) every later frame was
    refused as "jump: the body moved 78 px since the last good frame": the swimmer had only
    swum on. The tolerance is per frame since the last good one; every frame that is not blank
    is tracked, with its ends in place (a swap puts a tip a body length, 71 px, off)."""
    from types import SimpleNamespace

    import numpy as np

    from flutterswim.tracking import render, track

    r = fs.simulate(fs.PAPER, 12.0, n_segments=24, frame_dt=1.0 / 50)
    sl = slice(r.t.size - 150, r.t.size)
    sim = SimpleNamespace(t=r.t[sl], x=r.x[sl], y=r.y[sl])
    mv = render(sim, um_per_px=14.0, snr=5.0, seed=9)
    frames = mv.frames.copy()
    bg = float(np.median(frames[0]))
    blank = np.zeros(frames.shape[0], bool)
    blank[40:40 + lost] = True
    frames[blank] = np.random.default_rng(lost).normal(bg, 3.0, frames[blank].shape)
    tr = track(frames, px_per_mm=mv.px_per_mm, fps=50.0)
    ok = np.asarray(tr.meta["frames"]["ok"])
    assert np.array_equal(ok, ~blank), [m for m in tr.meta["frames"]["reason"] if m][:3]
    from flutterswim.tracking.evaluate import pixel_errors

    _, E, _ = pixel_errors(tr, mv)  # a swap shows as a body length
    assert E.max() < 1.0


def test_a_time_beyond_a_float_in_units_of_tau_is_bad_input(tmp_path, capsys):
    """--t-end 1.7e308 (infinite in units of tau) crashed with an OverflowError (exit 1), and
    the API called 1e308 "within round-off of t_start"."""
    from flutterswim.cli import main

    assert main(["simulate", "--t-end", "1.7e308", "--out", str(tmp_path / "x.nc")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--t-end" in err and "at most" in err
    with pytest.raises(fs.ParameterError, match="span more than a float holds"):
        fs.simulate(fs.PAPER, 1e308)
    assert not list(tmp_path.iterdir())


def test_a_bad_matplotlib_backend_in_the_environment_is_bad_input(tmp_path):
    """MPLBACKEND=nosuch failed as "ValueError: Key backend ..." with exit 1: it is a bad
    environment value, named, exit 2."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "MPLBACKEND": "nosuch"}
    run = fs.simulate(fs.PAPER, 3.0, n_segments=8).save(tmp_path / "r.nc")
    r = subprocess.run([sys.executable, "-m", "flutterswim", "plot", str(run), "--out",
                        str(tmp_path / "f.png")], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "MPLBACKEND='nosuch'" in r.stderr and not (tmp_path / "f.png").exists()
    # a command that draws nothing runs whatever it says (a review: describe had been refused)
    r = subprocess.run([sys.executable, "-m", "flutterswim", "describe", str(run)], capture_output=True, text=True,
                       env=env, timeout=120)
    assert "MPLBACKEND" not in r.stderr and "Traceback" not in r.stderr


def test_the_kernel_cache_falls_back_to_a_temporary_folder(tmp_path, monkeypatch):
    """With a home that cannot hold a cache (read-only on an HPC node or in a container) the
    cache folder was left to numba, which on a read-only install had nowhere to write: every
    run failed ("cannot cache function ...: no locator available"). It now falls back to a
    temporary folder of the user's."""
    pytest.importorskip("numba")
    import tempfile

    from numba.core import config

    from flutterswim import _jit

    home = tmp_path / "home"
    home.write_text("not a folder")  # (mkdir under it fails, root or not)
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(config, "CACHE_DIR", config.CACHE_DIR)  # (restored after the test)
    _jit._set_cache_dir()
    assert str(config.CACHE_DIR).startswith(str(tmp_path / "tmp")) and _jit._CACHE


def test_sigterm_ends_a_command_as_an_interrupt_does(tmp_path):
    """SIGTERM (kill, timeout, a batch system's time limit) killed the command at once: no
    line, and hidden partial files left that no later run removed. It now ends as Ctrl-C does,
    with one line, nothing left behind, and exit status 143."""
    import re
    import signal
    import subprocess
    import sys
    import time

    proc = subprocess.Popen([sys.executable, "-m", "flutterswim", "simulate", "--t-end", "600", "--segments", "12",
                             "--out", str(tmp_path / "r.nc")], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    first = proc.stderr.read(1)  # the progress bar: started and stepping (however long the imports took)
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, (proc.returncode, first + err)
    lines = [ln for ln in re.split(r"[\r\n]", err) if ln.strip()]
    assert lines[-1].startswith("flutterswim simulate: terminated (SIGTERM)"), err
    assert "Traceback" not in err and list(tmp_path.iterdir()) == []


def test_figures_are_not_written_into_a_sweep_store(tmp_path, capsys):
    """stability --out into a sweep store wrote its figures there; the store's own --overwrite
    then refused it as holding files it did not write."""
    from flutterswim.cli import main
    from flutterswim.sweep import sweep

    def point(task):
        return {"a": 1.0}

    point.variables = ["a"]
    store = tmp_path / "s.zarr"
    sweep({"chi": [1.0]}, out=str(store), backend="serial", point_fn=point, progress=False)
    before = sorted(p.name for p in store.iterdir())
    assert main(["stability", "--out", str(store), "--step", "2", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "flutterswim sweep folder" in err
    assert sorted(p.name for p in store.iterdir()) == before


def test_two_reproduce_runs_do_not_write_one_folder_at_once(tmp_path):
    """Each reproduce run keeps its manifest in memory: two at once in one folder lost each
    other's records (a full build of table1 recorded as quick). The second is refused."""
    from flutterswim._lock import acquire
    from flutterswim.reproduce import reproduce

    out = tmp_path / "rr"
    reproduce(out, targets=["table1"])
    before = sorted(p.name for p in out.iterdir())
    with acquire(out, kind="reproduce", noun="folder", inside=True):
        with pytest.raises(fs.ParameterError, match="another reproduce process"):
            reproduce(out, targets=["table1"], force=True)
    assert sorted(p.name for p in out.iterdir()) == before
    res = reproduce(out, targets=["table1"], force=True)  # (the lock is gone with its holder)
    assert res.report.is_file() and sorted(p.name for p in tmp_path.iterdir()) == ["rr"]
    assert not (out / ".lock").exists()


def _trials_csv(path, body_mm, volts=(85.0,), rows=3):
    lines = ["voltage_V,sample,period_s,advance_mm,lateral_mm,body_length_mm"]
    for v in volts:
        for k in range(rows):
            f = 1 + 0.01 * k
            lines.append(f"{v},{k},{0.377 * f},{0.394 * f},{1.13 * f},{body_mm}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_fit_checks_the_tracked_body_length_against_the_models(tmp_path, monkeypatch, capsys):
    """fit always took the paper's geometry and dropped the CSV's tracked body length: a 3 mm
    ribbon fitted as a 3.7 mm one gave B 187 % off, 7-160 sigma from the truth, exit 0. A body
    length more than 10 % off the model's l is refused, naming both and the options; the
    sample's geometry is given by --length-mm, --width-mm, --thickness-mm; 2-10 % is noted."""
    import importlib

    from flutterswim.cli import main
    from flutterswim.fitting.model import OutsideModel

    ff = importlib.import_module("flutterswim.fitting.fit")
    seen = []

    def stop(mean, sem, **kw):
        seen.append(kw["base"])
        raise OutsideModel("stopped by the test")

    monkeypatch.setattr(ff, "fit", stop)
    csv = _trials_csv(tmp_path / "t.csv", 3.0)
    assert main(["fit", str(csv), "--out", str(tmp_path / "f.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "3 mm" in err and "3.7 mm" in err and "--length-mm" in err
    assert seen == []
    assert main(["fit", str(csv), "--out", str(tmp_path / "f.json"), "--length-mm", "3", "--width-mm", "0.15"]) == 1
    assert seen[-1].l == pytest.approx(3e-3) and seen[-1].b == pytest.approx(0.075e-3)
    assert seen[-1].a == fs.PAPER.a and seen[-1].mu == fs.PAPER.mu
    capsys.readouterr()
    _trials_csv(csv, 3.7 * 1.05)  # 5 % off: noted, fitted
    assert main(["fit", str(csv), "--out", str(tmp_path / "f.json")]) == 1
    assert "note: the trials' tracked body length" in capsys.readouterr().err and seen[-1].l == fs.PAPER.l


def test_the_default_guess_is_the_papers_dimensionless_point_in_any_geometry():
    """Fitting a ribbon of another geometry from the paper's guess started below onset (no
    stroke at the start: "the data are outside what the model can reproduce"). The default
    guess keeps the paper guess's chi and eta_perp in the base's geometry."""
    from flutterswim.fitting.fit import PAPER_GUESS, default_guess

    B0, tau0, k0 = PAPER_GUESS
    ref = fs.PAPER.replace(B=B0, tau=tau0, kappa_E=k0).groups
    for change in ({"l": 3e-3, "b": 0.075e-3}, {"l": 5e-3}, {"mu": 2e-3, "a": 1e-5}):
        base = fs.PAPER.replace(**change)
        B, tau, k = default_guess(base)
        g = base.replace(B=B, tau=tau, kappa_E=k).groups
        assert g.chi == pytest.approx(ref.chi, rel=1e-12) and g.eta_perp == pytest.approx(ref.eta_perp, rel=1e-12)
    assert default_guess(fs.PAPER) == pytest.approx(PAPER_GUESS, rel=1e-15)


@pytest.mark.parametrize("column, value, words", [("advance_mm", 394.0, "advance_mm in millimetres"),
                                                  ("lateral_mm", 1130.0, "lateral_mm in millimetres"),
                                                  ("voltage_V", 0.085, r"in volts \(not kV\)")])
def test_descriptors_in_the_wrong_unit_are_warned_of(tmp_path, column, value, words):
    """Only periods in ms were warned of; a lateral of 1170 mm for a 3.7 mm body, an advance of
    376 mm, voltages of 0.08-0.1 went in without a word."""
    from flutterswim.fitting import read_trials

    row = {"voltage_V": 85.0, "sample": "a", "period_s": 0.377, "advance_mm": 0.394, "lateral_mm": 1.13}
    row[column] = value
    p = tmp_path / "t.csv"
    p.write_text(",".join(row) + "\n" + ",".join(str(v) for v in row.values()) + "\n")
    with pytest.warns(UserWarning, match=words):
        read_trials(p)


def test_an_uneven_background_is_named_when_it_breaks_tracking():
    """A bright hump of illumination (3 times the background) broke most frames into
    "crossing" and "gap", and nothing said the background might be the cause."""
    import math
    from types import SimpleNamespace

    import numpy as np

    from flutterswim.tracking import render, track

    r = fs.simulate(fs.PAPER, 10.0, n_segments=24, frame_dt=1 / 50, field=math.radians(37))
    sl = slice(r.t.size - 40, r.t.size)
    mv = render(SimpleNamespace(t=r.t[sl], x=r.x[sl], y=r.y[sl]), um_per_px=14.0, snr=4.0, seed=3)
    T, H, W = mv.frames.shape
    yy, xx = np.mgrid[0:H, 0:W]
    hump = 3 * float(np.median(mv.frames[0])) * np.exp(-((xx - 0.5 * W) ** 2 + (yy - 0.3 * H) ** 2) / (2 * 60 ** 2))
    with pytest.warns(UserWarning, match="background that is not a plane"):
        tr = track(mv.frames + hump[None].astype(np.float32), px_per_mm=mv.px_per_mm, fps=50)
    reasons = [m.split(":")[0] for m in tr.meta["frames"]["reason"] if m]
    assert reasons.count("crossing") + reasons.count("gap") > T // 2
    import warnings

    with warnings.catch_warnings():  # the clean movie: no such warning
        warnings.filterwarnings("error", message=".*background that is not a plane")
        track(mv.frames, px_per_mm=mv.px_per_mm, fps=50)


def _wave_body(t, x0, y0, U, L=60.0, period=25.0):
    """A 60 px travelling-wave body (head first) at frame t, its centre moving U px per frame."""
    import numpy as np

    s = np.linspace(0, L, 400)
    lat = (2.0 + 8.0 * (s / L) ** 2) * np.sin(2 * np.pi * s / (0.9 * L) - 2 * np.pi * t / period)
    bx, by = -s - (-s).mean(), lat - lat.mean()
    return np.stack([x0 + U * t + bx, y0 + by], 1)


def _line_frames(curves, shape=(200, 320), seed=1):
    """Frames of bright lines (PSF sigma 1.5 px, peak 60 over a background of 100, noise 4)."""
    import numpy as np
    from scipy.ndimage import gaussian_filter

    rng = np.random.default_rng(seed)
    out = np.empty((len(curves), *shape), np.float32)
    for i, objs in enumerate(curves):
        img = np.zeros(shape)
        for pts, f in objs:
            if f:
                xi, yi = np.rint(pts[:, 0]).astype(int), np.rint(pts[:, 1]).astype(int)
                np.add.at(img, (np.clip(yi, 0, shape[0] - 1), np.clip(xi, 0, shape[1] - 1)), 0.15 * f)
        out[i] = 100 + gaussian_filter(img, 1.5) * 60 * np.sqrt(2 * np.pi) * 1.5 + rng.normal(0, 4, shape)
    return out


def test_a_second_ribbon_is_not_taken_after_a_few_lost_frames():
    """Diff review: with the jump tolerance per lost frame, a second, dimmer ribbon one body
    length away was taken after 3 lost frames and followed for the rest of the movie. The
    swimmer's travel across lost frames is bounded (SWIM_PER_FRAME): the frames after the gap
    are on the swimmer again."""
    import numpy as np

    from flutterswim.tracking import track

    T, g0, gap = 110, 60, 7
    curves, truth = [], []
    for i in range(T):
        b = _wave_body(i, 60.0, 100.0, 0.6)
        truth.append(b)
        curves.append([(b, 0.0 if g0 <= i < g0 + gap else 1.0), (_wave_body(0.7 * i + 7, 60.0, 160.0, 0.3), 0.8)])
    tr = track(_line_frames(curves), px_per_mm=16.0, fps=50.0)
    f = tr.meta["frames"]
    ok = np.asarray(f["ok"])
    for i in np.nonzero(ok)[0]:
        P = np.stack([f["x_px"][i], f["y_px"][i]], 1)
        ends = [truth[i][0], truth[i][-1]]
        assert min(np.hypot(*(P[0] - e)) for e in ends) < 5, i  # on the swimmer, not the other ribbon
    assert ok[g0 + gap:].all() and not ok[g0:g0 + gap].any()


def test_the_body_length_check_takes_the_trials_fitted(tmp_path, monkeypatch, capsys):
    """Diff review: the check pooled every trial of the CSV, so another sample of 4.4 mm at 95 V
    refused a fit at 85 V of a sample matching the model's l."""
    import importlib

    from flutterswim.cli import main
    from flutterswim.fitting.model import OutsideModel

    ff = importlib.import_module("flutterswim.fitting.fit")

    def stop(mean, sem, **kw):
        raise OutsideModel("stopped by the test")

    monkeypatch.setattr(ff, "fit", stop)
    a = _trials_csv(tmp_path / "a.csv", 3.7, volts=(85.0,)).read_text().splitlines()
    b = _trials_csv(tmp_path / "b.csv", 4.4, volts=(95.0, 96.0, 97.0), rows=3).read_text().splitlines()[1:]
    csv = tmp_path / "mix.csv"
    csv.write_text("\n".join(a + b) + "\n")
    assert main(["fit", str(csv), "--voltage", "85", "--out", str(tmp_path / "f.json")]) == 1  # (fitted)
    assert "body length" not in capsys.readouterr().err
    assert main(["fit", str(csv), "--voltage", "95", "--out", str(tmp_path / "f.json")]) == 2
    assert "at 95 V, 4.4 mm" in capsys.readouterr().err


def test_a_large_netcdf_is_written_by_hdf5_after_a_check_that_it_fits(tmp_path, monkeypatch):
    """Diff review: built in memory, a NetCDF needed about twice its size again (+808 MB for a
    400 MB run). Above IN_MEMORY_NETCDF_BYTES it is written by HDF5 directly, after a check of the
    free space (HDF5 meeting a full disk crashes the interpreter): refused as an OSError there."""
    import errno
    import importlib
    from collections import namedtuple

    import xarray as xr

    from flutterswim._paths import is_ours

    paths = importlib.import_module("flutterswim._paths")
    run = fs.simulate(fs.PAPER, 0.5, n_segments=8)
    monkeypatch.setattr(paths, "IN_MEMORY_NETCDF_BYTES", 0)
    p = run.save(tmp_path / "big.nc")
    assert is_ours(p)
    with xr.open_dataset(p, engine="h5netcdf") as ds:
        assert ds["x"].shape == run.x.shape
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(paths.shutil, "disk_usage", lambda _: usage(10 ** 9, 10 ** 9 - 1000, 1000))
    with pytest.raises(OSError) as e:
        run.save(tmp_path / "full.nc")
    assert e.value.errno == errno.ENOSPC and not (tmp_path / "full.nc").exists()
    assert sorted(q.name for q in tmp_path.iterdir()) == ["big.nc"]


def test_main_called_by_a_program_leaves_its_sigterm_handler(monkeypatch):
    """Diff review: cli.main() without arguments, called by a program, replaced the program's
    SIGTERM handler for good (a later SIGTERM raised KeyboardInterrupt in the program)."""
    import signal
    import sys

    from flutterswim.cli import main

    def mine(signum, frame):
        pass

    old = signal.signal(signal.SIGTERM, mine)
    try:
        monkeypatch.setattr(sys, "argv", ["flutterswim", "--version"])
        try:
            main()
        except SystemExit:
            pass
        assert signal.getsignal(signal.SIGTERM) is mine
    finally:
        signal.signal(signal.SIGTERM, old)


def test_the_kernel_cache_does_not_use_a_folder_of_another_user(tmp_path, monkeypatch):
    """Diff review: the temporary fallback took $TMPDIR/flutterswim-<uid> whoever owned it (numba
    unpickles its cache index there). Another user's folder is left alone: no cache then."""
    pytest.importorskip("numba")
    import os
    import tempfile

    from numba.core import config

    from flutterswim import _jit

    home = tmp_path / "home"
    home.write_text("not a folder")
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    planted = tmp_path / "tmp" / f"flutterswim-{os.getuid()}"
    planted.mkdir(parents=True, mode=0o777)
    os.chmod(planted, 0o777)
    monkeypatch.setattr(config, "CACHE_DIR", config.CACHE_DIR)
    monkeypatch.setattr(_jit, "_CACHE", True)
    real = os.lstat

    class Other:  # the planted folder as another user's
        def __init__(self, st):
            self._st = st

        def __getattr__(self, name):
            return getattr(self._st, name)

        st_uid = os.getuid() + 1

    monkeypatch.setattr(os, "lstat", lambda p, *a, **k: Other(real(p)) if str(p) == str(planted) else real(p, *a, **k))
    before = config.CACHE_DIR
    _jit._set_cache_dir()
    assert config.CACHE_DIR == before and _jit._CACHE is False
    assert (os.stat(planted).st_mode & 0o777) == 0o777  # not changed


def test_figures_are_not_written_into_a_folder_inside_a_store(tmp_path):
    """Diff review: demo --out s.zarr/demo wrote three files into a sweep store (its --overwrite
    then refused it as holding files it did not write)."""
    from flutterswim._paths import MARKER, check_output_dir

    store = tmp_path / "s.zarr"
    store.mkdir()
    (store / MARKER).write_text('{"kind": "sweep"}')
    for out in (store, store / "demo"):
        with pytest.raises(fs.ParameterError, match="flutterswim sweep folder"):
            check_output_dir(out)
    assert check_output_dir(tmp_path / "plain") == tmp_path / "plain"


def test_a_sample_geometry_the_model_refuses_names_the_options(tmp_path, capsys):
    """--width-mm 5 with the paper's 3.7 mm length was refused as "b=0.0025 m ...", naming
    neither the option nor its unit."""
    from flutterswim.cli import main

    csv = _trials_csv(tmp_path / "t.csv", 3.7)
    assert main(["fit", str(csv), "--out", str(tmp_path / "f.json"), "--width-mm", "5"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--width-mm=5.0" in err and not (tmp_path / "f.json").exists()
