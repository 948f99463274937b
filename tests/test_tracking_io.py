"""Tracking: NetCDF round trip with units, the CLI, raw-frame kymographs against the
simulated crossings, and batch CSV / Fig. 3e from a folder of trials."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("skimage")
tifffile = pytest.importorskip("tifffile")

import flutterswim as fs  # noqa: E402
from flutterswim.analysis.descriptors import describe  # noqa: E402
from flutterswim.analysis.kymograph import line_kymograph  # noqa: E402
from flutterswim.analysis.track import Track  # noqa: E402
from flutterswim.cli import main  # noqa: E402
from flutterswim.tracking import (load_track, raw_kymographs, plot_raw_kymographs, render,  # noqa: E402
                                  save_track, track, track_batch)

FPS = 50.0


@pytest.fixture(scope="module")
def movie():
    """2.4 cycles of the settled stroke (45 frames), SNR 5."""
    r = fs.simulate(fs.PAPER, 10.0, n_segments=24, frame_dt=1.0 / FPS)
    sl = slice(r.t.size - 45, r.t.size)
    sub = SimpleNamespace(t=r.t[sl], x=r.x[sl], y=r.y[sl])
    return render(sub, um_per_px=14.0, snr=5.0, seed=7, dtype="uint16")


@pytest.fixture(scope="module")
def tracked(movie):
    return track(movie, px_per_mm=movie.px_per_mm, fps=FPS)


def truth(mv) -> Track:
    mm = mv.um_per_px / 1000.0
    return Track(t=mv.t - mv.t[0], x=mv.x_px * mm, y=mv.y_px * mm, units="mm", length=3.7)


def test_netcdf_round_trip_with_units(tracked, tmp_path):
    import xarray as xr

    p = save_track(tracked, tmp_path / "t.nc")
    with xr.open_dataset(p, engine="h5netcdf") as ds:
        for name in list(ds.data_vars) + list(ds.coords):
            assert "units" in ds[name].attrs, name
        assert ds.attrs["Conventions"].startswith("CF")
        assert ds.sizes["frame"] == tracked.meta["n_frames"]
        assert ds["body_length"].attrs["units"] == "mm"
    back = load_track(p)
    np.testing.assert_array_equal(back.x, tracked.x)
    np.testing.assert_array_equal(back.t, tracked.t)
    assert back.length == tracked.length
    assert describe(back).to_dict() == describe(tracked).to_dict()
    save_track(tracked, p)  # our own file: replaced
    foreign = tmp_path / "foreign.nc"
    foreign.write_bytes(b"not ours")
    with pytest.raises(fs.ParameterError, match="not written by flutterswim"):
        save_track(tracked, foreign)


def test_cli_track_json_and_errors(movie, tmp_path, capsys):
    tifffile.imwrite(tmp_path / "stack.tif", movie.frames, photometric="minisblack")
    out = tmp_path / "track.nc"
    rc = main(["track", str(tmp_path / "stack.tif"), "--px-per-mm", str(movie.px_per_mm), "--fps", "50",
               "--out", str(out), "--quiet", "--json"])
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    d = json.loads(cap.out)
    assert set(d) == set(describe(truth(movie)).to_dict())
    assert d["period_s"] == pytest.approx(describe(truth(movie)).period_s, rel=0.01)
    assert "tracked 45 of 45 frames" in cap.err
    assert load_track(out).n_frames == 45
    assert main(["describe", str(out), "--json"]) == 0  # describe reads a tracked movie as it reads a run
    assert json.loads(capsys.readouterr().out) == d  # over the same default cycles as track's (5)
    assert d["n_cycles_used"] < 5 and "fewer than the 5 asked for" in d["note"]
    rc = main(["track", str(tmp_path / "stack.tif"), "--px-per-mm", "70", "--fps", "50", "--out",
               str(tmp_path / "b.nc"), "--roi", "0,0,5000,10", "--quiet"])
    cap = capsys.readouterr()
    assert rc == 2 and "roi" in cap.err and len(cap.err.strip().splitlines()) == 1
    rc = main(["track", str(tmp_path / "missing.tif"), "--px-per-mm", "70", "--fps", "50", "--out",
               str(tmp_path / "c.nc"), "--quiet"])
    assert rc == 2
    # bright field: the line darker than the background; one line naming --dark-line, then tracked
    tifffile.imwrite(tmp_path / "dark.tif", (60000 - movie.frames.astype(np.int64)).astype(np.uint16),
                     photometric="minisblack")
    args = ["track", str(tmp_path / "dark.tif"), "--px-per-mm", str(movie.px_per_mm), "--fps", "50", "--quiet"]
    capsys.readouterr()
    assert main(args + ["--out", str(tmp_path / "d.nc")]) == 2
    cap = capsys.readouterr()
    assert "--dark-line" in cap.err and len(cap.err.strip().splitlines()) == 1
    assert main(args + ["--out", str(tmp_path / "d.nc"), "--dark-line"]) == 0
    assert "tracked 45 of 45 frames" in capsys.readouterr().out


def test_raw_kymographs_follow_the_simulated_crossings(movie, tracked, tmp_path):
    k = raw_kymographs(movie, tracked)
    ppm = movie.px_per_mm
    T, W = k.horizontal.shape
    assert (T, W) == (movie.frames.shape[0], movie.frames.shape[2])
    # the bright pixels of the horizontal kymograph sit where the true body crosses the row
    lk = line_kymograph(truth(movie), "horizontal", level=k.row / ppm)
    bg = np.median(k.horizontal)
    amp = movie.meta["amplitude"]
    on, n = [], 0
    for i in range(T):
        for xc in lk.positions[i][np.isfinite(lk.positions[i])]:
            on.append(k.horizontal[i, int(round(xc * ppm))] - bg)
            n += 1
    assert n > T  # the body crosses the row at least once a frame
    assert np.median(on) > 0.5 * amp
    # vertical line, same test
    lv = line_kymograph(truth(movie), "vertical", level=k.col / ppm)
    bgv = np.median(k.vertical)
    onv = [k.vertical[i, int(round(yc * ppm))] - bgv for i in range(T)
           for yc in lv.positions[i][np.isfinite(lv.positions[i])]]
    assert np.median(onv) > 0.5 * amp
    # the average-velocity line: the least-squares centroid velocity of the simulation
    xc, _ = truth(movie).centroid()
    vx = np.polyfit(movie.t, xc, 1)[0]
    assert k.velocity[0] == pytest.approx(vx, rel=0.02)
    # intensity along the tracked body: on the ridge, so about the line's amplitude
    assert np.nanmedian(k.body) - bg > 0.7 * amp
    p = tmp_path / "kym.png"
    fig = plot_raw_kymographs(k, p, tr=tracked)
    # the two colour-coded panels carry their scale: intensity over the body's range, curvature
    # symmetric about 0 in 1/mm
    bars = {ax.get_ylabel(): ax for ax in fig.axes if ax.get_label() == "<colorbar>"}
    assert set(bars) == {"intensity [grey levels]", "curvature [1/mm]"}
    lo, hi = bars["intensity [grey levels]"].get_ylim()
    assert lo <= np.nanpercentile(k.body, 5) and hi >= np.nanpercentile(k.body, 95)
    lo, hi = bars["curvature [1/mm]"].get_ylim()
    assert lo == pytest.approx(-hi) and hi > 0
    # each line's legend names the component it draws, and the speed (a swimmer at 37 degrees
    # read "average velocity 0.835 mm/s", its x component, for 1.045)
    texts = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    speed = f"(speed {math.hypot(*k.velocity):.3g})"
    assert any(t.startswith(f"average velocity, x: {k.velocity[0]:.3g}") and speed in t for t in texts), texts
    assert any(t.startswith(f"average velocity, y: {k.velocity[1]:.3g}") and speed in t for t in texts), texts
    import matplotlib.image as mpimg

    img = mpimg.imread(p)
    assert np.unique(img.reshape(-1, img.shape[-1]), axis=0).shape[0] > 50


def test_batch_csv_sidecar_pattern_failures_and_figure(movie, tmp_path, capsys):
    from flutterswim.fitting.data import read_trials

    folder = tmp_path / "trials"
    folder.mkdir()
    tifffile.imwrite(folder / "85V_sample1_trial1.tif", movie.frames, photometric="minisblack")
    tifffile.imwrite(folder / "72p5V_sample2.tif", movie.frames[5:], photometric="minisblack")
    tifffile.imwrite(folder / "b.tif", movie.frames, photometric="minisblack")
    (folder / "b.json").write_text(json.dumps({"voltage_V": 60, "sample": "s7", "fps": 50}))
    noise = np.random.default_rng(0).poisson(100, movie.frames.shape).astype(np.uint16)
    tifffile.imwrite(folder / "90V_sample9.tif", noise, photometric="minisblack")
    out = tmp_path / "trials.csv"
    fig = tmp_path / "fig3e.png"
    p, rows, failed = track_batch(folder, out, px_per_mm=movie.px_per_mm, fps=FPS, plot=str(fig))
    assert len(rows) == 3 and len(failed) == 1 and "90V_sample9" in failed[0][0]
    assert "lost contrast" in failed[0][1]
    tr = read_trials(p)
    assert sorted(tr.voltage_V.tolist()) == [60.0, 72.5, 85.0]
    assert sorted(tr.sample.tolist()) == ["1", "2", "s7"]
    dt = describe(truth(movie))
    np.testing.assert_allclose(tr.values[:, 0], dt.period_s, rtol=0.01)
    np.testing.assert_allclose(tr.values[:, 2], dt.trailing_lateral_p2p_mm, rtol=0.01)
    assert (tmp_path / "trials_failed.csv").read_text().count("\n") == 2
    assert fig.stat().st_size > 10_000
    # rerun over our own CSV is allowed; the CLI gives the same table
    rc = main(["track-batch", str(folder), "--px-per-mm", str(movie.px_per_mm), "--fps", "50", "--out", str(out),
               "--quiet"])
    assert rc == 1  # a failed trial fails the batch (the others are kept), as a failed point a sweep
    assert read_trials(out).values == pytest.approx(tr.values)
    said = capsys.readouterr()
    assert "tracked 3 of 4 trials" in said.out and "trials_failed.csv" in said.out
    assert "90V_sample9" in said.err and "lost contrast" in said.err


def test_batch_field_across_the_image_is_given_on_the_command_line_or_warned(movie, tmp_path, capsys):
    """The swimmer swims along the field. A movie turned by 90 degrees (field along the rows)
    tracked with the default field direction (+x) would report the advance across the field
    (about 0): track-batch warns, naming the trial and the option; with --field-angle-deg 90
    the advance per cycle is that of the untouched movie (the lateral excursion never changed)."""
    from flutterswim.fitting.data import read_trials

    folder = tmp_path / "t"
    folder.mkdir()
    tifffile.imwrite(folder / "85V_sample1.tif", np.ascontiguousarray(movie.frames.transpose(0, 2, 1)),
                     photometric="minisblack")
    out = tmp_path / "turned.csv"
    common = ["track-batch", str(folder), "--px-per-mm", str(movie.px_per_mm), "--fps", "50", "--quiet"]
    assert main(common + ["--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "85V_sample1" in err and "to the field" in err and "--field-angle-deg" in err
    assert main(common + ["--out", str(out), "--field-angle-deg", "90"]) == 0
    assert "to the field" not in capsys.readouterr().err
    dt = describe(truth(movie))
    turned = read_trials(out).values[0]
    assert turned[1] == pytest.approx(abs(dt.advance_per_cycle_mm), rel=0.01)
    assert turned[2] == pytest.approx(dt.trailing_lateral_p2p_mm, rel=0.01)


def test_batch_needs_voltage_and_sample(tmp_path, movie):
    folder = tmp_path / "t"
    folder.mkdir()
    tifffile.imwrite(folder / "whatever.tif", movie.frames[:4], photometric="minisblack")
    # (beside others it fails alone; with none to track, the pattern or the sidecars are wrong: bad input)
    with pytest.raises(fs.ParameterError, match="none of its 1 trials has a voltage.*no sidecar JSON"):
        track_batch(folder, tmp_path / "x.csv", px_per_mm=70, fps=50)
    assert not (tmp_path / "x.csv").exists()
    with pytest.raises(fs.ParameterError, match="named groups"):
        track_batch(folder, tmp_path / "x.csv", px_per_mm=70, fps=50, pattern=r"(\d+)V")
    assert math.isfinite(movie.px_per_mm)


def test_cli_describe_names_missing_frames_and_takes_max_gap(movie, tmp_path, capsys):
    """A movie with 6 blank frames (0.32 period) in every stroke: the track is saved, and
    `describe` exits 2 with one line naming the gap and the option; with --max-gap 0.4 it
    describes the track (period within 1 % of the simulated one), and a bad --max-gap is named."""
    frames = movie.frames.copy()
    blank = (np.arange(frames.shape[0]) % 19) >= 13
    frames[blank] = np.median(frames[0])
    tifffile.imwrite(tmp_path / "gappy.tif", frames, photometric="minisblack")
    out = tmp_path / "gappy.nc"
    assert main(["track", str(tmp_path / "gappy.tif"), "--px-per-mm", str(movie.px_per_mm), "--fps", "50",
                 "--out", str(out), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["describe", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "misses frames, in it or within 0.6 period of it, over more than 0.25 period" in err[0] and "--max-gap" in err[0]
    assert main(["describe", str(out), "--max-gap", "0.4", "--json"]) == 0
    period = describe(truth(movie)).period_s
    assert json.loads(capsys.readouterr().out)["period_s"] == pytest.approx(period, rel=1e-2)
    assert main(["describe", str(out), "--max-gap", "-1"]) == 2
    assert "--max-gap=-1" in capsys.readouterr().err


# --------------------------------------------------------------------------- damaged or odd inputs
def _small_stack(T: int = 6) -> np.ndarray:
    return (np.random.default_rng(3).random((T, 40, 50)) * 1000).astype(np.uint16)


def test_damaged_tiff_is_bad_input_without_tifffile_log(tmp_path, capsys, caplog):
    """A truncated TIFF and one with a garbage header: a ParameterError naming the file (API);
    the CLI exits 2 with one line, and tifffile's logger says nothing."""
    from flutterswim.tracking.io import open_frames

    tifffile.imwrite(tmp_path / "whole.tif", _small_stack(), photometric="minisblack")
    data = (tmp_path / "whole.tif").read_bytes()
    (tmp_path / "cut.tif").write_bytes(data[: len(data) // 2])
    (tmp_path / "garbage.tif").write_bytes(b"II*\x00garbage" * 10)
    for name in ("cut.tif", "garbage.tif"):
        with pytest.raises(fs.ParameterError, match=f"{name}' cannot be read as a TIFF stack"):
            open_frames(tmp_path / name)
        caplog.clear()
        capsys.readouterr()
        rc = main(["track", str(tmp_path / name), "--px-per-mm", "70", "--fps", "50", "--quiet",
                   "--out", str(tmp_path / "x.nc")])
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and len(err) == 1 and name in err[0] and "cannot be read as a TIFF stack" in err[0], err
        assert not [r for r in caplog.records if r.name.startswith("tifffile")]
    assert not (tmp_path / "x.nc").exists()


def test_tiff_stack_of_other_shape_is_refused_colour_is_read(movie, tracked, tmp_path, capsys):
    """(T, Z, H, W) is refused naming the shape (it was read as T*Z frames); colour stacks,
    interleaved (T, H, W, 3) or planar (T, 3, H, W), track as the grey one."""
    from flutterswim.tracking.io import open_frames

    tifffile.imwrite(tmp_path / "tz.tif", _small_stack().reshape(3, 2, 40, 50), imagej=False)
    tifffile.imwrite(tmp_path / "tz_ij.tif", _small_stack().reshape(3, 2, 40, 50), imagej=True,
                     metadata={"axes": "TZYX"})
    for name in ("tz.tif", "tz_ij.tif"):
        with pytest.raises(fs.ParameterError, match=rf"{name}' is a TIFF stack of shape \(3, 2, 40, 50\)"):
            open_frames(tmp_path / name)
    rc = main(["track", str(tmp_path / "tz.tif"), "--px-per-mm", "70", "--fps", "50", "--quiet",
               "--out", str(tmp_path / "x.nc")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "(3, 2, 40, 50)" in err[0] and "one Z plane" in err[0], err
    rgb = np.repeat(movie.frames[..., None], 3, axis=-1)
    tifffile.imwrite(tmp_path / "rgb.tif", rgb, photometric="rgb")
    tifffile.imwrite(tmp_path / "planar.tif", np.moveaxis(rgb, -1, 1), photometric="rgb", planarconfig="separate")
    for name in ("rgb.tif", "planar.tif"):
        fr = open_frames(tmp_path / name)
        assert (fr.n_frames, fr.shape) == (45, movie.frames.shape[1:])
        got = track(tmp_path / name, px_per_mm=movie.px_per_mm, fps=FPS)
        np.testing.assert_allclose(got.x, tracked.x, atol=1e-6)
        np.testing.assert_allclose(got.y, tracked.y, atol=1e-6)


def test_png_folder_with_a_frame_of_another_shape_is_refused(tmp_path):
    """A frame 10 rows short, or in colour among grey ones: refused naming that file and both shapes."""
    import imageio.v3 as iio

    from flutterswim.tracking.io import open_frames

    frames = (_small_stack(8) // 4).astype(np.uint8)
    for case, odd in (("short", frames[5][:-10]), ("colour", np.repeat(frames[5][..., None], 3, axis=-1))):
        folder = tmp_path / case
        folder.mkdir()
        for i, f in enumerate(frames):
            iio.imwrite(folder / f"f{i}.png", odd if i == 5 else f)
        want = r"'f5.png' has shape \(30, 50\)" if case == "short" else r"'f5.png' has shape \(40, 50, 3\)"
        with pytest.raises(fs.ParameterError, match=want + r" but the first frame 'f0.png' has \(40, 50\)"):
            open_frames(folder)


def test_a_bad_sigma_is_refused_before_any_frame_is_read(tmp_path):
    with pytest.raises(fs.ParameterError, match="sigma=-1"):
        track(tmp_path / "not-read.tif", px_per_mm=70.0, fps=50.0, sigma=-1.0)


def test_a_track_does_not_replace_a_simulated_run_nor_a_run_a_track(tracked, tmp_path):
    """A review: `track --out run.nc` replaced a saved simulation (both are flutterswim files)
    without a word. Each command replaces only its own kind of file."""
    run = fs.simulate(fs.PAPER, 0.05, n_segments=8)
    run_path = run.save(tmp_path / "run.nc")
    before = run_path.read_bytes()
    with pytest.raises(fs.ParameterError, match="another kind of flutterswim result"):
        save_track(tracked, run_path)
    assert run_path.read_bytes() == before
    track_path = save_track(tracked, tmp_path / "t.nc")
    with pytest.raises(fs.ParameterError, match="another kind of flutterswim result"):
        run.save(track_path)
    assert load_track(track_path).t.size == tracked.t.size
    save_track(tracked, track_path)  # its own kind: replaced as before
    run.save(run_path)
