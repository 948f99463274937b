"""Bad sizes and ranges are refused before anything is computed or allocated, one line naming
the option, exit 2; a failed computation reports on stderr (exit 1)."""

import re
import time
import warnings

import numpy as np
import pytest

import flutterswim as fs
from flutterswim import defaults
from flutterswim.cli import main


def _run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _one_line(err, *words):
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


def test_simulate_refuses_a_t_end_whose_frames_exceed_the_limit_before_allocating(tmp_path, capsys):
    """--t-end 1e7 reached 6.6 GB in 15 s (5e9 frames at 50 per tau); the bound follows from
    the frame rate: the longest allowed run is (MAX_FRAMES - 1) / (FRAMES_PER_TAU / tau)."""
    tau = fs.preset("paper").tau
    longest = (defaults.MAX_FRAMES - 1) * tau / defaults.FRAMES_PER_TAU
    t0 = time.perf_counter()
    code, out, err = _run(capsys, "simulate", "--t-end", "1e7", "--segments", "24", "--out", str(tmp_path / "h.nc"))
    assert code == 2 and out == "" and time.perf_counter() - t0 < 5
    line = _one_line(err, "--t-end=", str(defaults.MAX_FRAMES))
    assert f"{longest:.6g}" in line
    assert not (tmp_path / "h.nc").exists()
    # the API: the same bound, in the run's time unit; just inside it is accepted by the check
    with pytest.raises(fs.ParameterError, match=r"t_end=.*at most 500000"):
        fs.simulate(fs.preset("paper"), 1e7, n_segments=24)
    from flutterswim.simulate import _frames

    assert _frames(0.0, longest / tau, None, None).size <= defaults.MAX_FRAMES
    with pytest.raises(fs.ParameterError, match="frame_dt"):
        _frames(0.0, 1.0, None, 1e-7, tau)
    with pytest.raises(fs.ParameterError, match="n_frames=1000000000 is too many"):
        fs.simulate(fs.preset("paper"), 1.0, n_frames=10**9)


@pytest.mark.parametrize("opt,value", [("--rtol", "10"), ("--rtol", "0.5"), ("--atol", "1"), ("--rtol", "0")])
def test_simulate_tolerances_must_be_in_range(tmp_path, capsys, opt, value):
    code, out, err = _run(capsys, "simulate", opt, value, "--t-end", "1", "--out", str(tmp_path / "r.nc"))
    assert code == 2
    _one_line(err, f"{opt}={float(value)!r}")
    assert not (tmp_path / "r.nc").exists()


def test_api_tolerances_must_be_in_range():
    with pytest.raises(fs.ParameterError, match=r"rtol=10.*\(0, 0.1\]"):
        fs.simulate(fs.preset("paper"), 1.0, rtol=10)
    from flutterswim.sweep.spec import PointSettings

    with pytest.raises(fs.ParameterError, match="atol"):
        PointSettings(atol=1.0)
    assert PointSettings(rtol=0.1).rtol == 0.1


def test_simulate_failure_goes_to_stderr(tmp_path, capsys):
    """--kappa-E-ratio 1e9: the failure was printed on stdout. (Its step size collapsed within a
    second while the mobility solve was unstable on the kinks this makes; solved stably, the run
    took 9.2 million legitimate steps of 5e-9 tau in 110 s before "maximum number of steps";
    now it says "too stiff" a tenth of the way in.)"""
    code, out, err = _run(capsys, "simulate", "--kappa-E-ratio", "1e9", "--t-end", "1", "--segments", "12",
                          "--quiet", "--out", str(tmp_path / "k.nc"))
    assert code == 1 and out == ""
    _one_line(err, "flutterswim simulate:", "failed")
    assert "too stiff" in err and "max_steps=" in err


@pytest.mark.parametrize("suffix,limit", [(".gif", 100.0), (".mp4", 240.0)])
def test_animate_refuses_a_frame_rate_beyond_the_format(tmp_path, capsys, suffix, limit):
    """--fps 1e9 ran out of memory building the list of video frames (exit 1)."""
    run = fs.simulate(fs.preset("paper"), 0.2, n_segments=8)
    nc = run.save(tmp_path / "run.nc")
    for fps in ("1e9", str(limit * 1.01)):
        code, out, err = _run(capsys, "animate", str(nc), str(tmp_path / f"a{suffix}"), "--fps", fps, "--quiet")
        assert code == 2
        _one_line(err, f"--fps={float(fps)!r}", f"{limit:g}")
        assert not (tmp_path / f"a{suffix}").exists()
    from flutterswim.plotting.animation import MAX_VIDEO_FRAMES

    with pytest.raises(fs.ParameterError, match="speed="):
        fs.animate(run, tmp_path / f"b{suffix}", fps=10, speed=0.2 * 10 / (MAX_VIDEO_FRAMES * 2))


