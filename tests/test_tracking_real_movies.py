"""What real microscope movies have. Frames' times: a movie with dropped frames, tracked with
the camera's timestamps, keeps its period and its periodic template; duplicated frames are
flagged; the timestamps file reader. Static debris brighter than the swimmer is passed over."""

from __future__ import annotations

import math
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("skimage")

from conftest import rendered_paper_stroke  # noqa: E402
from flutterswim._validate import ParameterError  # noqa: E402
from flutterswim.analysis.descriptors import describe  # noqa: E402
from flutterswim.tracking import failures, render, track  # noqa: E402
from flutterswim.tracking.evaluate import pixel_errors  # noqa: E402
from flutterswim.tracking.io import read_times  # noqa: E402
from flutterswim.tracking.render import line_image  # noqa: E402
from flutterswim.tracking.track import static_objects, track_frame  # noqa: E402

FPS = 50.0
DROP = [20, 47, 73]


@pytest.fixture(scope="module")
def movie():
    """The paper's settled stroke, 101 frames at 50 fps, SNR 5, and its described truth."""
    return rendered_paper_stroke(seed=0, fps=FPS)


def _rel(a: float, b: float) -> float:
    return abs(a / b - 1.0)


def test_dropped_frames_with_their_times(movie):
    """Three frames dropped: with the frames' times the period, both ends and the advance stay
    those of the full movie's truth and the periodic template is used; counted at the nominal
    frame rate instead, every frame after a drop is a frame interval late (the period comes out
    3 % short) and the template is refused with a hint to give the times."""
    mv, truth = movie
    keep = np.setdiff1d(np.arange(mv.t.size), DROP)
    tr = track(mv.frames[keep], px_per_mm=mv.px_per_mm, times=mv.t[keep])
    assert not failures(tr)
    assert tr.meta["temporal"]["periodic"].startswith("done")
    np.testing.assert_allclose(tr.t, mv.t[keep])
    d = describe(tr, n_last=100)
    assert _rel(d.period_s, truth.period_s) < 1e-3
    assert _rel(d.trailing_lateral_p2p_mm, truth.trailing_lateral_p2p_mm) < 5e-3
    assert _rel(d.advance_per_cycle_mm, truth.advance_per_cycle_mm) < 5e-3
    naive = track(mv.frames[keep], px_per_mm=mv.px_per_mm, fps=FPS, t0=float(mv.t[0]))
    assert _rel(describe(naive, n_last=100).period_s, truth.period_s) > 0.01
    assert "give the frames' times" in naive.meta["temporal"]["periodic"]


@pytest.mark.parametrize("drop", [[40, 41], [30, 60, 61], [70, 71, 72]])
def test_runs_of_dropped_frames_with_their_times(movie, drop, tmp_path, capsys):
    """Two or three frames dropped in a row: the fits in time use the frames' times. The end
    smoothing fitted its polynomial over frame indices and moved the frame before the gap by
    2-3 px; the stroke's period, counted over indices, came out 4.7 % short, outside the
    template's search, and the template was refused."""
    from flutterswim.cli import main
    from flutterswim.tracking.netcdf import load_track, save_track

    mv, truth = movie
    keep = np.setdiff1d(np.arange(mv.t.size), drop)
    kept = SimpleNamespace(x_px=mv.x_px[keep], y_px=mv.y_px[keep])
    tr = track(mv.frames[keep], px_per_mm=mv.px_per_mm, times=mv.t[keep])
    assert tr.meta["temporal"]["periodic"].startswith("done")
    _, E, _ = pixel_errors(tr, kept)
    assert float(np.sqrt(np.mean(E ** 2))) < 0.5 and float(E.max()) < 1.0
    d = describe(tr, n_last=100)
    assert _rel(d.period_s, truth.period_s) < 1e-3
    # the file says where its times come from (it had said "index / fps" of timestamps)
    import xarray as xr

    save_track(tr, tmp_path / "stamped.nc")
    with xr.open_dataset(tmp_path / "stamped.nc", engine="h5netcdf") as ds:
        assert "timestamp" in ds["time"].attrs["long_name"] and np.allclose(ds["time"].values, mv.t[keep])
    save_track(load_track(tmp_path / "stamped.nc"), tmp_path / "again.nc")  # (reloaded, saved anew)
    with xr.open_dataset(tmp_path / "again.nc", engine="h5netcdf") as ds:
        assert "timestamp" in ds["time"].attrs["long_name"]
    # without the times: the hint reaches the track file, describe and the command's output
    naive = track(mv.frames[keep], px_per_mm=mv.px_per_mm, fps=FPS)
    save_track(naive, tmp_path / "naive.nc")
    with xr.open_dataset(tmp_path / "naive.nc", engine="h5netcdf") as ds:
        assert "index / fps" in ds["time"].attrs["long_name"]
    back = load_track(tmp_path / "naive.nc")
    assert "give the frames' times" in back.meta["temporal"]["periodic"]
    assert main(["describe", str(tmp_path / "naive.nc")]) == 0
    assert "give the frames' times" in capsys.readouterr().err  # (describe's note)


