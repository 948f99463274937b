"""A command whose optional package is missing says so in one line before it computes (a
review: branch computed 35 s, track tracked a whole movie, stability 21 s, before failing to
write their files without xarray or matplotlib)."""

import importlib.util
import time

import pytest

from flutterswim.cli import main


@pytest.mark.parametrize("argv,missing,extra", [
    (["simulate", "--t-end", "50", "--segments", "48", "--quiet"], "h5netcdf", "io"),
    (["branch", "kappa_E_ratio=0.7:2", "--quiet"], "xarray", "io"),
    (["stability", "--step", "0.1"], "matplotlib", "plot"),
    (["sweep", "kappa_E_ratio=0.7,1", "--out", "s.zarr", "--backend", "dask-local"], "distributed", "dask"),
    (["fit", "trials.csv", "--plot", "f.png"], "matplotlib", "plot"),
])
def test_a_missing_package_is_named_before_any_work(tmp_path, monkeypatch, capsys, argv, missing, extra):
    monkeypatch.chdir(tmp_path)
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == missing else real(name, *a))
    t0 = time.perf_counter()
    assert main(argv) == 1
    assert time.perf_counter() - t0 < 5.0  # (nothing computed)
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and repr(missing) in err[0] and f"flutterswim[{extra}]" in err[0], err
    assert not any(tmp_path.iterdir())  # nothing written


def test_only_what_the_command_needs_is_asked_for(monkeypatch):
    """A folder of PNG frames needs no tifffile, a reproduce without videos no imageio; steer
    --animate needs the video packages (a review)."""
    import argparse

    from flutterswim.cli import _check_optional

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name in ("tifffile", "imageio", "imageio_ffmpeg") else real(name, *a))
    _check_optional(argparse.Namespace(command="track"))
    _check_optional(argparse.Namespace(command="track-batch"))
    _check_optional(argparse.Namespace(command="reproduce"))
    _check_optional(argparse.Namespace(command="steer", animate=None))
    with pytest.raises(ModuleNotFoundError, match="imageio"):
        _check_optional(argparse.Namespace(command="steer", animate="a.gif"))
