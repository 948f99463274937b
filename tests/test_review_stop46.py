"""Stop 46: items left at stop 45 (bad brackets, reasons in CSV files)."""

import pytest

import flutterswim as fs
from flutterswim._validate import ParameterError
from flutterswim.orbits.linear import hopf_point


@pytest.mark.parametrize("bracket", [(float("nan"), 1.0), (1.0,), "ab", (0.5, 0.5), (0.5, float("inf"))])
def test_a_bad_bracket_names_the_bracket(bracket):
    """(nan, 1) had been reported as kappa_E_ratio=nan, a value the user never gave."""
    with pytest.raises(ParameterError, match=r"^bracket="):
        hopf_point(fs.PAPER, bracket=bracket, n_segments=12)


def test_continuing_across_zero_field_names_the_mirror_branch():
    """From chi = -70.67 towards +100 the branch from -48 cannot get there; the error named only
    that Hopf point, although the mirror branch from +48 holds chi = 100."""
    from flutterswim.orbits.continuation import continue_orbits
    from flutterswim.orbits.linear import hopf_point
    from flutterswim.params import Groups

    g = Groups(eta_par=41.49, eta_perp=71.52, chi=-70.67)
    hp = hopf_point(g, "chi", n_segments=16)
    with pytest.raises(ParameterError) as e:
        continue_orbits(g, "chi", 100.0, n_points=3, n_segments=16)
    assert f"mirror branch from {-hp.value:.6g}" in str(e.value)
    with pytest.raises(ParameterError) as e:  # on its own side: no mirror to name
        continue_orbits(g, "chi", -10.0, n_points=3, n_segments=16)
    assert "mirror" not in str(e.value)


