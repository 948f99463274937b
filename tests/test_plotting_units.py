"""Figures of a dimensionless run (fs.Groups: lengths in l, times in tau) are drawn in l and
tau. A review found them labelled mm and s with lengths 1000 times too long ("x 500-1600 mm",
"t = 20.000 s" for 20 tau, a growth rate per tau labelled 1/s)."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.plotting.figures import plot_descriptors, plot_swimmer


@pytest.fixture(scope="module")
def runs():
    p = fs.PAPER
    return fs.simulate(p.groups, 16.0, n_segments=16), fs.simulate(p, 16.0 * p.tau, n_segments=16), p


def test_the_same_run_in_groups_and_in_si_draws_the_same_figure_in_its_units(runs):
    g, si, p = runs
    a, b = plot_swimmer(g).axes[0], plot_swimmer(si).axes[0]
    assert (a.get_xlabel(), a.get_ylabel()) == ("x (l)", "y (l)") and b.get_xlabel() == "x (mm)"
    assert a.get_title().endswith("τ") and b.get_title().endswith(" s")
    ga = np.concatenate([ln.get_xydata() for ln in a.get_lines()])
    sb = np.concatenate([ln.get_xydata() for ln in b.get_lines()])
    np.testing.assert_allclose(ga * p.l * 1e3, sb, rtol=1e-6, atol=1e-6 * p.l * 1e3)


def test_descriptor_panels_name_l_and_tau(runs):
    g, si, p = runs
    fg, fp = plot_descriptors(g), plot_descriptors(si)
    assert [ax.get_ylabel() for ax in fg.axes[:3]] == ["amplitude (l)", "period (τ)", "length (l)"]
    assert fg.axes[-1].get_xlabel() == "t (τ)" and fp.axes[-1].get_xlabel() == "t (s)"
    # the period panel: tau in one, seconds in the other
    tg = fg.axes[1].get_lines()[0].get_ydata()
    tp = fp.axes[1].get_lines()[0].get_ydata()
    np.testing.assert_allclose(np.asarray(tg) * p.tau, tp, rtol=1e-4)  # (the integrator tolerance)
