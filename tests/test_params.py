import math
import warnings

import pytest

import flutterswim as fs


def test_paper_groups_match_the_definitions():
    p = fs.PAPER
    log = math.log(2 * p.l / p.b)
    assert p.mu_par == pytest.approx(4 * math.pi * p.mu / (2 * log - 1), rel=1e-15)
    assert p.mu_perp == pytest.approx(4 * math.pi * p.mu / log, rel=1e-15)
    g = p.groups
    assert g.eta_perp == pytest.approx(p.mu_perp * p.l**4 / (p.B * p.tau))
    assert g.chi == pytest.approx(p.kappa_E * p.l)
    # the brief's rounded values
    assert (round(g.eta_perp, 1), round(g.eta_par, 1), round(g.chi, 1)) == (71.5, 41.5, 70.7)


def test_from_groups_round_trip():
    g = fs.PAPER.groups
    p = fs.Parameters.from_groups(g.eta_par, g.eta_perp, g.chi, l=2.0, tau=3.0, B=5.0)
    for a, b in zip((g.eta_par, g.eta_perp, g.chi), (p.eta_par, p.eta_perp, p.chi)):
        assert b == pytest.approx(a, rel=1e-12)


@pytest.mark.parametrize(
    "change, name",
    [({"l": -1.0}, "l"), ({"mu": float("nan")}, "mu"), ({"tau": 0.0}, "tau"),
     ({"kappa_E": float("inf")}, "kappa_E"), ({"a": 1e-3}, "a="), ({"b": 2.5e-3}, "b=")],
)
def test_invalid_parameters_are_named(change, name):
    with pytest.raises(fs.ParameterError, match=name):
        fs.PAPER.replace(**change)


def test_stubby_geometry_warns_but_works():
    with pytest.warns(fs.SlendernessWarning):
        p = fs.PAPER.replace(b=0.25 * fs.PAPER.l)
    assert p.mu_par > 0


def test_paper_geometry_is_slender_without_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fs.PAPER.replace(kappa_E=1.0)


def test_groups_reject_nonpositive_drag():
    with pytest.raises(fs.ParameterError, match="eta_perp"):
        fs.Groups(eta_par=1.0, eta_perp=0.0, chi=1.0)
    with pytest.raises(fs.ParameterError, match="from_groups|eta_perp/eta_par"):
        fs.Parameters.from_groups(10.0, 30.0, 1.0)
