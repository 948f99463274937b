"""Sizes that asked for gigabytes or ran without end are refused by name, before any work (a
review: --segments 10^5 allocated 74.5 GiB per sweep point, --steps 10^7, --sigma 10^6 and
--bootstrap 10^9 ran on); a binary file given as a CSV is refused by name (exit 2, not a
UnicodeDecodeError with exit 1)."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim._validate import MAX_SEGMENTS
from flutterswim.cli import main


def test_segments_are_bounded_everywhere():
    from flutterswim.orbits.continuation import continue_orbits
    from flutterswim.orbits.periodic import periodic_orbit
    from flutterswim.sweep.spec import PointSettings

    big = MAX_SEGMENTS + 1
    for call in (lambda: fs.simulate(fs.PAPER, 0.01, n_segments=big),
                 lambda: periodic_orbit(fs.PAPER, n_segments=big),
                 lambda: continue_orbits(fs.PAPER, "kappa_E_ratio", 1.5, n_segments=big),
                 lambda: PointSettings(n_segments=big)):
        with pytest.raises(fs.ParameterError, match=rf"n_segments={big} must be an integer in \[4, {MAX_SEGMENTS}\]"):
            call()
    assert fs.simulate(fs.PAPER, 1e-4, n_segments=8).ok  # (small ones as before)


@pytest.mark.parametrize("argv,name", [
    (["simulate", "--segments", "100000"], "--segments"),
    (["sweep", "kappa_E_ratio=1,2", "--n-segments", "100000"], "--n-segments"),
    (["branch", "kappa_E_ratio=1.5:2", "--steps", "10000000"], "--steps"),
    (["fit", "TRIALS", "--bootstrap", "1000000000"], "--bootstrap"),
])
def test_the_cli_refuses_sizes_in_one_line(tmp_path, capsys, argv, name):
    trials = tmp_path / "t.csv"
    trials.write_text("voltage_V,sample,period_s,advance_mm,lateral_mm\n85,a,0.38,0.39,1.1\n85,b,0.37,0.40,1.2\n")
    argv = [str(trials) if a == "TRIALS" else a for a in argv]
    suffix = {"sweep": ".zarr", "fit": ".json"}.get(argv[0], ".nc")
    assert main(argv + ["--out", str(tmp_path / f"o{suffix}")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and name.lstrip("-").replace("-", "_") in err.replace("-", "_")
    assert not (tmp_path / f"o{suffix}").exists()


def test_track_refuses_a_filter_wider_than_a_line_and_too_many_samples(tmp_path):
    from flutterswim.tracking import track

    frames = np.zeros((3, 20, 20))
    with pytest.raises(fs.ParameterError, match="sigma=1000000.0"):
        track(frames, px_per_mm=70.0, fps=50.0, sigma=1e6)
    with pytest.raises(fs.ParameterError, match="n_points=100000000"):
        track(frames, px_per_mm=70.0, fps=50.0, n_points=10**8)


def test_a_binary_csv_is_refused_by_name(tmp_path, capsys):
    blob = tmp_path / "b.csv"
    blob.write_bytes(bytes(range(128, 256)) * 8)
    assert main(["simulate", "--t-end", "0.01", "--segments", "8", "--field-csv", str(blob), "--out",
                 str(tmp_path / "x.nc"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "b.csv" in err and "not a text" in err and err.count("\n") == 1
    from flutterswim.steering.path import waypoints_csv

    with pytest.raises(fs.ParameterError, match="not a text"):
        waypoints_csv(blob, 1e-3)


def test_inputs_once_taken_silently_are_refused_by_name(tmp_path):
    """A review's silent acceptances: an empty sweep value ("1,,2" ran 2 points), a preset
    given as a list (TypeError), continuation's max_newton=0, fps contradicting the frames'
    times (dropped without a word), sidecar values of the wrong JSON type (true read as 1.0)."""
    import json

    from flutterswim.orbits.continuation import continue_orbits
    from flutterswim.sweep.spec import parse_axis
    from flutterswim.tracking import track
    from flutterswim.tracking.batch import find_trials

    with pytest.raises(fs.ParameterError, match="empty value"):
        parse_axis("kappa_E_ratio=1,,2")
    assert parse_axis("kappa_E_ratio=1,2,").values == (1.0, 2.0)
    with pytest.raises(fs.ParameterError, match="preset"):
        fs.preset(["paper"])
    with pytest.raises(fs.ParameterError, match="max_newton"):
        continue_orbits(fs.PAPER, "kappa_E_ratio", 1.5, max_newton=0)
    frames = np.zeros((4, 20, 20))
    with pytest.raises(fs.ParameterError, match="disagrees with the frames' times"):
        track(frames, px_per_mm=70.0, fps=10.0, times=[0.0, 0.02, 0.04, 0.06])
    folder = tmp_path / "trials"
    folder.mkdir()
    (folder / "a.tif").write_bytes(b"")
    for bad in ({"px_per_mm": True}, {"px_per_mm": "71"}, {"fps": 50, "times": [0, 0.02]}):
        (folder / "a.json").write_text(json.dumps({"voltage_V": 85, "sample": "s1", **bad}))
        with pytest.raises(fs.ParameterError, match="a.json"):
            find_trials(folder)
    (folder / "a.json").write_text(json.dumps({"voltage_V": 85, "sample": ["s1", "s2"]}))
    assert "sample a name" in find_trials(folder)[0].problem


def test_fit_and_reproduce_refuse_what_they_would_have_ignored(tmp_path, capsys):
    """--workers without --backend was ignored; a row with more fields than the header had its
    extras dropped; a bad trials CSV given to reproduce with --only table1 was not read."""
    from flutterswim.fitting import read_trials

    good = "voltage_V,sample,period_s,advance_mm,lateral_mm\n85,a,0.38,0.39,1.1\n85,b,0.37,0.40,1.2\n"
    (tmp_path / "t.csv").write_text(good)
    assert main(["fit", str(tmp_path / "t.csv"), "--workers", "2", "--out", str(tmp_path / "f.json")]) == 2
    assert "--backend" in capsys.readouterr().err
    (tmp_path / "r.csv").write_text(good + "85,c,0.38,0.39,1.1,7,8\n")
    with pytest.raises(fs.ParameterError, match="row 4 has 7 fields under a header of 5"):
        read_trials(tmp_path / "r.csv")
    (tmp_path / "bad.csv").write_text("voltage_V,sample\n85,a\n")
    assert main(["reproduce", "--out", str(tmp_path / "rep"), "--only", "table1", "--trials",
                 str(tmp_path / "bad.csv")]) == 2
    assert "lacks the column" in capsys.readouterr().err and not (tmp_path / "rep").exists()


def test_scales_no_experiment_has_are_refused(tmp_path):
    """A review: px_per_mm 1e-300 tracked a body of 2.6e302 mm, noise_px 1e12 was scored,
    look_beyond 1e9 was taken."""
    from flutterswim.orbits.continuation import continue_orbits
    from flutterswim.steering.path import circle
    from flutterswim.steering.steer import steer
    from flutterswim.tracking import track

    with pytest.raises(fs.ParameterError, match="px_per_mm=1e-300"):
        track(np.zeros((3, 20, 20)), px_per_mm=1e-300, fps=50.0)
    with pytest.raises(fs.ParameterError, match="noise_px=1000000000000.0"):
        steer(fs.PAPER, lambda p, h: circle(2 * fs.PAPER.l, p, h), None, noise_px=1e12)
    with pytest.raises(fs.ParameterError, match="look_beyond=1000000000.0"):
        continue_orbits(fs.PAPER, "kappa_E_ratio", 1.5, look_beyond=1e9)
    assert main(["branch", "kappa_E_ratio=1.5:2", "--look-beyond", "1e9", "--out", str(tmp_path / "b.nc")]) == 2


def test_trials_rows_must_match_their_header(tmp_path):
    """A trailing comma is no field; a row short of a column is refused (with a comment column
    it was read shifted: sample '0.37', period 0.40)."""
    from flutterswim.fitting import read_trials

    head = "voltage_V,sample,period_s,advance_mm,lateral_mm"
    (tmp_path / "a.csv").write_text(f"{head}\n85,a,0.38,0.39,1.1,\n85,b,0.37,0.40,1.2,\n")
    assert read_trials(tmp_path / "a.csv").values.shape == (2, 3)
    (tmp_path / "b.csv").write_text(f"{head},comment\n85,a,0.38,0.39,1.1,ok\n85,0.37,0.40,1.2,0.9\n")
    with pytest.raises(fs.ParameterError, match="row 3 has 5 fields under a header of 6"):
        read_trials(tmp_path / "b.csv")


def test_a_batch_trial_with_its_own_times_ignores_the_batch_fps(tmp_path, monkeypatch):
    """track-batch --fps 50 with a trial whose sidecar gives its times (48.5 fps): the times
    set the trial's rate (it was refused as disagreeing with --fps)."""
    import importlib
    import json

    batch = importlib.import_module("flutterswim.tracking.batch")
    track_module = importlib.import_module("flutterswim.tracking.track")
    seen = {}

    def fake_track(path, px_per_mm=None, fps=None, **kw):
        seen.update(fps=fps, times=kw.get("times"))
        raise RuntimeError("stop here")

    monkeypatch.setattr(track_module, "track", fake_track)
    folder = tmp_path / "trials"
    folder.mkdir()
    (folder / "a.tif").write_bytes(b"")
    times = np.arange(5) / 48.5
    (folder / "a_times.txt").write_text("\n".join(f"{t:.9f}" for t in times) + "\n")
    (folder / "a.json").write_text(json.dumps({"voltage_V": 85, "sample": "s", "px_per_mm": 71.4,
                                               "times": "a_times.txt"}))
    batch.track_batch(folder, tmp_path / "out.csv", fps=50.0, progress=False)  # (the trial fails here)
    assert seen["fps"] is None and np.allclose(seen["times"], times)