def test_duplicated_frames_are_flagged(movie):
    """A frame replaced by a copy of the one before (a grabber's duplicate) is flagged
    'repeated' and left out; the others are kept and the period is the truth's."""
    mv, truth = movie
    fr = mv.frames.copy()
    for i in DROP:
        fr[i] = fr[i - 1]
    tr = track(fr, px_per_mm=mv.px_per_mm, fps=FPS, t0=float(mv.t[0]))
    f = failures(tr)
    assert [i for i, _, _ in f] == DROP
    assert all(why.startswith("repeated: identical to frame") for _, _, why in f)
    assert _rel(describe(tr, n_last=100).period_s, truth.period_s) < 1e-3


def test_a_noiseless_body_at_rest_is_not_flagged_repeated():
    """Every frame identical (a noiseless movie of a still body) is not a run of duplicates."""
    s = np.linspace(0.0, 3.7e-3, 25)
    t = np.arange(12) / FPS
    rest = SimpleNamespace(t=t, x=np.tile(s, (t.size, 1)), y=np.tile(2e-4 * np.sin(3 * s / 3.7e-3), (t.size, 1)))
    mv = render(rest, um_per_px=14.0, snr=math.inf)
    tr = track(mv, px_per_mm=mv.px_per_mm, fps=FPS)
    assert not [why for _, _, why in failures(tr) if why.startswith("repeated")]
    assert tr.t.size == t.size


def test_batch_sidecar_names_the_frames_times(movie, tmp_path):
    """track-batch: a trial with dropped frames whose sidecar names its timestamps file keeps
    the full movie's period; a sidecar naming a missing file stops the batch before any trial
    is tracked or anything is written."""
    tifffile = pytest.importorskip("tifffile")
    import json

    from flutterswim.fitting.data import read_trials
    from flutterswim.tracking import track_batch

    mv, truth = movie
    keep = np.setdiff1d(np.arange(mv.t.size), DROP)
    folder = tmp_path / "trials"
    folder.mkdir()
    tifffile.imwrite(folder / "d.tif", mv.frames[keep], photometric="minisblack")
    (folder / "stamps").mkdir()
    (folder / "stamps" / "d.csv").write_text("time_ms\n" + "\n".join(f"{1e3 * v:.6f}" for v in mv.t[keep]))
    (folder / "d.json").write_text(json.dumps({"voltage_V": 80, "sample": "a", "times": "stamps/d.csv"}))
    out = tmp_path / "trials.csv"
    _, rows, failed = track_batch(folder, out, px_per_mm=mv.px_per_mm, fps=FPS)
    assert not failed and len(rows) == 1
    assert _rel(read_trials(out).values[0, 0], truth.period_s) < 1e-3
    (folder / "d.json").write_text(json.dumps({"voltage_V": 80, "sample": "a", "times": "stamps/missing.csv"}))
    out2 = tmp_path / "again.csv"
    with pytest.raises(ParameterError, match="missing.csv"):
        track_batch(folder, out2, px_per_mm=mv.px_per_mm, fps=FPS)
    assert not out2.exists()


