"""Steering: schedules, turning analysis, the reduced model against the full model, and
closed-loop path following with tracking noise and delay."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.steering import cycle_average, fit_circle, identify, rotation
from flutterswim.steering.path import _polyline, circle, square
from flutterswim.steering.reduced import follows, rotating_run
from flutterswim.steering.steer import steer

P = fs.PAPER
L = P.l


def test_schedules():
    from flutterswim.steering.schedules import Rotation, ramp, step

    r = Rotation(0.5, start=2.0)
    assert r(1.0) == 0.0 and r(4.0) == pytest.approx(1.0)
    assert r.scaled(0.5)(8.0) == pytest.approx(r(4.0))  # seen in units of 0.5 s
    s = step(0.7, at=3.0).direction
    assert s(2.9) == 0.0 and s(3.0) == pytest.approx(0.7)
    m = ramp(1.0, start=1.0, duration=2.0).direction
    assert m(0.5) == 0.0 and m(2.0) == pytest.approx(0.5) and m(9.0) == pytest.approx(1.0)
    with pytest.raises(fs.ParameterError, match="seconds_per_turn"):
        rotation(0.0)


def test_csv_schedule(tmp_path):
    from flutterswim.steering.schedules import from_csv

    f = tmp_path / "field.csv"
    f.write_text("t,angle_deg,strength\n0,0,1\n10,90,0.5\n")
    fld = from_csv(f)
    assert fld.direction(5.0) == pytest.approx(math.radians(45)) and fld.strength(5.0) == pytest.approx(0.75)
    bad = tmp_path / "bad.csv"
    bad.write_text("t,angle\n0,0\n1,x\n")
    with pytest.raises(fs.ParameterError, match="line 3"):
        from_csv(bad)
    # a non-finite entry names its file and line (it was 'values has 1 non-finite entries')
    bad.write_text("t,angle\n0,0\n1,nan\n")
    with pytest.raises(fs.ParameterError, match=r"bad.csv.*line 3.*not finite"):
        from_csv(bad)


def test_csv_schedule_units_comments_and_inconsistent_rows(tmp_path):
    """The header's units are read (t_ms, angle [rad]: 10000 and 1.5708 were read as 10000 s
    and 1.57 deg); a comment may precede the header; rows mixing 2 and 3 columns (the strength
    column was dropped) and times out of order (one long line without the file) name the line;
    a unit recognised but not taken is refused."""
    from flutterswim.steering.schedules import from_csv

    f = tmp_path / "field.csv"
    same = ["t,angle\n0,0\n10,90\n", "t_ms,angle_rad\n0,0\n10000,1.5707963267948966\n",
            "# by hand\ntime [s], angle (deg)\n0,0\n10,90\n", "t (ms),field_angle_deg\n0,0\n10000,90\n",
            # names, not units; and other spellings of the units taken
            "time,field_angle\n0,0\n10,90\n", "t_start,angle_field\n0,0\n10,90\n",
            "t (sec),angle (°)\n0,0\n10,90\n", "time (seconds),angle_degree\n0,0\n10,90\n"]
    for text in same:
        f.write_text(text)
        fld = from_csv(f)
        assert fld.direction(5.0) == pytest.approx(math.radians(45), rel=1e-12), text
        assert fld.direction(20.0) == pytest.approx(math.radians(90), rel=1e-12), text
    for text, words in [("0,0,1\n5,45\n10,90,1\n", r"field.csv.*line 2.*2 columns.*line 1 has 3"),
                        ("t,angle\n0,0\n10,90\n5,45\n", r"field.csv.*line 4.*t = 5.*line 3"),
                        ("t,angle\n0,0\n0,90\n", r"line 3.*must increase"),
                        ("t_min,angle\n0,0\n1,90\n", r"line 1.*t_min.*allowed: s, ms"),
                        ("t,angle_grad\n0,0\n1,90\n", r"angle_grad.*allowed: deg"),
                        # any unit not taken, not only those listed as refused (were read as s)
                        ("t_hours,angle_deg\n0,0\n1,90\n", r"t_hours.*in hours.*allowed: s, ms"),
                        ("t [h],angle\n0,0\n1,90\n", r"'t \[h\]'.*allowed: s, ms"),
                        ("t,angle\n", "no rows")]:
        f.write_text(text)
        with pytest.raises(fs.ParameterError, match=words):
            from_csv(f)


def test_circle_fit_and_cycle_average_are_exact():
    a = np.linspace(0, 1.5, 50)
    x, y = 3.0 + 2.0 * np.cos(a), -1.0 + 2.0 * np.sin(a)
    xc, yc, r, rms = fit_circle(x, y)
    assert (xc, yc, r) == pytest.approx((3.0, -1.0, 2.0), abs=1e-10) and rms < 1e-10
    # a straight swim with a periodic wiggle: the cycle average is the straight line
    t = np.linspace(0, 20, 4001)
    T = 0.8
    xs = 0.5 * t + 0.1 * np.sin(2 * np.pi * t / T) + 0.03 * np.cos(4 * np.pi * t / T)
    ys = 0.2 * np.sin(2 * np.pi * t / T + 0.3)
    avg = cycle_average(t, xs, ys, np.zeros_like(t), T)
    assert np.max(np.abs(avg.y)) < 1e-4 and np.max(np.abs(avg.heading)) < 1e-3
    assert np.allclose(avg.speed, 0.5, rtol=1e-3)


@pytest.fixture(scope="module")
def reduced():
    return identify(P, n_segments=24)


def test_circle_radius_is_U_over_Omega_below_half_the_step_out(reduced):
    """Rotating fields at 0.2 and 0.45 Omega_max: the cycle-averaged path is a circle of radius
    U / Omega (U from the periodic orbit) within 3 %."""
    for frac in (0.2, 0.45):
        om = frac * reduced.omega_max
        ok, d = follows(rotating_run(P, om, turns=0.4, period=reduced.period), om, reduced.U, reduced.period, 12.0)
        assert ok
        assert d.turning_radius == pytest.approx(reduced.U / om, rel=0.03)
        assert d.circle_fit_rms < 0.01 * d.turning_radius


def test_step_out_is_detected_within_5_percent(reduced):
    """Bisection brackets the step-out to 2 %; just below it the swimmer follows, 5 % above it
    it does not (it loses the stroke and turns with the field in place)."""
    lo, hi = reduced.omega_max_bracket
    assert hi / lo - 1 < 0.025
    om = 0.97 * reduced.omega_max
    assert follows(rotating_run(P, om, period=reduced.period), om, reduced.U, reduced.period, 12.0)[0]
    om = 1.05 * reduced.omega_max
    assert not follows(rotating_run(P, om, period=reduced.period), om, reduced.U, reduced.period, 12.0)[0]
    assert reduced.r_min == pytest.approx(reduced.U / reduced.omega_max)


def test_closed_loop_circle_beats_open_loop(reduced):
    make = lambda p, h: circle(2 * L, p, h)  # noqa: E731
    closed = steer(P, make, reduced, closed_loop=True, seed=1).metrics
    opened = steer(P, make, reduced, closed_loop=False, seed=1).metrics
    assert closed["cross_track_rms_bl"] <= 0.1 and closed["corner_overshoot_bl"] <= 0.3 and not closed["trapped"]
    assert closed["path_covered_fraction"] > 0.95
    assert closed["cross_track_rms_bl"] < opened["cross_track_rms_bl"]


@pytest.mark.slow
def test_closed_loop_square(reduced):
    """A square with 10-body-length sides: RMS <= 0.1 bl, corner overshoot <= 0.3 bl, never
    trapped; every corner reached; better than the open-loop schedule under the same noise."""
    make = lambda p, h: square(10 * L, p, h)  # noqa: E731
    closed = steer(P, make, reduced, closed_loop=True, seed=2).metrics
    assert closed["cross_track_rms_bl"] <= 0.1, closed
    assert closed["corner_overshoot_bl"] <= 0.3 and not closed["trapped"]
    assert all(np.isfinite(closed["waypoint_arrival_s"]))
    opened = steer(P, make, reduced, closed_loop=False, seed=2).metrics
    assert closed["cross_track_rms_bl"] < opened["cross_track_rms_bl"]


def test_simulate_cli_field_options_and_describe_turning(tmp_path):
    from flutterswim.cli import main

    out = tmp_path / "rot.nc"
    assert main(["simulate", "--t-end", "20", "--field-rotate", "60", "--field-start", "8", "--segments", "16",
                 "--out", str(out), "--quiet"]) == 0
    run = fs.load(out)
    assert run.field_angle[-1] == pytest.approx(2 * math.pi * 12 / 60)
    d = fs.describe(run, n_last=5)
    orb = fs.periodic_orbit(P, n_segments=16)
    assert d.turning_radius_mm == pytest.approx(orb.speed / (2 * math.pi / 60) * 1e3, rel=0.03)
    assert d.field_turn_rate_deg_s == pytest.approx(6.0, rel=1e-6)
    assert main(["simulate", "--field-rotate", "60", "--out", str(tmp_path / "x.nc")]) == 2


def test_lengths_in_body_lengths_or_with_units():
    from flutterswim.steering.cli import length

    assert length("--side", "10", L) == pytest.approx(10 * L)
    assert length("--side", "2bl", L) == pytest.approx(2 * L)
    assert length("--side", "37mm", L) == pytest.approx(0.037)
    assert length("--radius", "0.5 cm", L) == pytest.approx(0.005)
    for bad in ("x", "-2", "3 furlongs", "nan"):
        with pytest.raises(fs.ParameterError, match="--side"):
            length("--side", bad, L)


def test_the_trap_is_the_bent_equilibrium_family():
    """From a large tilt the filament stops in a bent equilibrium: a moment-free shape on the
    family kappa = -chi sin(theta), reached to a discretisation error that halves with h; a
    small tilt swims."""
    from flutterswim.initial import InitialState
    from flutterswim.settle import settle
    from flutterswim.steering.trap import tilt_basin

    chi, res = P.groups.chi, []
    for n in (24, 48):
        st = settle(P, initial=InitialState.straight(8.0), n_segments=n, frames_per_tau=25, n_cycles=3,
                    refine=False, t_max=60 * P.tau)
        assert st.outcome == "bent_equilibrium"
        th, k = st.run.theta[-1], st.run.kappa[-1] * P.l
        assert np.ptp(th) > 1.0  # bent, not straight
        res.append(np.max(np.abs(k[1:-1] + chi * np.sin(0.5 * (th[1:] + th[:-1])))) / chi)
    assert res[1] < 0.6 * res[0], res
    assert list(tilt_basin(P, [0.5, 8.0])) == ["limit_cycle", "bent_equilibrium"]


@pytest.mark.parametrize("seconds_per_turn", [60.0, 30.0])
def test_turning_does_not_bias_the_lateral_amplitudes(seconds_per_turn):
    """A settled straight stroke turned rigidly (each frame rotated about its centroid at a
    constant rate, the centroid path bent to match) has the same body-frame stroke: describe
    reads both ends' lateral peak-to-peak as for the straight run, within 0.5 % (it read 3-12 %
    low when measuring across fixed per-cycle directions)."""
    from scipy.integrate import cumulative_trapezoid

    from flutterswim.analysis.track import Track

    r = fs.simulate(P, 30.0, n_segments=24, frame_dt=0.02)
    d0 = fs.describe(r, n_last=10)
    m = r.t > 10.0
    t = r.t[m]
    a = 2 * math.pi / seconds_per_turn * (t - 10.0)
    xc, yc = r.x[m].mean(axis=1), r.y[m].mean(axis=1)
    c, s = np.cos(a), np.sin(a)
    vx, vy = np.gradient(xc, t), np.gradient(yc, t)
    X = cumulative_trapezoid(c * vx - s * vy, t, initial=0)[:, None]
    Y = cumulative_trapezoid(s * vx + c * vy, t, initial=0)[:, None]
    dx, dy = r.x[m] - xc[:, None], r.y[m] - yc[:, None]
    turned = Track(t=t, x=X + c[:, None] * dx - s[:, None] * dy, y=Y + s[:, None] * dx + c[:, None] * dy,
                   field_angle=a, units="m")
    d = fs.describe(turned, n_last=10)
    assert d.trailing_lateral_p2p_mm == pytest.approx(d0.trailing_lateral_p2p_mm, rel=0.005)
    assert d.leading_lateral_p2p_mm == pytest.approx(d0.leading_lateral_p2p_mm, rel=0.005)
    assert d.period_s == pytest.approx(d0.period_s, rel=1e-3)


def test_path_min_radius_matches_the_analytic_curvature():
    """Smallest radius of curvature of the reference paths (used to warn when a path is tighter
    than the swimmer's smallest turning radius): a circle's radius, a filleted square's fillet,
    and the lemniscate of Gerono's 1 / max curvature."""
    from flutterswim.steering.path import figure8, fillet, min_radius

    assert min_radius(circle(2 * L), L) == pytest.approx(2 * L, rel=2e-3)
    assert min_radius(fillet(square(10 * L), 1.1 * L), L) == pytest.approx(1.1 * L, rel=2e-3)
    u = np.linspace(0, 2 * np.pi, 200001)
    a = 4 * L  # size 8 L: x = a sin u, y = a/2 sin 2u
    k = np.abs(a * np.cos(u) * -2 * a * np.sin(2 * u) + a * np.cos(2 * u) * a * np.sin(u)) / (
        (a * np.cos(u)) ** 2 + (a * np.cos(2 * u)) ** 2) ** 1.5
    assert min_radius(figure8(8 * L), L) == pytest.approx(1 / k.max(), rel=2e-3)
    # a circle far smaller than the radius of interest (it read as straight: inf)
    assert min_radius(circle(1e-3 * L), L) == pytest.approx(1e-3 * L, rel=2e-2)


class Calls(list):
    """The names of the replaced steps called, and the keywords of the last steer call."""

    kw: dict = {}


@pytest.fixture()
def fast_steer(monkeypatch):
    """The steer CLI with the slow parts replaced: identify returns the paper's reduced model
    at once, steer a short run; ``calls`` counts them (checks must come before either)."""
    import importlib

    red = importlib.import_module("flutterswim.steering.reduced")
    st = importlib.import_module("flutterswim.steering.steer")

    calls = Calls()
    model = red.ReducedModel(U=1.06e-3, period=0.378, k=3.83, omega_max=0.26, omega_max_bracket=(0.259, 0.262),
                             r_min=1.06e-3 / 0.26, onset_time=12.0)
    run = fs.simulate(P, 0.3, n_segments=8)

    def identify(*a, **kw):
        calls.append("identify")
        return model

    def fake(params, factory, reduced, **kw):
        calls.append("steer")
        calls.kw = kw
        path = factory(np.zeros(2), 0.0)
        return st.SteerResult(run, path, {"cross_track_rms_bl": 0.05, "cross_track_max_bl": 0.1,
                                          "corner_overshoot_bl": 0.0, "trapped": False, "completed": True,
                                          "path_covered_fraction": 1.0, "waypoint_arrival_s": [math.nan]},
                               True, 0.0)

    def orbit(*a, **kw):  # the CLI checks the path's duration at the orbit's speed before identify
        calls.append("orbit")
        return SimpleNamespace(speed=model.U, period=model.period)

    monkeypatch.setattr(red, "identify", identify)
    monkeypatch.setattr(st, "steer", fake)
    monkeypatch.setattr(importlib.import_module("flutterswim.orbits"), "periodic_orbit", orbit)
    return calls


def test_steer_cli_rerun_replaces_its_own_metrics(tmp_path, fast_steer):
    """The metrics JSON is signed like every other output: the same command run twice replaces
    its own files instead of refusing them as foreign."""
    from flutterswim._paths import is_ours
    from flutterswim.cli import main

    args = ["steer", "--path", "circle", "--out", str(tmp_path / "s.nc"), "--metrics", str(tmp_path / "s.json"),
            "--quiet"]
    assert main(args) == 0
    assert is_ours(tmp_path / "s.json")
    assert main(args) == 0
    assert fast_steer == ["orbit", "identify", "steer"] * 2
    # the run's file holds what scores it: the path as placed, when control started, the model
    import json

    import xarray as xr

    with xr.open_dataset(tmp_path / "s.nc", engine="h5netcdf") as ds:
        assert ds["path_x"].attrs["units"] == "m" and ds["path_x"].size > 100
        assert ds.attrs["steering_closed_loop"] == 1 and ds.attrs["steering_path_closed"] == 1
        assert json.loads(ds.attrs["steering_reduced_model"])["omega_max_rad_s"] == pytest.approx(0.26)
    assert fs.load(tmp_path / "s.nc").t.size > 0


@pytest.mark.parametrize("option, value", [("--noise-px", "nan"), ("--noise-px", "-1"), ("--noise-px", "inf"),
                                           ("--um-per-px", "0"), ("--um-per-px", "-14"), ("--um-per-px", "nan"),
                                           ("--px-per-mm", "0"), ("--px-per-mm", "-71"), ("--segments", "4")])
def test_steer_cli_refuses_bad_camera_settings_before_computing(tmp_path, fast_steer, option, value, capsys):
    from flutterswim.cli import main

    status = main(["steer", "--path", "circle", option, value, "--out", str(tmp_path / "s.nc"),
                   "--metrics", str(tmp_path / "s.json"), "--quiet"])
    err = capsys.readouterr().err
    assert status == 2 and fast_steer == []
    assert option in err and value in err and len(err.strip().splitlines()) == 1


def test_steer_cli_takes_the_scale_as_track_does(tmp_path, fast_steer, capsys):
    """--px-per-mm (track's option) is the camera scale 1000 / --um-per-px; both at once are refused."""
    from flutterswim.cli import main

    out = ["--out", str(tmp_path / "s.nc"), "--metrics", str(tmp_path / "s.json"), "--quiet"]
    assert main(["steer", "--path", "circle", "--px-per-mm", "50", *out]) == 0
    assert fast_steer.kw["um_per_px"] == pytest.approx(20.0)
    with pytest.raises(SystemExit) as stop:
        main(["steer", "--path", "circle", "--px-per-mm", "50", "--um-per-px", "20", *out])
    assert stop.value.code == 2
    assert "not allowed with" in capsys.readouterr().err


@pytest.mark.parametrize("rows, words", [("0,0\nnan,1\n5,5\n", "line 2"), ("0,0\ninf,1\n", "line 2"),
                                         ("0,0\n0,0\n", "two distinct"), ("x,y\n1,2\n", "two")])
def test_steer_cli_checks_the_waypoints_before_computing(tmp_path, fast_steer, rows, words, capsys):
    from flutterswim.cli import main

    (tmp_path / "w.csv").write_text(rows)
    status = main(["steer", "--path", "waypoints", "--waypoints", str(tmp_path / "w.csv"),
                   "--out", str(tmp_path / "s.nc"), "--metrics", str(tmp_path / "s.json"), "--quiet"])
    err = capsys.readouterr().err
    assert status == 2 and fast_steer == [], err
    assert "w.csv" in err and words in err and len(err.strip().splitlines()) == 1


def test_steer_refuses_bad_noise_and_laps():
    """The API checks its own inputs (NaN noise made every observation NaN and the command ran
    at the rate limit; NaN laps crashed with a ValueError)."""
    from flutterswim.steering.reduced import ReducedModel

    model = ReducedModel(U=1e-3, period=0.4, k=4.0, omega_max=0.26, omega_max_bracket=(0.25, 0.27), r_min=1e-3 / 0.26,
                         onset_time=12.0)
    make = lambda p, h: circle(2 * L, p, h)  # noqa: E731
    for kw in ({"noise_px": math.nan}, {"noise_px": -0.2}, {"um_per_px": 0.0}, {"laps": math.nan}, {"laps": 0.0},
               {"delay_frames": -1}):
        with pytest.raises(fs.ParameterError, match=next(iter(kw))):
            steer(P, make, model, **kw)
    # a path of 1e9 m (a stray waypoint) ran until it was out of memory: refused before any run
    far = lambda p, h: circle(1e9, p, h)  # noqa: E731
    with pytest.raises(fs.ParameterError, match="at most 3600 s"):
        steer(P, far, model)


def test_waypoints_repeated_points_keep_the_corner(tmp_path):
    """A waypoint written twice is one waypoint: the 90 degree turn there is still a corner
    (it was lost, so it was neither rounded nor measured)."""
    from flutterswim.steering.path import waypoints_csv

    (tmp_path / "a.csv").write_text("0,0\n5,0\n5,5\n")
    (tmp_path / "b.csv").write_text("0,0\n5,0\n5,0\n5,5\n")
    a, b = waypoints_csv(tmp_path / "a.csv", L), waypoints_csv(tmp_path / "b.csv", L)
    assert len(b.corners) == len(a.corners) == 1
    assert np.allclose(b.points[b.corners], [[5 * L, 0.0]])
    assert b.length == pytest.approx(10 * L)


@pytest.mark.parametrize("rows", ["0,0\n10,0\n0,0.2\n", "0,0\n10,0\n0,0\n", "0,0\n1,0\n1,1\n0,1\n"])
def test_fillet_stays_on_the_path_where_the_arc_does_not_fit(tmp_path, rows):
    """Where the edges are too short for an arc of the swimmer's turning radius (a hairpin, an
    exact reversal, a one-body-length square) the rounded path stays within the original
    path's reach: every point within half an edge of it, no jump between neighbours. (The
    hairpin's arc began 0.47 m away; the exact reversal asked for 4.6 EiB.)"""
    from flutterswim.steering.path import fillet, waypoints_csv

    (tmp_path / "w.csv").write_text(rows)
    p = waypoints_csv(tmp_path / "w.csv", L)
    f = fillet(p, 1.4 * L)
    assert np.isfinite(f.points).all()
    d = np.hypot(f.points[:, None, 0] - p.points[None, ::10, 0], f.points[:, None, 1] - p.points[None, ::10, 1])
    assert d.min(axis=1).max() <= 0.5 * L + 1e-9
    assert np.hypot(*np.diff(f.points, axis=0).T).max() < 0.05 * L
    assert f.length <= p.length + 1e-12


def test_min_radius_of_a_path_that_turns_straight_back_is_zero(tmp_path):
    """A waypoint path reversing on itself has a cusp (radius 0), not an infinite radius, so
    steer warns that it cannot be followed."""
    from flutterswim.steering.path import fillet, min_radius, waypoints_csv

    (tmp_path / "w.csv").write_text("0,0\n10,0\n0,0\n")
    p = waypoints_csv(tmp_path / "w.csv", L)
    assert min_radius(p, L) < 1e-3 * L
    assert min_radius(fillet(p, 1.4 * L), L) < 1e-3 * L


def test_a_trapped_run_says_why_in_one_line():
    """steer exits 1 when the swimmer is trapped; the reason is one line naming the trap, when
    the run was stopped for it, and its speed against the free swimmer's (it printed only
    'trapped: True' in the summary)."""
    from flutterswim.steering.cli import trapped_reason

    m = {"trapped": True, "trapped_at_s": 12.5, "mean_speed_mm_s": 0.04, "reduced_model": {"U_mm_s": 0.61}}
    line = trapped_reason(m)
    assert "\n" not in line and line.startswith("failed:")
    assert "bent equilibrium" in line and "t = 12.5 s" in line and "0.04 mm/s" in line and "0.61 mm/s" in line
    assert "t = " not in trapped_reason({**m, "trapped_at_s": None})  # found at the end (the JSON's null)


def _watched(ctrl, xy0, velocity, until):
    """Feed the controller two periods of a swimmer moving at ``velocity`` from ``xy0``."""
    for t in np.arange(0.0, until, 1.0 / ctrl.fps):
        ctrl.observe(t, np.asarray(xy0) + t * np.asarray(velocity))
    return t


@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("heading_error_deg", [60.0, 100.0, 150.0])
def test_controller_turns_the_field_towards_the_path_at_any_heading_error(sign, heading_error_deg):
    """A swimmer heading along x and a path along sign * y: the field turns towards the path
    (by lead_max, the feedback saturated), to the left for a path to the left, for heading
    errors below and above 90 degrees (above 90, err (1 + gain) passed pi, its wrap turned the
    field the other way and the swimmer swam off; the mirror image is the mirror command)."""
    from flutterswim.steering.control import Controller
    from flutterswim.steering.path import _polyline

    a = math.radians(heading_error_deg)
    path = _polyline(np.array([[0.0, 0.0], [20 * L * math.cos(a), sign * 20 * L * math.sin(a)]]), False, "line",
                     1e-5)
    ctrl = Controller(path, period=0.4, speed=1e-3, omega_max=0.26, lookahead=0.15 * L, correction=0.4 * L)
    t = _watched(ctrl, (0.0, 0.0), (1e-3, 0.0), 0.9)
    cmd = ctrl.update(t)
    assert ctrl.heading_estimate == pytest.approx(0.0, abs=1e-9)
    step = ctrl.rate_fraction * ctrl.omega_max / ctrl.fps
    assert cmd == pytest.approx(sign * step, rel=1e-9)  # the first step of the turn, towards the path
    for _ in range(200):  # held at lead_max ahead of the heading, on the path's side
        cmd = ctrl.update(t)
    assert cmd == pytest.approx(sign * ctrl.lead_max, rel=1e-9)


def test_corner_overshoot_is_measured_outward_for_right_and_left_turns():
    """The same stroke-averaged trajectory overshooting a 90 degree corner by 0.3 body lengths,
    turning left and its mirror image turning right: the same overshoot (a right turn read its
    inward cut, 0.38 against 0.007 for the left turn)."""
    from types import SimpleNamespace

    from flutterswim.steering.path import _polyline
    from flutterswim.steering.reduced import ReducedModel
    from flutterswim.steering.steer import metrics

    red = ReducedModel(U=1e-3, period=0.05, k=4.0, omega_max=0.26, omega_max_bracket=(0.25, 0.27), r_min=1e-3 / 0.26,
                       onset_time=0.0)
    d = 0.3 * L
    out = {}
    for sign in (1.0, -1.0):
        path = _polyline(np.array([[0.0, 0.0], [8 * L, 0.0], [8 * L, sign * 8 * L]]), False, "corner", 1e-5)
        # along the first edge past the corner by d, then across, then back onto the second edge
        way = np.array([[0.0, 0.0], [8 * L + d, 0.0], [8 * L + d, sign * 2 * L], [8 * L, sign * 3 * L],
                        [8 * L, sign * 8 * L]])
        seg = np.hypot(*np.diff(way, axis=0).T)
        s = np.r_[0.0, np.cumsum(seg)]
        t = np.linspace(0.0, s[-1] / red.U, 4001)
        x, y = np.interp(t * red.U, s, way[:, 0]), np.interp(t * red.U, s, way[:, 1])
        run = SimpleNamespace(t=t, x=x[:, None], y=y[:, None])
        out[sign] = metrics(run, path, red, 0.0, L)["corner_overshoot_bl"]
    assert out[1.0] == pytest.approx(0.3, rel=1e-3)
    assert out[-1.0] == pytest.approx(out[1.0], rel=1e-9)


def test_a_path_tighter_than_the_controllers_turn_is_warned_before_any_run(monkeypatch):
    """The controller turns at most rate_fraction Omega_max, a radius U / (0.8 Omega_max) = 1.25
    r_min: a circle of 1.1 r_min (above the swimmer's own limit) was called feasible and followed
    at the controller's radius, 0.36 body lengths RMS off. Now it is warned, and a circle of 1.4
    r_min is not; both before the onset is simulated."""
    import importlib
    import warnings

    from flutterswim.steering.reduced import ReducedModel

    sim_mod = importlib.import_module("flutterswim.simulate")

    class Started(Exception):
        pass

    def no_run(*a, **kw):
        raise Started

    monkeypatch.setattr(sim_mod, "simulate", no_run)
    model = ReducedModel(U=1.06e-3, period=0.378, k=3.83, omega_max=0.26, omega_max_bracket=(0.259, 0.262),
                         r_min=1.06e-3 / 0.26, onset_time=12.0)
    with pytest.warns(UserWarning, match="tightest turn the controller makes"):
        with pytest.raises(Started):
            steer(P, lambda p, h: circle(1.1 * model.r_min, p, h), model)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(Started):
            steer(P, lambda p, h: circle(1.4 * model.r_min, p, h), model)
    with pytest.raises(fs.ParameterError, match="rate_fraction"):
        steer(P, lambda p, h: circle(1.4 * model.r_min, p, h), model, rate_fraction=1.5)


def test_paths_far_too_long_or_too_small_are_refused_by_name():
    """A waypoint 1e9 body lengths away ran out of memory sampling the path; a square of 1e-9
    body lengths failed with 'ValueError: arange'. Both are refused, naming the path."""
    with pytest.raises(fs.ParameterError, match="square.*at most"):
        square(1e9 * L)
    with pytest.raises(fs.ParameterError, match="square.*at least"):
        square(1e-9 * L)
    assert square(0.1 * L).length == pytest.approx(0.4 * L, rel=1e-12)


def test_the_cross_track_integral_waits_while_the_turn_saturates_the_field():
    """Conditional integration: while the field's lead is saturated (a turn under way) the
    cross-track integral holds; it wound up over the 45 degree turn onto a line and the swimmer
    overshot the line after it (0.21 body lengths RMS; 0.13 without the wind-up)."""
    from flutterswim.steering.control import Controller
    from flutterswim.steering.path import _polyline

    def ctrl_for(angle_deg):
        a = math.radians(angle_deg)
        path = _polyline(np.array([[0.0, -0.02 * L], [20 * L * math.cos(a), 20 * L * math.sin(a) - 0.02 * L]]),
                         False, "line", 1e-5)
        c = Controller(path, period=0.4, speed=1e-3, omega_max=0.26, lookahead=0.15 * L, correction=0.4 * L)
        return c, _watched(c, (0.0, 0.0), (1e-3, 0.0), 0.9)

    turning, t = ctrl_for(45.0)  # heading error ~45 degrees: the lead saturates
    for _ in range(50):
        turning.update(t)
    assert turning._integral == 0.0
    along, t = ctrl_for(0.0)  # on course, 0.02 body lengths to the left of the line: it integrates
    for _ in range(50):
        along.update(t)
    assert along._integral != 0.0 and abs(along._integral) < along.correction


# On a straight leg the commanded field holds still: the controller does not hunt. With the
# delayed, cycle-averaged heading fed back (gain 1) the command slewed at the rate limit by +-5
# degrees at about 0.5 Hz, 8 degrees per second of needless turning, on every leg.
def _needless_turning(run, t0):
    """Total turning of the command beyond its net turn, in degrees per second, after t0."""
    m = run.t >= t0
    phi = np.unwrap(run.field_angle[m])
    return math.degrees(np.sum(np.abs(np.diff(phi))) - abs(phi[-1] - phi[0])) / (run.t[m][-1] - run.t[m][0])


def test_the_field_holds_still_on_a_straight_leg(reduced):
    line = lambda p, h: _polyline(np.array([p, (p[0] + 8 * L, p[1])]), False, "line", 1e-5)  # noqa: E731
    res = steer(P, line, reduced, seed=3)
    m = res.metrics
    assert np.isfinite(m["end_arrival_s"]) and not m["trapped"]
    # the rate limit allows 0.8 Omega_max = 11.8 degrees per second; tracking noise alone
    # (0.2 px) costs a fraction of a degree per second
    assert _needless_turning(res.run, res.control_start + 2 * reduced.period) < 1.5
    assert m["cross_track_rms_bl"] < 0.02


def test_control_waits_until_the_stroke_is_established():
    """Near the onset the stroke takes long to establish (0.75 kappa_E: the settle engine's limit
    cycle at ~28 s, against 6.7 s at the paper's point); a field turned at a fixed 10-12 s found
    the filament mid-onset and trapped it. ``established_time`` is after the settle time, and
    from it on the straight run's cycle-averaged speed is the periodic orbit's within 2 %,
    while at the old fixed 12 s it is not yet half of it."""
    from flutterswim.orbits import periodic_orbit
    from flutterswim.steering.reduced import ESTABLISHED_PERIODS, established_time

    near = P.replace(kappa_E=0.75 * P.kappa_E)
    t_est = established_time(near, n_segments=24)
    orb = periodic_orbit(near, n_segments=24)
    run = fs.simulate(near, t_est + 6 * orb.period, n_segments=24, frame_dt=0.02)
    avg = cycle_average(run.t, run.x.mean(axis=1), run.y.mean(axis=1), run.field_angle, orb.period)
    after = avg.t >= t_est
    assert np.allclose(avg.speed[after], orb.speed, rtol=0.02)
    assert np.interp(12.0, avg.t, avg.speed) < 0.5 * orb.speed
    paper = established_time(P, n_segments=24)
    assert ESTABLISHED_PERIODS * orb.period < paper < t_est


def test_steer_starts_control_at_the_models_onset(monkeypatch):
    """steer's default control start is the reduced model's onset_time (it was a fixed 10 s,
    whatever the model said)."""
    import importlib

    from flutterswim.steering.reduced import ReducedModel

    sim_mod = importlib.import_module("flutterswim.simulate")
    seen = []

    class Started(Exception):
        pass

    def first_run(params, t_end, **kw):
        seen.append(t_end)
        raise Started

    monkeypatch.setattr(sim_mod, "simulate", first_run)
    for onset in (7.5, 29.4):
        model = ReducedModel(U=1.06e-3, period=0.378, k=3.83, omega_max=0.26, omega_max_bracket=(0.259, 0.262),
                             r_min=1.06e-3 / 0.26, onset_time=onset)
        with pytest.raises(Started):
            steer(P, lambda p, h: circle(4 * L, p, h), model)
    assert seen == [7.5, 29.4]


def test_identify_refuses_a_swimmer_that_follows_no_rotation():
    """Turned mid-onset (0.75 kappa_E from 12 s) the filament is trapped at every rate: identify
    says so instead of bracketing a step-out rate it never saw followed (it returned
    Omega_max = 0.05/T x 1.005 and k = NaN as if measured)."""
    near = P.replace(kappa_E=0.75 * P.kappa_E)
    with pytest.raises(RuntimeError, match="does not follow"):
        identify(near, n_segments=24, onset=12.0)


@pytest.mark.slow
def test_near_onset_the_step_out_is_bracketed_and_a_circle_followed():
    """0.75 kappa_E: the identified step-out rate is followed just below (0.95 Omega_max) and not
    just above (1.1 Omega_max), judged from the established stroke; the closed loop follows a
    circle of 4 body lengths without trapping (it trapped with control at a fixed 10 s)."""
    near = P.replace(kappa_E=0.75 * P.kappa_E)
    model = identify(near, n_segments=24)
    t0 = model.onset_time
    for frac, ok in ((0.95, True), (1.1, False)):
        om = frac * model.omega_max
        run = rotating_run(near, om, onset=t0, period=model.period)
        assert follows(run, om, model.U, model.period, t0)[0] is ok, frac
    met = steer(near, lambda p, h: circle(4 * L, p, h), model, seed=1).metrics
    assert not met["trapped"] and met["cross_track_rms_bl"] < 0.1


def test_steer_warns_of_a_corner_whose_waypoint_it_cannot_reach(monkeypatch):
    """A triangle's 120 degree turns are rounded 1.37 body lengths inside their waypoints (its
    arrivals were reported all the same); a square's 90 degree ones 0.57: no warning."""
    import importlib
    import warnings

    from flutterswim.steering.reduced import ReducedModel

    class Started(Exception):
        pass

    def no_run(*a, **kw):
        raise Started

    monkeypatch.setattr(importlib.import_module("flutterswim.simulate"), "simulate", no_run)
    model = ReducedModel(U=1.06e-3, period=0.378, k=3.83, omega_max=0.26, omega_max_bracket=(0.259, 0.262),
                         r_min=1.06e-3 / 0.26, onset_time=12.0)
    tri = np.array([[0.0, 0.0], [6 * L, 0.0], [3 * L, 6 * L * math.sin(math.pi / 3)]])
    with pytest.warns(UserWarning, match="not arrived"):
        with pytest.raises(Started):
            steer(P, lambda p, h: _polyline(tri + np.asarray(p), True, "triangle", 1e-5), model)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(Started):
            steer(P, lambda p, h: square(10 * L, p, h), model)


def test_min_radius_is_not_fooled_by_the_paths_own_point_spacing():
    """Resampled finer than the path's own points, the circumradius of points on its chords read
    kinks: a circle of 3 body lengths (points 17 um apart) read 2.36 at a 15 um scale, and a
    square rounded at 0.08 body lengths read 0.07, so a strong field's paths were warned and
    marked infeasible though followed to 0.006 body lengths. Now within 1 % at every scale."""
    from flutterswim.steering.path import fillet, min_radius

    for scale in (0.08, 0.5, 1.4):
        assert min_radius(circle(3 * L), scale * L) == pytest.approx(3 * L, rel=0.01), scale
        r = scale * L
        assert min_radius(fillet(square(8 * L, (0.0, 0.0), 0.0), r), r) == pytest.approx(r, rel=0.01), scale


def test_identify_refuses_a_stroke_that_swims_against_the_field(monkeypatch):
    """At 2.5 kappa_E the stroke swims against the field (180 degrees): its heading read as
    leading a slow rotation by 178 degrees, k came back NaN with 'the step-out rate stands', and
    the step-out bracket was not reproducible. identify refuses it before any rotating run."""
    import importlib

    red = importlib.import_module("flutterswim.steering.reduced")
    monkeypatch.setattr(red, "rotating_run", lambda *a, **k: pytest.fail("a rotating run was simulated"))
    monkeypatch.setattr(red, "established_time", lambda *a, **k: pytest.fail("the onset was simulated"))
    with pytest.raises(RuntimeError, match="against the field"):
        identify(P.replace(kappa_E=2.5 * P.kappa_E), n_segments=24)


def test_min_radius_finds_a_hairpin_beside_a_long_chord():
    """A path with one long straight chord and a finely sampled hairpin of 0.5 body lengths: a
    step floor from the largest spacing (the chord's) hid the hairpin (inf)."""
    from flutterswim.steering.path import RefPath, min_radius

    a = np.linspace(-math.pi / 2, math.pi / 2, 400)
    hairpin = np.stack([20 * L + 0.5 * L * np.cos(a), 0.5 * L + 0.5 * L * np.sin(a)], axis=1)
    pts = np.vstack([[[0.0, 0.0]], hairpin, [[0.0, L]]])
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(pts, axis=0).T))]
    p = RefPath(pts, s, np.array([], int), False, "hairpin")
    assert min_radius(p, 1.37 * L) == pytest.approx(0.5 * L, rel=0.01)


