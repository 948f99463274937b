"""Tracking inputs: bad input is refused in one line before any long computation, and a batch
records a failed trial and goes on (its finished trials kept)."""

from __future__ import annotations

import csv
import importlib
import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("skimage")
tifffile = pytest.importorskip("tifffile")

import flutterswim as fs  # noqa: E402
from flutterswim.cli import main  # noqa: E402
from flutterswim.tracking import render, track, track_batch  # noqa: E402
from flutterswim.tracking.io import open_frames, parse_roi  # noqa: E402

FPS = 50.0
trk = importlib.import_module("flutterswim.tracking.track")  # the module (the package's ``track`` is the function)


def wave(T: int = 40, P: int = 25) -> SimpleNamespace:
    """A 1 mm line carrying a travelling wave (5 Hz), advancing 1 mm/s: 4 strokes in T = 40 frames."""
    t = np.arange(T) / FPS
    s = np.linspace(0.0, 1e-3, P)[None, :]
    x = s + 1e-3 * t[:, None]
    y = 0.08e-3 * (s / 1e-3) * np.sin(2 * np.pi * s / 1.2e-3 - 2 * np.pi * 5.0 * t[:, None])
    return SimpleNamespace(t=t, x=x, y=y)


@pytest.fixture(scope="module")
def movie():
    return render(wave(), um_per_px=14.0, snr=8.0, seed=1, dtype="uint16")


def _trials(folder, movie, names=("80V_sample1.tif",)):
    folder.mkdir()
    for n in names:
        tifffile.imwrite(folder / n, movie.frames, photometric="minisblack")
    return folder


def _rows(p):
    with open(p) as f:
        return list(csv.DictReader(f))


# ---- batch: a failed trial is recorded and the batch goes on --------------------------------------------------------

def test_batch_corrupt_movie_is_a_failed_trial_and_the_others_are_kept(movie, tmp_path, capsys):
    folder = _trials(tmp_path / "t", movie, ("80V_sample1.tif", "90V_sample3.tif"))
    (folder / "85V_sample2.mp4").write_bytes(b"not a movie" * 20)
    out = tmp_path / "trials.csv"
    rc = main(["track-batch", str(folder), "--px-per-mm", str(movie.px_per_mm), "--fps", "50", "--last", "3",
               "--out", str(out), "--quiet"])
    cap = capsys.readouterr()
    assert rc == 1, cap.err  # a failed trial fails the batch; the others are kept
    assert [r["sample"] for r in _rows(out)] == ["1", "3"]
    failed = _rows(tmp_path / "trials_failed.csv")
    assert len(failed) == 1 and "85V_sample2.mp4" in failed[0]["trial"]
    assert "cannot be read as a movie" in failed[0]["reason"] and len(failed[0]["reason"]) < 400
    assert "tracked 2 of 3 trials" in cap.out


def test_batch_any_error_of_one_trial_is_recorded(movie, tmp_path, monkeypatch):
    """An unexpected exception (not a ParameterError) of one trial is that trial's failure."""
    real = trk.track

    def flaky(source, **kw):
        if "sample2" in str(source):
            raise ValueError("something broke\ninside")
        return real(source, **kw)

    monkeypatch.setattr(trk, "track", flaky)
    folder = _trials(tmp_path / "t", movie, ("80V_sample1.tif", "85V_sample2.tif"))
    p, rows, failed = track_batch(folder, tmp_path / "o.csv", px_per_mm=movie.px_per_mm, fps=FPS, n_last=3)
    assert len(rows) == 1 and len(failed) == 1
    assert "sample2" in failed[0][0] and failed[0][1] == "ValueError: something broke inside"
    assert len(_rows(p)) == 1