@pytest.mark.parametrize("argv,named,says", [
    (["--path", "square", "--radius", "2"], "--radius=", "--side sets the square"),
    (["--path", "circle", "--side", "3"], "--side=", "--radius sets the circle"),
    (["--path", "square", "--size", "3"], "--size=", "--side sets the square"),
    (["--path", "circle", "--waypoints", "w.csv"], "--waypoints=", "--radius sets the circle"),
])
def test_steer_refuses_the_size_option_of_another_path(tmp_path, capsys, argv, named, says):
    """--path square --radius 2 silently ignored --radius."""
    code, out, err = _run(capsys, "steer", *argv, "--out", str(tmp_path / "s.nc"),
                          "--metrics", str(tmp_path / "s.json"))
    assert code == 2
    _one_line(err, named, says)


def test_steer_refuses_too_long_a_path_before_identifying_the_model(tmp_path, capsys):
    """--path circle --radius 1e9 was refused after ~50 s (after identifying the reduced model);
    now after the periodic orbit alone. The time it states is the length over the orbit's speed."""
    from flutterswim.orbits import periodic_orbit
    from flutterswim.steering import reduced

    called = []
    orig = reduced.identify
    reduced.identify = lambda *a, **k: called.append(1) or orig(*a, **k)
    try:
        code, out, err = _run(capsys, "steer", "--path", "circle", "--radius", "1e9", "--segments", "8", "--out",
                              str(tmp_path / "e.nc"), "--metrics", str(tmp_path / "e.json"), "--quiet")
    finally:
        reduced.identify = orig
    assert code == 2 and called == []
    line = _one_line(err, "--path circle", "3600")
    orb = periodic_orbit(fs.preset("paper"), n_segments=8)
    L = fs.preset("paper").l
    est = 1.1 * 2 * np.pi * 1e9 * L / orb.speed + 3 * orb.period
    assert f"{est:.3g} s" in line


@pytest.mark.parametrize("argv,named", [
    (["--field-rotate", "0"], "--field-rotate=0"),
    (["--field-ramp", "90", "0"], "--field-ramp duration=0.0"),
    (["--field-ramp", "90", "-1"], "--field-ramp duration=-1.0"),
])
def test_field_messages_name_the_option(tmp_path, capsys, argv, named):
    code, out, err = _run(capsys, "simulate", *argv, "--t-end", "1", "--out", str(tmp_path / "f.nc"))
    assert code == 2
    line = _one_line(err, named)
    assert "seconds_per_turn" not in line and "duration=" not in line.replace("--field-ramp duration=", "")


def test_stability_message_names_out(tmp_path, capsys):
    d = tmp_path / "st"
    d.mkdir()
    (d / "eigenmodes.png").write_bytes(b"mine")
    code, out, err = _run(capsys, "stability", "--out", str(d), "--quiet")
    assert code == 2 and (d / "eigenmodes.png").read_bytes() == b"mine"
    line = _one_line(err, "--out=")
    assert "out_dir" not in line


def test_a_refused_map_grid_makes_no_folder(tmp_path):
    """stability --step 1e-6 refused the grid but first made the empty output folder."""
    from flutterswim.stability import stability_figures

    with pytest.raises(fs.ParameterError, match=r"step=1e-06 gives a map of"):
        stability_figures(tmp_path / "st3", step=1e-6)
    assert not (tmp_path / "st3").exists()


@pytest.mark.parametrize("axis,other", [("tau=375", "ms"), ("l=3.7", "mm"), ("kappa_E=19.1", "1/mm"),
                                        ("B=1.94e-8", "N mm^2")])
def test_a_sweep_value_a_thousand_times_off_asks_about_units(axis, other):
    """sweep tau=375 (ms typed for s) and l=3.7 (mm for m) ran and recorded a straight state,
    without a word. A value within a factor 3 of 1000 (B: a million) times the base's is asked
    about; the base's own values are not."""
    from flutterswim.sweep.spec import SweepSpec

    with pytest.warns(UserWarning, match=rf"typed in {re.escape(other)}\?"):
        SweepSpec.build([axis])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        SweepSpec.build(["tau=0.2,0.375,1", "l=0.003,0.0037"])
        SweepSpec.build(["mu=0.001,0.01,0.1,1"])  # water to glycerol: decades, not a unit slip
