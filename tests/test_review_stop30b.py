"""Review findings (stop 30b): a fit on data the model cannot reproduce (an internal
continuation that leaves the branch's region was a bad-input error, exit 2, after minutes);
steer --seed -1 (a ValueError from numpy, exit 1); angles in radians given as degrees
(step(90, 8) is 90 rad)."""

import importlib
import math
import warnings

import numpy as np
import pytest

import flutterswim as fs
from flutterswim import cli
from flutterswim._validate import ParameterError
from flutterswim.orbits import OrbitNotFound, periodic_orbit
from flutterswim.orbits.linear import hopf_point, leading_pair
from flutterswim.orbits.periodic import NEAR_ONSET


# ------------------------------------------------------- no stroke is OrbitNotFound, not bad input
def test_no_oscillatory_mode_is_no_stroke_not_bad_input():
    """kappa_E = 0 is a valid parameter set without a stroke (as 0.5 x kappa_E is)."""
    with pytest.raises(OrbitNotFound, match="no stroke"):
        periodic_orbit(fs.PAPER.replace(kappa_E=0.0), n_segments=8)


def test_continuation_outside_the_branch_is_no_stroke(monkeypatch):
    """Near onset periodic_orbit continues from the Hopf point; a continuation that cannot
    reach the point (its ParameterError: 'the branch exists below the Hopf point') means no
    stroke there, and the fit's worker reports it as a failed point instead of raising."""
    g = fs.PAPER.groups
    hopf = hopf_point(g, "chi", n_segments=8).value
    near = g.replace(chi=hopf * 1.001)
    lam = leading_pair(near, 8)
    assert 0 < lam.real < NEAR_ONSET * lam.imag  # the continuation path is the one taken

    def outside(params, parameter, to, **kw):
        raise ParameterError(f"to={to:g}: the stroke branch exists for {parameter} below the Hopf point 1")

    monkeypatch.setattr(importlib.import_module("flutterswim.orbits.continuation"), "continue_orbits", outside)
    with pytest.raises(OrbitNotFound, match="does not reach it"):
        periodic_orbit(near, n_segments=8)
    from flutterswim.fitting.model import solve_point

    out = solve_point((near, None, 8, 16))
    assert isinstance(out, str) and "does not reach it" in out


def test_bad_guess_is_still_bad_input():
    with pytest.raises(ParameterError, match="guess"):
        periodic_orbit(fs.PAPER.groups, guess="orbit", n_segments=8)


# ------------------------------------------------------------------------------ the fit stops
class _Model:
    """A descriptor model with a stroke only at the start (or nowhere): counts its calls."""

    def __init__(self, x0, at_start=True):
        self.x0, self.at_start, self.calls = np.asarray(x0), at_start, 0

    def __call__(self, x):
        from flutterswim.fitting.model import NotSwimming

        self.calls += 1
        # the start and its Jacobian's differences (1e-5), nothing the optimiser steps to
        if self.at_start and np.allclose(x, self.x0, rtol=0, atol=3e-5):
            return np.array([0.3, 1.0, 0.2]) * (1 + 0.1 * (x - self.x0)[[2, 0, 1]])
        raise NotSwimming("no stroke here")


def _x0():
    from flutterswim.fitting.fit import PAPER_GUESS
    from flutterswim.fitting.model import to_identifiable

    return to_identifiable(fs.PAPER, *PAPER_GUESS)


def test_fit_stops_when_every_trial_point_fails():
    fit_module = importlib.import_module("flutterswim.fitting.fit")

    limit = getattr(fit_module, "MAX_FAILED_IN_A_ROW", 6)
    m = _Model(_x0())
    res = fit_module.fit([0.4, 1.55, 0.3], [0.006, 0.03, 0.006], model=m)
    assert not res.converged
    # the start (checked, then its residual), the Jacobian there and at the end (the point and
    # 6 differences each) and the failed trial points in a row, not the optimiser's 60
    assert m.calls <= 2 + 2 * 7 + limit, m.calls
    assert "outside what the model can reproduce" in res.message


def test_fit_without_a_stroke_at_the_start_fails_at_once():
    from flutterswim.fitting.fit import fit
    from flutterswim.fitting.model import OutsideModel

    m = _Model(_x0(), at_start=False)
    with pytest.raises(OutsideModel, match="outside what the model can reproduce"):
        fit([0.4, 1.55, 0.3], [0.006, 0.03, 0.006], model=m)
    assert m.calls == 1


def test_fit_cli_outside_the_model_is_a_one_line_failure(tmp_path, monkeypatch, capsys):
    """Every orbit fails (as on data no stroke reproduces): exit 1, one line saying so, fast."""
    csv = tmp_path / "bad.csv"
    csv.write_text("voltage_V,sample,period_s,advance_mm,lateral_mm\n85,1,0.40,1.5,0.3\n85,2,0.41,1.6,0.31\n"
                   "85,3,0.39,1.55,0.29\n")
    calls = []

    def no_stroke(item):
        calls.append(item)
        return "no stroke here"

    monkeypatch.setattr(importlib.import_module("flutterswim.fitting.model"), "solve_point", no_stroke)
    status = cli.main(["fit", str(csv), "--segments", "8", "--no-extrapolate", "--out", str(tmp_path / "f.json")])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert status == 1 and len(err) == 1, (status, err)
    assert "outside what the model can reproduce" in err[0] and "Error" not in err[0]
    assert len(calls) == 1
    assert not (tmp_path / "f.json").exists()