@pytest.mark.parametrize("sidecar, match", [
    ({"voltage_V": 85, "sample": "s2", "field_angle_deg": "abc"}, "field_angle_deg='abc'"),
    ({"voltage_V": 85, "sample": "s2", "fps": -3}, "fps=-3"),
    ({"voltage_V": 85, "sample": "s2", "px_per_mm": "nan"}, "px_per_mm='nan'"),
    ({"voltage_V": 85, "sample": "s2", "start_end": "up"}, "start_end='up'"),
    ({"voltage_V": 85, "sample": "s2", "dark_line": "yes"}, "dark_line='yes'"),
    ({"voltage_V": 85, "sample": "s2", "roi": "0,0,inf,100"}, "roi="),
    ([1, 2], "not a JSON object"),
])
def test_batch_bad_sidecar_is_bad_input_before_any_trial_is_tracked(movie, tmp_path, monkeypatch, sidecar, match):
    monkeypatch.setattr(trk, "track", lambda *a, **k: pytest.fail("a trial was tracked"))
    folder = _trials(tmp_path / "t", movie, ("80V_sample1.tif", "b.tif"))
    (folder / "b.json").write_text(json.dumps(sidecar))
    with pytest.raises(fs.ParameterError, match=match) as exc:
        track_batch(folder, tmp_path / "o.csv", px_per_mm=70.0, fps=FPS)
    assert "b.json" in str(exc.value)
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize("sidecar, reason", [
    (None, "no sidecar JSON and the name does not match the pattern"),
    ({"voltage_V": "lots", "sample": "s2"}, "voltage 'lots' is not a number"),
    ({"voltage_V": "inf", "sample": "s2"}, "voltage inf is not finite"),
    ({"sample": "s2"}, "needs the keys voltage_V and sample"),
])
def test_batch_trial_without_a_voltage_fails_alone(movie, tmp_path, capsys, sidecar, reason):
    """README: a trial that fails ("no voltage") is listed with its reason in trials_failed.csv,
    the others are kept, exit 1; it stopped the whole batch (exit 2, nothing tracked)."""
    folder = _trials(tmp_path / "t", movie, ("85V_sample1.tif", "trialA.tif"))
    if sidecar is not None:
        (folder / "trialA.json").write_text(json.dumps(sidecar))
    out = tmp_path / "trials.csv"
    rc = main(["track-batch", str(folder), "--px-per-mm", str(movie.px_per_mm), "--fps", "50", "--out", str(out),
               "--quiet"])
    cap = capsys.readouterr()
    assert rc == 1, cap.err
    assert [(r["voltage_V"], r["sample"]) for r in _rows(out)] == [("85", "1")]
    failed = _rows(tmp_path / "trials_failed.csv")
    assert [Path(f["trial"]).name for f in failed] == ["trialA.tif"] and reason in failed[0]["reason"], failed
    assert "tracked 1 of 2 trials" in cap.out and "trialA.tif" in cap.err and reason in cap.err


def test_readme_track_batch_command_runs_on_tiff_stacks(movie, tmp_path, monkeypatch, capsys):
    """The README's track-batch line, run on a folder of TIFF stacks (which record no frame
    rate), tracks them: without --px-per-mm and --fps it exited 2 and tracked nothing."""
    import shlex

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    line = next(ln for ln in readme.splitlines() if ln.startswith("flutterswim track-batch "))
    argv = shlex.split(line.split("#")[0])[1:]
    _trials(tmp_path / "trials", movie, ("80V_sample1.tif", "85V_sample2.tif"))
    monkeypatch.chdir(tmp_path)
    assert main(argv + ["--quiet"]) == 0, capsys.readouterr().err
    rows = _rows(tmp_path / "trials.csv")
    assert [r["voltage_V"] for r in rows] == ["80", "85"]
    assert float(rows[0]["period_s"]) == pytest.approx(0.2, rel=0.02)  # the wave's 5 Hz