def test_times_are_checked(movie):
    mv, _ = movie
    fr = mv.frames[:12]
    for bad, word in ((mv.t[:11], "one time"), (mv.t[:12][::-1], "increase strictly"),
                      (np.r_[mv.t[:11], np.nan], "finite"), (["a"] * 12, "numbers")):
        with pytest.raises(ParameterError, match=word):
            track(fr, px_per_mm=mv.px_per_mm, times=bad)


def test_read_times(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("frame,time_ms\n0,0\n\n1,20.5\n2,40\n")
    np.testing.assert_allclose(read_times(p), [0.0, 0.0205, 0.04])
    p.write_text("# camera clock\n0.0\n0.02\n0.041\n")
    np.testing.assert_allclose(read_times(p), [0.0, 0.02, 0.041])
    # a name of several words joined by underscores, with its unit (had been refused)
    for head, f in (("elapsed_time_ms", 1e-3), ("Elapsed_Time_us", 1e-6), ("time_since_start_s", 1.0)):
        p.write_text(f"frame,{head}\n0,0\n1,20\n")
        np.testing.assert_allclose(read_times(p), [0.0, 20 * f])
    p.write_text("frame;stamp\n0;0\n")
    with pytest.raises(ParameterError, match="names no time column"):
        read_times(p)
    p.write_text("0.0\n0.02\nabc\n")
    with pytest.raises(ParameterError, match="row 3: 'abc'"):
        read_times(p)


def test_cli_times_of_the_wrong_count(tmp_path, movie):
    """`track --times` with fewer times than frames: one line, exit 2, nothing written."""
    import tifffile

    mv, _ = movie
    stack = tmp_path / "m.tif"
    tifffile.imwrite(stack, mv.frames[:10])
    times = tmp_path / "t.txt"
    times.write_text("\n".join(str(v) for v in mv.t[:9]))
    out = tmp_path / "tr.nc"
    r = subprocess.run([sys.executable, "-m", "flutterswim", "track", str(stack), "--px-per-mm", str(mv.px_per_mm),
                        "--times", str(times), "--out", str(out), "--quiet"], capture_output=True, text=True)
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "one time [s] per frame" in r.stderr
    assert not out.exists()


def _with_fibre(mv, height: float = 2.5):
    """The movie with a static straight fibre (a dust fibre) below the swimmer's path, whose
    line holds more light than the body (``height`` times the line's height, 0.6 of its
    length), with its own shot noise."""
    T, H, W = mv.frames.shape
    y0 = float(np.max(mv.y_px)) + 12.0
    xs = np.linspace(0.2 * W, 0.2 * W + 0.6 * (W - 48), 50)
    fibre = line_image(xs, np.full(xs.size, y0), (H + 20, W), mv.meta["psf_sigma"])
    big = np.concatenate([mv.frames, np.full((T, 20, W), np.median(mv.frames), np.float32)], axis=1)
    rng = np.random.default_rng(5)
    extra = height * mv.meta["amplitude"] * fibre
    return (big + rng.poisson(np.broadcast_to(extra, big.shape)).astype(np.float32)), fibre > 0.5


def test_static_debris_brighter_than_the_body_is_passed_over(movie):
    """A static fibre holding more light than the swimmer: one frame alone cannot tell them
    apart (track_frame takes the fibre; the swimmer is then a 'gap'), the movie can: the fibre stays put in every frame
    (static_objects covers it, not the swimmer), and the swimmer is tracked in every frame
    to the accuracy of the clean movie."""
    mv, _ = movie
    frames, fibre = _with_fibre(mv)
    lone = track_frame(frames[0])  # the fibre, or a failure for the body seen as its piece
    assert not (lone["ok"] and np.max(np.abs(np.sort(lone["y"]) - np.sort(mv.y_px[0]))) < 2.0)
    st = static_objects(frames)
    assert st is not None and np.all(st[fibre])
    rows = np.clip(np.rint(mv.y_px).astype(int), 0, st.shape[0] - 1)
    cols = np.clip(np.rint(mv.x_px).astype(int), 0, st.shape[1] - 1)
    assert not st[rows, cols].any()
    tr = track(frames, px_per_mm=mv.px_per_mm, fps=FPS, t0=float(mv.t[0]))
    assert not failures(tr)
    D, E, idx = pixel_errors(tr, mv)
    assert idx.size == mv.t.size
    assert math.sqrt(np.mean(D**2)) <= 0.25 and math.sqrt(np.mean(E**2)) <= 0.5


def test_a_noisy_body_at_rest_is_still_tracked():
    """A filament at rest (below the flutter threshold) is a static object itself: with nothing
    else moving it is tracked as before, in every frame."""
    s = np.linspace(0.0, 3.7e-3, 25)
    t = np.arange(12) / FPS
    rest = SimpleNamespace(t=t, x=np.tile(s, (t.size, 1)), y=np.tile(2e-4 * np.sin(3 * s / 3.7e-3), (t.size, 1)))
    mv = render(rest, um_per_px=14.0, snr=5.0, seed=2)
    assert static_objects(mv.frames) is not None
    tr = track(mv, px_per_mm=mv.px_per_mm, fps=FPS)
    assert not failures(tr) and tr.t.size == t.size


def test_a_movies_sample_frames_are_read_in_one_pass(tmp_path):
    """The frames static_objects samples from a movie are read in one pass that keeps only them
    (indexing a movie decodes all of it into memory: 2.6 GB for 10 000 frames of 512 x 512),
    and they are the frames iteration gives."""
    import dataclasses

    import imageio_ffmpeg

    from flutterswim.tracking.io import open_frames

    p = tmp_path / "m.mp4"
    w = imageio_ffmpeg.write_frames(str(p), (64, 48), pix_fmt_in="gray", pix_fmt_out="yuv420p", quality=10)
    w.send(None)
    for i in range(20):
        w.send(np.full((48, 64), 10 * i, np.uint8).tobytes())
    w.close()
    f = open_frames(p)

    def boom(i):
        raise AssertionError("the whole movie decoded into memory")

    g = dataclasses.replace(f, _get=boom)
    every = list(f)
    for got, i in zip(g.take([0, 7, 19]), (0, 7, 19)):
        np.testing.assert_array_equal(got, every[i])
    assert static_objects(g) is None  # a flat movie has no objects; read without indexing


def test_the_tip_check_follows_the_frames_times():
    """The check of each end against the path of its neighbouring frames fits a polynomial in
    time: by frame index, a dropped frame makes the frames beside it look 80 times farther off
    the path than any other; by the frames' times they are on it."""
    from flutterswim.tracking.temporal import _leave_one_out

    t = np.setdiff1d(np.arange(60.0), [30.0])  # frame 30 dropped
    v = 10.0 * np.sin(2 * np.pi * t / 19.0)  # an end's smooth path
    ok = np.ones(t.size, bool)
    near = [28, 29, 30, 31]  # the frames beside the drop (their indices after it)
    far = np.setdiff1d(np.arange(2, t.size - 2), near)
    by_index = _leave_one_out(v, ok, 2, 2)
    by_time = _leave_one_out(v, ok, 2, 2, t)
    assert np.abs(by_index[near]).max() > 20 * np.abs(by_index[far]).max()
    assert np.nanmax(np.abs(by_time)) <= 1.5 * np.abs(by_index[far]).max()