# --------------------------------------------------------------------------------- steer --seed
@pytest.fixture()
def no_computing(monkeypatch):
    def computed(*a, **kw):
        raise AssertionError("computed before the input was checked")

    monkeypatch.setattr(importlib.import_module("flutterswim.steering.reduced"), "identify", computed)


@pytest.mark.parametrize("seed", ["-1", "-5"])
def test_steer_negative_seed_is_bad_input(seed, tmp_path, capsys, no_computing):
    status = cli.main(["steer", "--seed", seed, "--quiet", "--out", str(tmp_path / "s.nc"),
                       "--metrics", str(tmp_path / "s.json")])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert status == 2 and len(err) == 1, (status, err)
    assert f"--seed={seed}" in err[0] and ">= 0" in err[0]


def test_steer_api_negative_seed_is_parameter_error():
    from flutterswim.steering.steer import steer

    with pytest.raises(ParameterError, match="seed=-1"):
        steer(fs.PAPER, None, None, seed=-1)


# ------------------------------------------------------------------- angles in radians, not degrees
def _warned(call, name):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        call()
    msgs = [str(x.message) for x in w if issubclass(x.category, UserWarning)]
    assert any(m.startswith(f"{name}=") and "radians" in m for m in msgs), msgs
    assert all(x.filename == __file__ for x in w), [x.filename for x in w]  # points at the caller


def _quiet(call):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return call()


def test_step_and_ramp_warn_about_degrees():
    from flutterswim.steering import ramp, rotation, step

    _warned(lambda: step(90, 8), "angle")
    _warned(lambda: ramp(-180, 0, 1), "angle")
    _warned(lambda: ramp(1.0, 0, 1, phi0=45), "phi0")
    _warned(lambda: rotation(2.0, phi0=30), "phi0")
    f = _quiet(lambda: step(math.radians(90), 8))
    assert f.direction(9.0) == pytest.approx(math.pi / 2)
    _quiet(lambda: ramp(-2 * math.pi, 0, 1))
    assert "rad" in step.__doc__ and "rad" in ramp.__doc__


def test_field_and_simulate_warn_about_degrees():
    _warned(lambda: fs.Field(direction=90), "direction")
    _warned(lambda: fs.simulate(fs.PAPER, 0.005, field=90.0, n_segments=4), "field")
    _quiet(lambda: fs.Field(direction=math.pi))


def test_cli_degrees_do_not_warn():
    """The CLI takes degrees: more than a turn there is no sign of a unit mix-up."""
    import argparse

    from flutterswim.steering.schedules import field_from_args

    base = dict(field_angle=None, field_rotate=None, field_step=None, field_ramp=None, field_csv=None,
                field_start=None)
    for k, v in (("field_angle", 400.0), ("field_step", 400.0), ("field_ramp", [720.0, 2.0])):
        f = _quiet(lambda k=k, v=v: field_from_args(argparse.Namespace(**{**base, k: v})))
        assert f.direction(10.0) == pytest.approx(math.radians(v if k != "field_ramp" else v[0]))


def test_field_start_without_a_timed_schedule_is_refused():
    """--field-start times a rotation, step or ramp; with a constant angle, a CSV or no
    schedule at all it would be silently ignored."""
    import argparse

    from flutterswim.steering.schedules import field_from_args

    base = dict(field_angle=None, field_rotate=None, field_step=None, field_ramp=None, field_csv=None)
    for extra in ({}, {"field_angle": 30.0}, {"field_csv": "f.csv"}):
        with pytest.raises(ParameterError, match="--field-start"):
            field_from_args(argparse.Namespace(**{**base, **extra, "field_start": 2.0}))
    f = field_from_args(argparse.Namespace(**{**base, "field_step": 90.0, "field_start": 2.0}))
    assert f.direction(1.9) == pytest.approx(0.0) and f.direction(2.1) == pytest.approx(math.pi / 2)
    assert field_from_args(argparse.Namespace(**{**base, "field_start": None})) is None


def test_tracking_field_angle_warns_about_degrees_and_the_cli_takes_any_turn(tmp_path):
    """track(field_angle=90) is 90 rad: warned at the caller's line, before any frame is read;
    the command line's degrees (any number of turns) give the same direction without a warning."""
    pytest.importorskip("skimage")
    from flutterswim._validate import direction_deg
    from flutterswim.tracking import track

    def call():
        with pytest.raises(ParameterError, match="does not exist"):
            track(tmp_path / "none.tif", px_per_mm=70.0, field_angle=90.0)

    _warned(call, "field_angle")
    for deg in (400.0, -190.0, 720.0 + 35.0, 180.0):
        rad = _quiet(lambda deg=deg: direction_deg("--field-angle-deg", deg))
        assert -math.pi < rad <= math.pi
        assert (math.cos(rad), math.sin(rad)) == pytest.approx((math.cos(math.radians(deg)), math.sin(math.radians(deg))))
    with pytest.raises(ParameterError, match="--field-angle-deg"):
        direction_deg("--field-angle-deg", math.nan)
