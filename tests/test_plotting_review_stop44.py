"""Figures a held-out review (stop 44) found misleading: a summary titling a run that never
settled "limit", trials drawn at a voltage never applied, API figure functions replacing a
user's file, and GIF frame rates a GIF cannot store."""

import dataclasses

import numpy as np
import pytest

import flutterswim as fs
from flutterswim._validate import ParameterError


def test_the_summary_names_windows_by_what_the_run_did():
    from flutterswim.analysis.cycles import detect_cycles
    from flutterswim.plotting.figures import plot_summary

    slow = fs.simulate(dataclasses.replace(fs.PAPER, kappa_E=0.8 * fs.PAPER.kappa_E), 12.0, n_segments=24)
    cyc = detect_cycles(slow)
    assert not cyc.limit_cycle  # (describe's verdict, which the titles must follow)
    titles = [a.get_title() for a in plot_summary(slow).axes if a.get_title()]
    assert not any(t.startswith(("limit", "onset")) for t in titles), titles
    assert any(t.startswith("last cycles (no limit cycle)") for t in titles), titles
    settled = fs.simulate(fs.PAPER, 12.0, n_segments=24)
    assert detect_cycles(settled).limit_cycle
    titles = [a.get_title() for a in plot_summary(settled).axes if a.get_title()]
    assert any(t.startswith("limit cycle") for t in titles) and any(t.startswith("onset") for t in titles), titles


def test_trials_are_drawn_at_their_own_voltage():
    """One voltage, 700 V: the trial dots sat at 658 V on the voltage axis (shifted by 6 % of it)."""
    from flutterswim.fitting.data import Trials, plot_trials, summarise

    v = np.full(6, 700.0)
    tr = Trials(v, np.array(["a"] * 6), np.column_stack([np.linspace(0.37, 0.39, 6), np.full(6, 0.39),
                                                         np.full(6, 1.13)]))
    fig = plot_trials(summarise(tr), None, trials=tr)
    dots = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_label() == "trials"]
    assert dots and all(np.allclose(ln.get_xdata(), 700.0) for ln in dots)
    for ax in fig.axes:
        lo, hi = ax.get_xlim()
        if dots[0] in ax.get_lines():
            assert lo < 700.0 < hi and abs((700.0 - lo) - (hi - 700.0)) < 0.2 * (hi - lo)


def test_api_figures_never_replace_a_users_file(tmp_path):
    from flutterswim.fitting.data import Trials, plot_trials, summarise

    mine = tmp_path / "n1.png"
    mine.write_bytes(b"\x89PNG mine")
    tr = Trials(np.array([80.0, 80.0, 90.0, 90.0]), np.array(["a"] * 4), np.ones((4, 3)))
    with pytest.raises(ParameterError, match="not written by flutterswim"):
        plot_trials(summarise(tr), mine, trials=tr)
    assert mine.read_bytes() == b"\x89PNG mine"
    plot_trials(summarise(tr), tmp_path / "ours.png", trials=tr)
    plot_trials(summarise(tr), tmp_path / "ours.png", trials=tr)  # ours: replaced


@pytest.mark.parametrize("fps,ok", [(15.0, False), (60.0, False), (25.0, True), (100.0 / 3.0, True), (50.0, True)])
def test_a_gif_takes_only_the_frame_rates_it_can_store(tmp_path, fps, ok):
    """GIF delays are whole hundredths of a second: fps 15 played 11 % fast, 60 at 67 %."""
    from flutterswim.plotting.animation import animate

    run = fs.simulate(fs.PAPER, 0.2, n_segments=8)
    if ok:
        animate(run, tmp_path / "a.gif", fps=fps, max_frames=3, size=(96, 64))
    else:
        with pytest.raises(ParameterError, match="whole hundredths of a second"):
            animate(run, tmp_path / "a.gif", fps=fps, max_frames=3, size=(96, 64))