def test_a_path_starting_behind_the_swimmer_is_followed_to_its_end(reduced):
    """The run's length had been the time the path's length takes: a path leading straight back
    (the swimmer must first turn about) ended a quarter of the way along, scored and reported as a
    success. Now the run goes on until the end is reached (up to three times as long), and the
    end is reached; a path the swimmer cannot finish in that time says so (completed False, a
    warning)."""
    make = lambda p, h: _polyline(np.array([p, p - np.array([4 * L, 0.0])]), False, "back", 1e-5)  # noqa: E731
    m = steer(P, make, reduced, seed=0).metrics
    assert m["completed"] and math.isfinite(m["end_arrival_s"]) and not m["trapped"]
    assert m["end_miss_bl"] < 1.0
    assert m["path_covered_fraction"] > 0.95


def test_joined_runs_say_their_field_changed():
    """A steered run is many short runs joined: its settings had kept the first one's field,
    "direction=constant(0)", though the field turned."""
    from flutterswim.result import concatenate

    a = fs.simulate(P, 0.05, n_segments=8)
    b = fs.simulate(P, 0.1, t_start=0.05, initial=a.final_state(), field=fs.Field(direction=fs.field.Constant(0.5)),
                    n_segments=8)
    assert concatenate([a, a]).settings["field"] == a.settings["field"]
    said = concatenate([a, b]).settings["field"]
    assert said.startswith("changes between the 2 joined runs") and a.settings["field"] in said
    assert b.settings["field"] in said


