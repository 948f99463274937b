"""Figures and animation are written (smoke), results are frozen dataclasses."""

import dataclasses

import numpy as np
import pytest

from flutterswim.params import PAPER
from flutterswim.stability import animate_mode, bifurcation, eigenmodes, neutral_curve, stability_map
from flutterswim.stability.plots import plot_bifurcation, plot_map, plot_modes


def test_figures_and_gif(tmp_path):
    g = PAPER.groups
    m = stability_map(eta_perp=np.linspace(0, 350, 36), chi=np.linspace(-130, 130, 27))
    nc = neutral_curve(np.linspace(0, 350, 36))
    plot_map(m, neutral=nc, path=tmp_path / "map.png")
    b1 = bifurcation(parameter="chi", values=np.linspace(0.5, 130, 60), fixed=g.eta_perp)
    b2 = bifurcation(parameter="eta_perp", values=np.linspace(1, 350, 60), fixed=g.chi)
    plot_bifurcation([b1, b2], path=tmp_path / "bif.png")
    modes = eigenmodes(g.chi, g.eta_perp)
    plot_modes(modes, path=tmp_path / "modes.png")
    animate_mode(modes[0], tmp_path / "mode.gif", frames=6)
    for name in ("map.png", "bif.png", "modes.png", "mode.gif"):
        assert (tmp_path / name).stat().st_size > 1000
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.omega = None
    # bifurcation curve continuous: neighbouring points close (no branch jumps)
    for b in (b1, b2):
        assert np.max(np.abs(np.diff(b.omega))) < 1.0


def test_stability_figures_entry_point(tmp_path):
    from flutterswim.stability import stability_figures

    figs = stability_figures(tmp_path, step=5.0)
    for p in (figs.map_png, figs.bifurcation_png, figs.modes_png, figs.mode_gif):
        assert p.stat().st_size > 1000
