"""A review's smaller findings on the orbits (stop 41): an orbit solved at steps the caller
fixed says when they are too few, max_newton is checked, and the sweep's stroke flags say that
0 also means "no stroke"."""

import warnings

import pytest

import flutterswim as fs
from flutterswim._validate import ParameterError
from flutterswim.orbits.periodic import ACCURACY_GAUGE, periodic_orbit

EP = 41.49104790788428
BENT = fs.Groups(EP, 2.5 * EP, 88.0)  # about twice the onset's chi: a strongly bent stroke


def test_too_few_fixed_steps_are_called_out():
    checked = periodic_orbit(BENT, n_segments=24)  # steps chosen and checked
    with pytest.warns(UserWarning, match="trivial Floquet multiplier"):
        coarse = periodic_orbit(BENT, guess=checked, steps=8)
    assert coarse.trivial_multiplier_error > ACCURACY_GAUGE
    # what the warning is about: the advance is off by far more than an orbit's tolerance
    assert abs(coarse.advance / checked.advance - 1) > 1e-4
    with warnings.catch_warnings():  # enough steps: no warning
        warnings.simplefilter("error")
        fine = periodic_orbit(BENT, guess=checked, steps=checked.steps)
    assert fine.trivial_multiplier_error <= ACCURACY_GAUGE


def test_max_newton_is_checked():
    with pytest.raises(ParameterError, match="max_newton"):
        periodic_orbit(BENT, n_segments=24, max_newton=0)


def test_stroke_flags_say_that_0_also_means_no_stroke():
    from flutterswim.sweep.store import variable_attrs

    for name in ("stable", "self_intersecting"):
        assert "no stroke" in variable_attrs(name, "s")["long_name"]
    assert "no stroke" not in variable_attrs("straight", "s")["long_name"]


def test_the_branch_progress_bar_stays_within_its_total(tmp_path, capsys):
    """(A review: counting how far into the range the branch had come against a total rounded
    to 6 digits ended above it: tqdm's 'clamping frac to range [0, 1]' on stderr.)"""
    from flutterswim.cli import main

    assert main(["branch", "kappa_E_ratio=1:1.5", "--points", "4", "--segments", "12", "--look-beyond", "0",
                 "--out", str(tmp_path / "b.nc")]) == 0
    assert "clamping" not in capsys.readouterr().err