def test_passing_the_end_far_off_is_not_arriving(reduced):
    """Open loop on a path straight back: the planned schedule turns the swimmer about on a wide
    arc, so it passes the end's perpendicular 2.9 body lengths off. That had counted as the end
    reached (completed, exit 0); arriving needs passing within ARRIVAL_BL of the end point."""
    from flutterswim.steering.steer import ARRIVAL_BL

    make = lambda p, h: _polyline(np.array([p, p - np.array([3 * L, 0.0])]), False, "back", 1e-5)  # noqa: E731
    # (control asked to start between two frames: it starts on the next one, and the frames keep
    # their spacing; 7.44 s had been followed by 7.475 s at 50 fps)
    with pytest.warns(UserWarning, match="end was not reached"):
        res = steer(P, make, reduced, closed_loop=False, n_segments=12, seed=0, onset=reduced.onset_time + 0.0123)
    assert np.allclose(np.diff(res.run.t), 1 / 50, rtol=1e-6)
    t0 = res.control_start
    assert t0 >= reduced.onset_time + 0.0123 and t0 - (reduced.onset_time + 0.0123) < 1 / 50
    q = np.column_stack([res.run.x.mean(axis=1), res.run.y.mean(axis=1)])
    closest = np.hypot(*(q - res.path.points[-1]).T).min() / L
    assert closest > ARRIVAL_BL and not res.metrics["completed"]
    # the metrics say by how much: the closest approach of the stroke-averaged centroid after
    # control starts, here from the steering package's own stroke average
    avg = cycle_average(res.run.t, res.run.x.mean(axis=1), res.run.y.mean(axis=1), res.run.field_angle,
                        reduced.period)
    after = avg.t >= t0
    own = np.hypot(avg.x[after] - res.path.points[-1][0], avg.y[after] - res.path.points[-1][1]).min() / L
    assert res.metrics["end_miss_bl"] == pytest.approx(own, abs=0.05)
    assert res.metrics["end_miss_bl"] > ARRIVAL_BL