def test_a_truncated_avi_says_so(tmp_path):
    """ffmpeg estimates a cut AVI's length from its size, so 140 of 200 frames were read as a
    whole movie of 140. The header's count tells."""
    import warnings

    import imageio_ffmpeg
    import numpy as np

    from flutterswim.tracking.io import open_frames

    W, H, n = 128, 96, 200
    rng = np.random.default_rng(0)
    full = tmp_path / "full.avi"
    w = imageio_ffmpeg.write_frames(str(full), (W, H), fps=50, codec="ffv1", pix_fmt_in="gray",
                                    pix_fmt_out="gray", macro_block_size=1)
    w.send(None)
    for i in range(n):
        a = rng.integers(0, 60, (H, W)).astype(np.uint8)
        a[:, i % W] = 200
        w.send(a.tobytes())
    w.close()
    cut = tmp_path / "cut.avi"
    data = full.read_bytes()
    cut.write_bytes(data[: len(data) * 7 // 10])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(open_frames(full)) == n
    with pytest.warns(UserWarning, match=r"the file is truncated \((\d+) of the (\d+) bytes") as rec:
        m = len(open_frames(cut))
    said = str(rec[0].message)
    assert 0 < m < n and f"the {m} frames" in said and f"{cut.stat().st_size} of the {len(data)} bytes" in said


def test_an_avi_with_dropped_frame_chunks_is_not_called_truncated(tmp_path):
    """Capture software writes a dropped frame as an empty chunk: the header counts it, the
    decoder gives nothing for it. Such a complete file had been called truncated."""
    import subprocess
    import warnings

    import imageio_ffmpeg

    from flutterswim.tracking.io import open_frames

    ff = imageio_ffmpeg.get_ffmpeg_exe()
    out = tmp_path / "gap.avi"
    subprocess.run([ff, "-v", "error", "-f", "lavfi", "-i", "testsrc=size=160x120:rate=50", "-frames:v", "100",
                    "-vf", r"select='not(between(n\,40\,44))'", "-fps_mode", "passthrough", "-c:v", "mjpeg",
                    str(out)], check=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(open_frames(out)) == 100  # (100 written after the 5 dropped: the header lists 105)


def test_field_start_after_the_run_is_refused(tmp_path, capsys):
    """--field-start 50 with --t-end 5 ran, its field never turning, without a word."""
    from flutterswim.cli import main

    out = tmp_path / "r.nc"
    assert main(["simulate", "--t-end", "5", "--field-rotate", "10", "--field-start", "50", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--field-start=50.0" in err and "--t-end=5.0" in err and not out.exists()


def test_describe_of_a_turning_field_says_why_there_is_no_limit_cycle():
    """A field turning at a changing rate over the cycles described: no limit cycle, and the
    advice is not to simulate longer (a longer run turns on) but that the field turns."""
    import numpy as np

    from flutterswim.analysis.descriptors import describe
    from flutterswim.field import Field, Piecewise

    f = Field(direction=Piecewise(np.array([0, 9, 11, 13, 16.0]), np.radians([0, 0, 20, 25, 60.0]), kind="linear"))
    d = describe(fs.simulate(fs.PAPER, 16.0, n_segments=16, field=f))
    assert not d.limit_cycle
    assert d.note.startswith("no limit cycle: the field turns by") and "simulate longer" not in d.note


def test_describe_of_a_field_step_says_why_the_turning_figures_are_nan():
    import math

    from flutterswim.analysis.descriptors import describe
    from flutterswim.steering.schedules import _step

    d = describe(fs.simulate(fs.PAPER, 14.0, n_segments=16, field=_step(math.radians(10), 11.0, 0.0)))
    assert math.isnan(d.turning_radius_mm)
    assert "the field turns by 10 deg in the record, but not steadily" in d.note


def test_paper_cost_takes_a_descriptor_without_spread(tmp_path, monkeypatch, capsys):
    """Three trials with the same period (frame quantisation): the error suggests --paper-cost,
    which then failed on the zero SEM with an API message. It must fit, and say the standard
    errors are missing."""
    import importlib
    import json

    from flutterswim.cli import main
    from flutterswim.fitting import to_identifiable
    from flutterswim.fitting.surrogate import ScalingSurrogate

    sur = ScalingSurrogate(fs.PAPER)
    y = sur(to_identifiable(fs.PAPER, 1.9e-14, 0.38, 19e3))
    fit_module = importlib.import_module("flutterswim.fitting.fit")
    real = fit_module.fit
    monkeypatch.setattr(fit_module, "fit", lambda *a, **kw: real(*a, **{**kw, "model": sur}))
    rows = [f"70,s{i},{y[0]:.9g},{y[1] * (1 + d):.9g},{y[2] * (1 + d):.9g}" for i, d in enumerate((-0.01, 0.0, 0.01))]
    csv = tmp_path / "t.csv"
    csv.write_text("voltage_V,sample,period_s,advance_mm,lateral_mm\n" + "\n".join(rows) + "\n")
    out = tmp_path / "f.json"
    assert main(["fit", str(csv), "--preset", "paper", "--out", str(out)]) == 2  # the SEM cost: refused
    assert "--paper-cost" in capsys.readouterr().err
    assert main(["fit", str(csv), "--preset", "paper", "--paper-cost", "--out", str(out)]) == 0
    assert "fitted without standard errors" in capsys.readouterr().err
    assert json.loads(out.read_text())["values"]["B_N_m2"] > 0


def test_voltages_equal_within_tolerance_are_one_group(tmp_path):
    from flutterswim.fitting.data import read_trials, summarise

    csv = tmp_path / "t.csv"
    csv.write_text("voltage_V,sample,period_s,advance_mm,lateral_mm\n85,a,0.40,0.30,1.0\n85.0000001,b,0.42,0.32,1.1\n"
                   "85,c,0.41,0.31,1.2\n90,d,0.38,0.35,1.3\n")
    s = summarise(read_trials(csv))
    assert s.voltage_V.tolist() == [85.0, 90.0] and s.n.tolist() == [3, 1]
    mean, _ = s.at(85)
    assert mean[0] == pytest.approx(0.41)


def test_fit_given_a_netcdf_file_points_to_the_trials_csv(tmp_path, capsys):
    from flutterswim.cli import main

    run = fs.simulate(fs.PAPER, 0.05, n_segments=8)
    nc = tmp_path / "run.nc"
    run.save(nc)
    assert main(["fit", str(nc), "--out", str(tmp_path / "f.json")]) == 2
    err = capsys.readouterr().err
    assert "is a NetCDF file" in err and "track-batch" in err


def test_fit_cli_passes_its_seed_and_refuses_a_negative_one(tmp_path, monkeypatch, capsys):
    import importlib

    from flutterswim.cli import main

    csv = tmp_path / "t.csv"
    csv.write_text("voltage_V,sample,period_s,advance_mm,lateral_mm\n85,a,0.40,0.30,1.0\n85,b,0.42,0.32,1.1\n"
                   "85,c,0.41,0.31,1.2\n")
    out = str(tmp_path / "f.json")
    assert main(["fit", str(csv), "--seed", "-1", "--out", out]) == 2
    assert "--seed=-1" in capsys.readouterr().err
    seen = {}

    def fake(*a, **kw):
        seen.update(kw)
        raise fs.ParameterError("stop here")

    monkeypatch.setattr(importlib.import_module("flutterswim.fitting.fit"), "fit", fake)
    main(["fit", str(csv), "--seed", "7", "--bootstrap", "3", "--out", out])
    assert seen["seed"] == 7 and seen["bootstrap"] == 3


def _branches(x, up, down, pu=None, pd=None):
    import numpy as np
    import xarray as xr

    ds = xr.Dataset({"limit_cycle": (("chi", "branch"), np.column_stack([up, down]))},
                    coords={"chi": np.asarray(x, float), "branch": ["up", "down"]})
    if pu is not None:
        ds["period_s"] = (("chi", "branch"), np.column_stack([pu, pd]))
    return ds


def test_hysteresis_of_a_subcritical_onset_and_of_a_fold():
    """The down branch swimming below the up branch's onset (a subcritical Hopf point, bistable at
    49.8 and 50.4) had read 'no hysteresis' (its bracket NaN), and so had a fold where both swim
    on different strokes."""
    import numpy as np

    from flutterswim.sweep import hysteresis

    nan = float("nan")
    sub = hysteresis(_branches([49.8, 50.4, 50.9, 51.5, 53.0], [0, 0, 1, 1, 1], [1, 1, 1, 1, 1]))
    assert sub["hysteresis"] and sub["bistable"] == [49.8, 50.4] and sub["up"] == (50.4, 50.9)
    fold = hysteresis(_branches([1.85, 1.95, 2.05, 2.15, 2.3], [1] * 5, [1] * 5,
                                [0.27, 0.2589, 0.2561, 0.36, 0.35], [0.27, 0.3439, 0.3514, 0.36, 0.35]))
    assert fold["hysteresis"] and fold["bistable"] == [1.95, 2.05] and fold["width"] == pytest.approx(0.1)
    # a failed or undone point's flag reads False: no hysteresis from it
    failed = _branches([1.0, 2.0, 3.0, 3.5], [0, 0, 1, 1], [0, 0, 0, 1])
    failed["failed"] = (("chi", "branch"), np.array([[0, 0], [0, 0], [0, 1], [0, 0]], bool))
    failed["done"] = (("chi", "branch"), np.array([[1, 1], [1, 1], [1, 1], [1, 1]], bool))
    h = hysteresis(failed)
    assert not h["hysteresis"] and h["up"] == (2.0, 3.0) and h["down"] == (2.0, 3.5)  # (skips the failed point)
    failed["failed"] = failed["failed"] * False
    failed["done"] = (("chi", "branch"), np.array([[1, 0], [1, 0], [1, 0], [1, 1]], bool))
    assert not hysteresis(failed)["hysteresis"]
    same = hysteresis(_branches([0.6, 0.7, 0.8], [0, 1, 1], [0, 1, 1], [nan, 0.45, 0.42], [nan, 0.45, 0.42]))
    assert not same["hysteresis"] and same["width"] == 0.0 and same["up"] == same["down"] == (0.6, 0.7)


def test_a_sweep_row_gives_a_direction_in_the_half_open_range():
    """A stroke swimming against the field read -180 at one point and 180 at the next."""
    import math
    from types import SimpleNamespace

    from flutterswim.settle import Settled

    for angle in (-math.pi, math.pi, -math.pi + 1e-12):
        o = SimpleNamespace(period=1.0, advance=0.1, speed=0.1, lateral_leading=0.1, lateral_trailing=0.2,
                            nonreciprocity=0.0, self_intersecting=False, stable=True, max_multiplier=0.5,
                            swim_direction=angle)
        st = Settled("limit_cycle", "", None, o, True, 1.0, 0.1, 1.0, 0.1, 10.0, units="dimensionless")
        assert st.values()["swim_direction_deg"] == pytest.approx(180.0)


def test_a_chain_of_close_voltages_counts_each_trial_once(tmp_path):
    from flutterswim.fitting.data import read_trials, summarise

    csv = tmp_path / "t.csv"
    rows = ["85,a,0.40,0.30,1.0", "85.0008,b,0.41,0.31,1.1", "85.0016,c,0.42,0.32,1.2", "85.0016,d,0.43,0.33,1.3",
            "90,e,0.38,0.35,1.3", "90,f,0.39,0.36,1.4"]
    csv.write_text("voltage_V,sample,period_s,advance_mm,lateral_mm\n" + "\n".join(rows) + "\n")
    s = summarise(read_trials(csv))
    assert int(s.n.sum()) == 6


def test_an_avi_written_to_a_pipe_is_not_called_truncated(tmp_path):
    """Written to a pipe, ffmpeg cannot seek back: the RIFF size stays 0xFFFFFFFF, which says
    nothing of the file's length (it had been called truncated, 91 kB of 4 GB)."""
    import subprocess
    import warnings

    import imageio_ffmpeg

    from flutterswim.tracking.io import open_frames

    out = tmp_path / "pipe.avi"
    with open(out, "wb") as fh:
        subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-f", "lavfi", "-i",
                        "testsrc=size=64x48:rate=25", "-t", "2", "-c:v", "mjpeg", "-f", "avi", "pipe:1"],
                       stdout=fh, check=True)
    assert out.read_bytes()[4:8] == b"\xff\xff\xff\xff"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(open_frames(out)) == 50