def test_batch_bad_pattern_is_still_bad_input(movie, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(trk, "track", lambda *a, **k: pytest.fail("a trial was tracked"))
    folder = _trials(tmp_path / "t", movie, ("85V_sample1.tif", "trialA.tif"))
    for pattern, words in (("(?P<voltage>[", "--pattern='(?P<voltage>[' is not a regular expression"),
                           (r"(\d+)V", "must have the named groups")):
        rc = main(["track-batch", str(folder), "--px-per-mm", "70", "--fps", "50", "--pattern", pattern,
                   "--out", str(tmp_path / "o.csv"), "--quiet"])
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and len(err) == 1 and words in err[0], err
    assert not (tmp_path / "o.csv").exists()


def test_batch_missing_px_per_mm_is_bad_input_before_any_trial_is_tracked(movie, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(trk, "track", lambda *a, **k: pytest.fail("a trial was tracked"))
    folder = _trials(tmp_path / "t", movie, ("80V_sample1.tif", "b.tif"))
    (folder / "80V_sample1.json").write_text(json.dumps({"voltage_V": 80, "sample": "1", "px_per_mm": 70}))
    (folder / "b.json").write_text(json.dumps({"voltage_V": 85, "sample": "s2"}))
    rc = main(["track-batch", str(folder), "--fps", "50", "--out", str(tmp_path / "o.csv"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and "px_per_mm" in err and "b.tif" in err


@pytest.mark.parametrize("opt", [["--last", "0"], ["--fps", "nan"], ["--px-per-mm", "-3"],
                                 ["--field-angle-deg", "nan"]])
def test_batch_bad_global_option_exits_2_before_tracking(movie, tmp_path, monkeypatch, capsys, opt):
    monkeypatch.setattr(trk, "track", lambda *a, **k: pytest.fail("a trial was tracked"))
    folder = _trials(tmp_path / "t", movie)
    args = {"--px-per-mm": "70", "--fps": "50"}
    args[opt[0]] = opt[1]
    rc = main(["track-batch", str(folder), *sum(map(list, args.items()), []), "--out", str(tmp_path / "o.csv"),
               "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and opt[0].lstrip("-").replace("-", "_")[:4] in err.replace("-", "_")
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize("kw, match", [({"length_tol": float("nan")}, "length_tol"),
                                       ({"min_contrast": -1.0}, "min_contrast"),
                                       ({"lenght_tol": 0.1}, "no option 'lenght_tol'")])
def test_batch_bad_track_option_is_refused_before_any_trial(movie, tmp_path, monkeypatch, kw, match):
    """From Python, a bad or misspelt option of track() failed every trial (rc 1) instead of
    being refused once, before the first trial."""
    monkeypatch.setattr(trk, "track", lambda *a, **k: pytest.fail("a trial was tracked"))
    folder = _trials(tmp_path / "t", movie)
    with pytest.raises(fs.ParameterError, match=match):
        track_batch(folder, tmp_path / "o.csv", px_per_mm=70.0, fps=FPS, **kw)
    assert not (tmp_path / "o.csv").exists()


def test_batch_foreign_failures_file_is_refused_before_computing(movie, tmp_path, monkeypatch):
    monkeypatch.setattr(trk, "track", lambda *a, **k: pytest.fail("a trial was tracked"))
    folder = _trials(tmp_path / "t", movie)
    (tmp_path / "o_failed.csv").write_text("somebody else's table\n")
    with pytest.raises(fs.ParameterError, match="o_failed.csv"):
        track_batch(folder, tmp_path / "o.csv", px_per_mm=70.0, fps=FPS)
    assert not (tmp_path / "o.csv").exists()


def test_batch_stale_failures_file_of_ours_does_not_survive_a_clean_rerun(movie, tmp_path):
    folder = _trials(tmp_path / "t", movie)
    (folder / "85V_sample2.mp4").write_bytes(b"not a movie" * 20)
    out = tmp_path / "o.csv"
    _, rows, failed = track_batch(folder, out, px_per_mm=movie.px_per_mm, fps=FPS, n_last=3)
    assert len(rows) == 1 and len(failed) == 1 and (tmp_path / "o_failed.csv").exists()
    (folder / "85V_sample2.mp4").unlink()
    _, rows, failed = track_batch(folder, out, px_per_mm=movie.px_per_mm, fps=FPS, n_last=3)
    assert len(rows) == 1 and not failed
    assert not (tmp_path / "o_failed.csv").exists()


# ---- track: options checked before any frame is read ----------------------------------------------------------------

@pytest.mark.parametrize("kw, match", [
    ({"field_angle": math.nan}, "field_angle=nan"), ({"jump_tol": math.nan}, "jump_tol=nan"),
    ({"min_contrast": math.nan}, "min_contrast=nan"), ({"window_px": math.nan}, "window_px=nan"),
    ({"length_tol": math.nan}, "length_tol=nan"), ({"length_tol": -1.0}, "length_tol=-1"),
    ({"window_px": -5.0}, "window_px=-5"), ({"gap_fraction": math.nan}, "gap_fraction=nan"),
])
def test_track_bad_options_are_refused_before_any_frame_is_read(tmp_path, kw, match):
    with pytest.raises(fs.ParameterError, match=match):
        track(tmp_path / "not-read.tif", px_per_mm=70.0, fps=50.0, **kw)


@pytest.mark.parametrize("opt", [["--last", "0"], ["--field-angle-deg", "nan"]])
def test_cli_track_bad_option_exits_2_before_writing(movie, tmp_path, capsys, monkeypatch, opt):
    monkeypatch.setattr(trk, "track", lambda *a, **k: pytest.fail("tracked"))
    tifffile.imwrite(tmp_path / "m.tif", movie.frames[:4], photometric="minisblack")
    out = tmp_path / "m.nc"
    rc = main(["track", str(tmp_path / "m.tif"), "--px-per-mm", "70", "--fps", "50", "--out", str(out),
               "--json", "--quiet", *opt])
    err = capsys.readouterr().err
    assert rc == 2 and opt[0] in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


# ---- io: damaged inputs named in one short line ---------------------------------------------------------------------

@pytest.mark.parametrize("roi", ["inf,0,100,100", "0,0,100,-inf", (0, 0, math.inf, 100)])
def test_roi_not_finite_is_a_parameter_error(roi):
    with pytest.raises(fs.ParameterError, match="roi="):
        parse_roi(roi, (200, 200))


@pytest.mark.parametrize("data", [b"", b"not a movie" * 20])
def test_damaged_movie_is_a_short_parameter_error_naming_the_input(tmp_path, data):
    p = tmp_path / "m.mp4"
    p.write_bytes(data)
    with pytest.raises(fs.ParameterError, match="input=.*m.mp4.*cannot be read as a movie") as exc:
        open_frames(p)
    assert len(str(exc.value)) < 400 and "ffmpeg version" not in str(exc.value)


def test_truncated_png_in_a_frame_folder_is_named(tmp_path):
    import imageio.v3 as iio

    frames = np.random.default_rng(0).integers(0, 255, (4, 40, 50)).astype(np.uint8)
    for i, f in enumerate(frames):
        iio.imwrite(tmp_path / f"f{i}.png", f)
    data = (tmp_path / "f2.png").read_bytes()
    (tmp_path / "f2.png").write_bytes(data[: len(data) // 2])
    fr = open_frames(tmp_path)
    with pytest.raises(fs.ParameterError, match="f2.png"):
        for _ in fr:
            pass


def test_hidden_companion_files_in_a_frame_folder_are_not_frames(tmp_path):
    """A review: a folder copied from a Mac holds "._f0.png" companions (AppleDouble, not images);
    the whole folder was refused as "cannot be read as an image"."""
    import imageio.v3 as iio

    frames = np.random.default_rng(0).integers(0, 255, (4, 40, 50)).astype(np.uint8)
    for i, f in enumerate(frames):
        iio.imwrite(tmp_path / f"f{i}.png", f)
        (tmp_path / f"._f{i}.png").write_bytes(b"\x00\x05\x16\x07" + b"\x00" * 60)
    fr = open_frames(tmp_path)
    assert fr.n_frames == 4
    np.testing.assert_array_equal(np.stack(list(fr)).astype(np.uint8), frames)


# ---- render: inputs -------------------------------------------------------------------------------------------------

def _line(T=3, P=9):
    t = np.arange(T) / FPS
    x = np.linspace(0.0, 0.5e-3, P)[None, :] + 1e-4 * t[:, None]
    return SimpleNamespace(t=t, x=x, y=np.zeros_like(x))


@pytest.mark.parametrize("change, kw, match", [
    (None, {"gradient": math.nan}, "gradient=nan"),
    (None, {"gradient": 5.0}, "gradient=5"),
    (None, {"gradient": -2.0}, "gradient=-2"),
    (None, {"margin_px": -3}, "margin_px=-3"),
    (None, {"snr": True}, "snr=True"),
    (None, {"seed": "a"}, "seed='a'"),
    ("nan", {}, "x"),
    ("shape", {}, "shape"),
    ("short_t", {}, "t"),
    ("reversed_t", {}, "increas"),
    ("repeated_t", {}, "increas"),
])
def test_render_bad_inputs_are_parameter_errors(change, kw, match):
    r = _line()
    if change == "nan":
        r.x[1, 2] = np.nan
    elif change == "shape":
        r.y = r.y[:, :-1]
    elif change == "short_t":
        r.t = r.t[:2]
    elif change == "reversed_t":
        r.t = r.t[::-1].copy()
    elif change == "repeated_t":
        r.t = np.array([0.0, 0.02, 0.02])
    with pytest.raises(fs.ParameterError, match=match):
        render(r, **kw)


def test_render_accepts_numpy_numbers():
    mv = render(_line(), snr=np.float32(5.0), seed=np.int64(3), margin_px=np.int64(8), gradient=-1.5)
    assert mv.frames.shape[0] == 3 and mv.fps == pytest.approx(FPS)


def test_a_grey_stack_saved_as_planar_rgb_says_how_it_was_read(tmp_path):
    """tifffile.imwrite of a (3, H, W) uint16 array without photometric tagged it as one planar
    RGB image: read as the tags say (one colour frame), and the error says so and how to save
    a grey stack."""
    tifffile = pytest.importorskip("tifffile")
    a = np.random.default_rng(0).integers(0, 1000, (3, 40, 50)).astype(np.uint16)
    # what tifffile's default did (a future version stores grey pages): explicit here
    tifffile.imwrite(tmp_path / "s.tif", a, photometric="rgb", planarconfig="separate")
    with pytest.raises(fs.ParameterError, match="holds 1 frame.*planar colour.*minisblack"):
        track(tmp_path / "s.tif", px_per_mm=70.0, fps=FPS)
    tifffile.imwrite(tmp_path / "g.tif", a, photometric="minisblack")
    from flutterswim.tracking.io import open_frames

    assert len(open_frames(tmp_path / "g.tif")) == 3


def test_batch_from_python_names_its_parameters_and_from_the_command_line_its_options(movie, tmp_path, capsys):
    """A TIFF stack records no frame rate and "trialA" misses the pattern: called from Python,
    the failures named the command line's --fps and --pattern; they name track_batch's fps and
    pattern there, and the options from the command line (its failures file too). A missing
    px_per_mm likewise."""
    folder = _trials(tmp_path / "t", movie, ("85V_sample1.tif", "trialA.tif"))
    _, rows, failed = track_batch(folder, tmp_path / "o.csv", px_per_mm=movie.px_per_mm)
    reasons = {Path(t).name: why for t, why in failed}
    assert not rows and "give fps, or fps or times in the trial's sidecar" in reasons["85V_sample1.tif"], reasons
    assert reasons["trialA.tif"].endswith("or give pattern") and not any("--" in r for r in reasons.values())
    with pytest.raises(fs.ParameterError, match="give px_per_mm or put it in the sidecar"):
        track_batch(folder, tmp_path / "o.csv")
    assert main(["track-batch", str(folder), "--px-per-mm", str(movie.px_per_mm), "--out", str(tmp_path / "c.csv"),
                 "--quiet"]) == 1
    typed = {Path(r["trial"]).name: r["reason"] for r in _rows(tmp_path / "c_failed.csv")}
    assert "give --fps, or fps" in typed["85V_sample1.tif"] and typed["trialA.tif"].endswith("or give --pattern")
    assert main(["track-batch", str(folder), "--out", str(tmp_path / "c.csv"), "--quiet"]) == 2
    assert "give --px-per-mm or put it in the sidecar" in capsys.readouterr().err


def test_batch_of_which_no_trial_is_tracked_writes_no_csv_of_descriptors(movie, tmp_path, capsys):
    """Every trial fails (TIFF stacks without a frame rate): the CSV of descriptors was written
    with its header alone, which the fitting reads as a batch of no trials. Now none is written
    (an earlier run's file is left as it was), the failures file is, and the command says in
    one line that no trial was tracked, exit 1."""
    folder = _trials(tmp_path / "t", movie, ("80V_sample1.tif", "85V_sample2.tif"))
    out = tmp_path / "trials.csv"
    _, rows, failed = track_batch(folder, out, px_per_mm=movie.px_per_mm)
    assert not rows and len(failed) == 2 and not out.exists()
    assert len(_rows(tmp_path / "trials_failed.csv")) == 2
    rc = main(["track-batch", str(folder), "--px-per-mm", str(movie.px_per_mm), "--out", str(out), "--quiet"])
    cap = capsys.readouterr()
    said = [ln for ln in cap.err.splitlines() if "no trial was tracked" in ln]
    assert rc == 1 and not out.exists() and len(said) == 1 and "wrote" not in cap.out, cap
    assert "trials_failed.csv" in said[0] and str(out) in said[0]
    # an earlier run's descriptors stay as they were
    assert main(["track-batch", str(folder), "--px-per-mm", str(movie.px_per_mm), "--fps", "50", "--last", "3",
                 "--out", str(out), "--quiet"]) == 0
    before = out.read_bytes()
    assert main(["track-batch", str(folder), "--px-per-mm", str(movie.px_per_mm), "--out", str(out), "--quiet"]) == 1
    assert out.read_bytes() == before and "an earlier run's" in capsys.readouterr().err


def test_a_bad_time_is_named_as_a_plain_number():
    """The frames' times checked: the value in the message is the number given, not a numpy
    repr (``np.float64(-0.02)``)."""
    from flutterswim._validate import ParameterError
    from flutterswim.tracking.track import _frame_times

    with pytest.raises(ParameterError) as e:
        _frame_times([0.0, -0.02, 0.04], 3)
    assert "times[1]=-0.02 follows times[0]=0.0" in str(e.value) and "np." not in str(e.value)
    with pytest.raises(ParameterError) as e:
        _frame_times(np.array([0.0, np.nan]), 2)
    assert "times[1]=nan must be finite" in str(e.value)


def test_every_reason_the_centreline_fit_gives_is_listed_in_the_failure_list():
    """A frame's reason is the centreline fit's own where track_frame does not reword it ("too
    short", "tips not found"): each is in the module docstring's list of failures."""
    import inspect
    import re

    from flutterswim.tracking import centreline

    track_module = importlib.import_module("flutterswim.tracking.track")  # (the package's track is the function)

    src = inspect.getsource(centreline.fit_centreline)
    reasons = set(re.findall(r'False, "([^"]+)"\)', src))
    assert {"too short", "tips not found"} <= reasons
    reworded = {"gap in the ridge", "lost ridge"}  # track_frame's "gap: ..." and "lost contrast: ..."
    assert reworded <= reasons
    for r in reasons - reworded:
        assert f"- {r.split(' (')[0]}:" in track_module.__doc__, r


def test_a_sidecar_of_options_only_leaves_voltage_and_sample_to_the_name(tmp_path):
    """A sidecar holding only tracking options (the field's direction) stopped the name from
    giving the voltage and sample: the trial failed with "needs the keys voltage_V and sample".
    Each key the sidecar lacks now comes from the name; a key it has wins."""
    from flutterswim.tracking.batch import find_trials

    folder = tmp_path / "t"
    folder.mkdir()
    for name in ("85V_sample1.tif", "72p5V_sample2.tif", "90V_sample3.tif"):
        (folder / name).write_bytes(b"")
    (folder / "85V_sample1.json").write_text(json.dumps({"field_angle_deg": 225}))
    (folder / "72p5V_sample2.json").write_text(json.dumps({"sample": "B"}))
    trials = {t.path.name: t for t in find_trials(folder)}
    one, two, three = trials["85V_sample1.tif"], trials["72p5V_sample2.tif"], trials["90V_sample3.tif"]
    assert (one.voltage_V, one.sample, one.problem) == (85.0, "1", ""), one
    assert one.options["field_angle_deg"] == 225
    assert (two.voltage_V, two.sample) == (72.5, "B") and (three.voltage_V, three.sample) == (90.0, "3")


def test_batch_fps_does_not_override_a_movies_recorded_rate(movie, tmp_path):
    """track-batch --fps 50 had overridden an AVI recording 40 fps: the period came out 20 %
    short, without a word, though --fps is documented as the rate of trials recording none.
    A movie's recorded rate is used (a warning names the difference); a single track given a
    rate other than the recorded one uses it, and warns."""
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    folder = tmp_path / "t"
    folder.mkdir()
    lo, hi = np.percentile(movie.frames, [0.1, 99.99])
    f8 = np.clip((movie.frames - lo) / (hi - lo) * 255, 0, 255).astype(np.uint8)
    H, W = f8.shape[1] // 2 * 2, f8.shape[2] // 2 * 2
    w = imageio_ffmpeg.write_frames(str(folder / "80V_sample1.avi"), (W, H), fps=40, codec="ffv1",
                                    pix_fmt_in="gray", pix_fmt_out="gray", macro_block_size=1)
    w.send(None)
    for f in f8:
        w.send(np.ascontiguousarray(f[:H, :W]))
    w.close()
    per_frame = FPS / 5.0  # the wave's stroke in frames (5 Hz rendered at 50 frames per second)
    with pytest.warns(UserWarning, match="records 40 fps, used"):
        _, rows, failed = track_batch(folder, tmp_path / "o.csv", px_per_mm=movie.px_per_mm, fps=FPS, n_last=3)
    assert not failed and rows[0]["period_s"] == pytest.approx(per_frame / 40.0, rel=0.01)
    with pytest.warns(UserWarning, match="records 40 fps"):
        tr = track(folder / "80V_sample1.avi", px_per_mm=movie.px_per_mm, fps=FPS)
    assert tr.meta["fps"] == FPS


def test_batch_warns_where_a_sidecar_overrides_or_lengths_disagree(movie, tmp_path):
    """A sidecar's voltage beside a name giving another, and a sidecar's px_per_mm 30 % off the
    command line's, were used without a word; so one batch held body lengths of 5.28 and 3.70
    mm, unflagged. Each is warned of (the sidecar's value is still used)."""
    from flutterswim.tracking.batch import find_trials

    folder = _trials(tmp_path / "t", movie, ("80V_sample1.tif", "85V_sample2.tif"))
    (folder / "85V_sample2.json").write_text(json.dumps({"voltage_V": 90, "sample": "2",
                                                        "px_per_mm": 1.3 * movie.px_per_mm}))
    with pytest.warns(UserWarning, match="gives voltage 90, its name '85'"):
        trials = find_trials(folder)
    assert [t.voltage_V for t in trials] == [80.0, 90.0]
    (folder / "85V_sample2.json").write_text(json.dumps({"voltage_V": 90}))  # the voltage alone
    with pytest.warns(UserWarning, match="gives voltage 90, its name '85'"):
        find_trials(folder)
    (folder / "85V_sample2.json").write_text(json.dumps({"voltage_V": 90, "sample": "2",
                                                        "px_per_mm": 1.3 * movie.px_per_mm}))
    with pytest.warns(UserWarning) as got:
        _, rows, failed = track_batch(folder, tmp_path / "o.csv", px_per_mm=movie.px_per_mm, fps=FPS, n_last=3)
    said = " ".join(str(w.message) for w in got)
    assert not failed and "its sidecar's px_per_mm" in said and "body length more than 10 %" in said
    assert rows[1]["body_length_mm"] == pytest.approx(rows[0]["body_length_mm"] / 1.3, rel=0.02)


def test_an_interrupted_batch_keeps_the_trials_tracked(movie, tmp_path, monkeypatch):
    """Interrupted after 2 of 3 trials, a batch kept nothing: every trial was tracked again. The
    trials tracked are written (CSV, signed) beside the batch's CSV, never over it (a complete CSV
    of an earlier run is kept as it was), before the interrupt goes on, which says so."""
    from flutterswim._paths import is_ours

    real = trk.track
    calls = []

    def stop_at_third(source, **kw):
        calls.append(source)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(source, **kw)

    folder = _trials(tmp_path / "t", movie, ("80V_sample1.tif", "85V_sample2.tif", "90V_sample3.tif"))
    out = tmp_path / "o.csv"
    track_batch(folder, out, px_per_mm=movie.px_per_mm, fps=FPS, n_last=3)  # a complete batch first
    before = out.read_bytes()
    monkeypatch.setattr(trk, "track", stop_at_third)
    with pytest.raises(KeyboardInterrupt, match=r"after 2 of 3 trials \(2 tracked\).*o_interrupted.csv"):
        track_batch(folder, out, px_per_mm=movie.px_per_mm, fps=FPS, n_last=3)
    part = tmp_path / "o_interrupted.csv"
    assert [r["sample"] for r in _rows(part)] == ["1", "2"] and is_ours(part)
    assert out.read_bytes() == before
    monkeypatch.setattr(trk, "track", real)
    track_batch(folder, out, px_per_mm=movie.px_per_mm, fps=FPS, n_last=3)  # complete: the partial CSV goes
    assert not part.exists()
