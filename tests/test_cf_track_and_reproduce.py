"""CF conventions of the tracked-movie file (``flutterswim track --out track.nc``) and of the
reproduction's figure data: opened with xarray, every data variable and coordinate has
``units`` and ``long_name``, no coordinate has a ``_FillValue`` (CF coordinates hold no missing
data), the file has ``title`` and ``Conventions``; a 0/1 variable says its flags. The track file
still reads back into the same :class:`Track` (the same ``describe`` numbers) and keeps the
title that lets ``track`` replace only tracks."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

import flutterswim as fs

xr = pytest.importorskip("xarray")

FPS = 50.0


def assert_cf_file(path, flags=()):
    """The CF checks on a written file, reopened with xarray; ``flags``: 0/1 variables, which
    must carry flag_values [0, 1] and one flag meaning per value."""
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        assert ds.attrs.get("title"), f"{path.name}: no title"
        assert str(ds.attrs.get("Conventions", "")).startswith("CF-"), f"{path.name}: no Conventions"
        assert ds.attrs.get("flutterswim_version") == fs.__version__, f"{path.name}: no flutterswim_version"
        for name, var in {**ds.data_vars, **ds.coords}.items():
            for key in ("units", "long_name"):
                assert isinstance(var.attrs.get(key), str) and var.attrs[key], f"{path.name}: {name} has no {key}"
        for name in ds.coords:
            assert ds[name].encoding.get("_FillValue") is None, f"{path.name}: coordinate {name} has a _FillValue"
        for name in flags:
            assert ds[name].attrs["flag_values"].tolist() == [0, 1], (path.name, name)
            assert len(ds[name].attrs["flag_meanings"].split()) == 2, (path.name, name)
        return dict(ds.attrs)


# --- the track file ----------------------------------------------------------------------
@pytest.fixture(scope="module")
def tracked():
    """A 1 mm line carrying a travelling wave (5 Hz, 4 strokes in 40 frames), frame 7 blank
    (a failed frame: NaN positions, the coordinates still whole)."""
    pytest.importorskip("skimage")
    from flutterswim.tracking import render, track

    t = np.arange(40) / FPS
    s = np.linspace(0.0, 1e-3, 25)[None, :]
    x = s + 1e-3 * t[:, None]
    y = 0.08e-3 * (s / 1e-3) * np.sin(2 * np.pi * s / 1.2e-3 - 2 * np.pi * 5.0 * t[:, None])
    mv = render(SimpleNamespace(t=t, x=x, y=y), um_per_px=14.0, snr=8.0, seed=1, dtype="uint16")
    mv.frames[7] = np.median(mv.frames[7]).astype(mv.frames.dtype)
    tr = track(mv, px_per_mm=mv.px_per_mm, fps=FPS)
    assert tr.meta["n_failed"] == 1 and not tr.meta["frames"]["ok"][7]
    return tr


def test_track_file_is_cf_and_reads_back_to_the_same_description(tracked, tmp_path, capsys):
    """track.nc was written without the CF helper: its float coordinates (time, s) carried
    _FillValue = NaN. Now as every other file; the reader and `describe` see the same track."""
    from flutterswim._paths import netcdf_title
    from flutterswim.analysis.descriptors import describe
    from flutterswim.cli import main
    from flutterswim.tracking import load_track, save_track
    from flutterswim.tracking.netcdf import TRACK_TITLE

    p = save_track(tracked, tmp_path / "track.nc")
    attrs = assert_cf_file(p, flags=("tracked",))
    assert attrs["title"] == TRACK_TITLE == netcdf_title(p)  # what `track` recognises as its own
    with xr.open_dataset(p) as ds:  # xarray's default engine too
        assert set(ds.coords) >= {"time", "frame", "s"}
        assert np.isfinite(ds["time"].values).all() and np.isfinite(ds["s"].values).all()
        assert np.isnan(ds["x"].values[7]).all()  # the failed frame: missing positions stay NaN
        assert ds["failure_reason"].values[7] and not ds["failure_reason"].values[0]
    back = load_track(p)
    np.testing.assert_array_equal(back.t, tracked.t)
    np.testing.assert_array_equal(back.x, tracked.x)
    np.testing.assert_array_equal(back.s, tracked.s)
    for key in ("template_coef_se", "template_coef_stderr"):  # the template's noise, for describe
        np.testing.assert_allclose(back.meta[key], tracked.meta[key], rtol=1e-12)
    want = describe(tracked).to_dict()
    assert describe(back).to_dict() == want
    capsys.readouterr()
    assert main(["describe", str(p), "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == json.loads(json.dumps(want))
    save_track(tracked, p)  # its own kind of file: replaced


# --- the reproduction's figure data --------------------------------------------------------
def test_reproduce_refuses_to_write_a_file_without_a_title(tmp_path):
    from flutterswim.reproduce.io import write_netcdf

    ds = xr.Dataset({"a": ("n", np.arange(3.0), {"units": "1", "long_name": "a"})},
                    coords={"n": ("n", np.arange(3.0), {"units": "1", "long_name": "index"})})
    with pytest.raises(ValueError, match="title"):
        write_netcdf(tmp_path / "a.nc", ds)
    assert not (tmp_path / "a.nc").exists()
    ds.attrs["title"] = "flutterswim reproduce: a test"
    assert_cf_file(write_netcdf(tmp_path / "a.nc", ds))


def test_linear_theory_and_steering_targets_write_cf_files(tmp_path, monkeypatch):
    """b_readings, Fig. 6a (map and neutral curve), 6b, 6c-d and 5 built directly (coarse grids):
    each file titled, CF, units and a long name on everything. Fig. 4c-e (which read the
    representative run) are checked on the reproduction built in test_reproduce_figures."""
    pytest.importorskip("matplotlib")
    from flutterswim.reproduce import figures_stability as st
    from flutterswim.reproduce import figures_steering as sg
    from flutterswim.reproduce.targets import Context, Settings

    prm = fs.PAPER.to_dict()
    monkeypatch.setattr(st, "b_params", lambda s: {"params": prm, "n_segments": 12, "step": 0.1})
    monkeypatch.setattr(st, "fig6a_params", lambda s: {"step": 5.0, "neutral_step": 5.0, "params": prm})
    monkeypatch.setattr(st, "fig6b_params", lambda s: {"step": 5.0, "params": prm})
    monkeypatch.setattr(st, "fig6cd_params", lambda s: {"n_points": 101, "params": prm})
    ctx = Context(tmp_path, Settings("quick"), {})
    for build in (st.build_b_readings, st.build_fig6a, st.build_fig6b, st.build_fig6cd, sg.build_fig5):
        build(ctx)
    files = {"b_readings.nc": (), "fig6a_map.nc": (), "fig6a_neutral.nc": (), "fig6b.nc": (), "fig6cd.nc": (),
             "fig5.nc": ("avg_in_fit",)}
    titles = set()
    for name, flags in files.items():
        attrs = assert_cf_file(tmp_path / name, flags)
        assert attrs["title"].startswith("flutterswim reproduce: "), name
        assert attrs["source"].startswith("flutterswim ") and attrs["source"].endswith(" reproduce"), name
        titles.add(attrs["title"])
    assert len(titles) == len(files)  # each file says what it holds