@pytest.mark.parametrize("closed", [True, False])
def test_steer_cli_says_how_far_a_failed_run_got(tmp_path, fast_steer, closed, capsys, monkeypatch):
    """A run that did not finish its path said only "N % covered": an open path's failure now
    gives the closest approach to its end against the arrival distance, a closed one's the laps
    swum of those asked for (its covered fraction counts laps)."""
    import importlib

    from flutterswim.cli import main

    st = importlib.import_module("flutterswim.steering.steer")
    done = st.steer

    def short(*a, **kw):
        res = done(*a, **kw)
        extra = {"completed": False, "path_covered_fraction": 0.6, "laps": 1.0,
                 "end_miss_bl": math.nan if closed else 2.9}
        return st.SteerResult(res.run, res.path, {**res.metrics, **extra}, True, 0.0)

    monkeypatch.setattr(st, "steer", short)
    (tmp_path / "w.csv").write_text("0,0\n5,0\n5,5\n")
    path = ["--path", "circle"] if closed else ["--path", "waypoints", "--waypoints", str(tmp_path / "w.csv")]
    status = main(["steer", *path, "--out", str(tmp_path / "s.nc"), "--metrics", str(tmp_path / "s.json"), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert status == 1 and err.startswith("failed:") and len(err.splitlines()) == 1
    assert ("swam 0.60 of its 1 laps" in err) if closed else ("2.90 body lengths from its end at the closest" in err)


def test_steer_does_not_replace_another_commands_json(tmp_path, fast_steer, capsys):
    """A fit's JSON (hours of profiles) was silently replaced by steer's metrics: NetCDF
    results were refused by kind, JSON ones were not. Now each JSON names its kind; steer's
    own metrics are still replaced by a rerun, and a fit refuses steer's metrics as well."""
    import json

    from flutterswim import __version__
    from flutterswim._paths import check_output_file
    from flutterswim.cli import main

    fit = tmp_path / "fit.json"
    fit.write_text(json.dumps({"generator": f"flutterswim {__version__} fit", "B": 1.0}))
    before = fit.read_bytes()
    args = ["steer", "--path", "circle", "--out", str(tmp_path / "s.nc"), "--quiet"]
    assert main([*args, "--metrics", str(fit)]) == 2
    err = capsys.readouterr().err
    assert fit.read_bytes() == before and "'fit'" in err and len(err.strip().splitlines()) == 1
    assert fast_steer == []  # refused before computing
    assert main([*args, "--metrics", str(tmp_path / "m.json")]) == 0
    assert main([*args, "--metrics", str(tmp_path / "m.json")]) == 0  # its own: replaced
    with pytest.raises(fs.ParameterError, match="steer metrics"):
        check_output_file(tmp_path / "m.json", (".json",), kind="fit")
