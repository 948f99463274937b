"""Figure of a path-following run: the path, the cycle-averaged trajectory and the body every
few seconds with the field arrow; the commanded field direction below."""

from __future__ import annotations


import numpy as np

__all__ = ["plot_steer"]


def plot_steer(res, path=None):
    from ..plotting._common import new_figure

    from .turning import _moving_average

    run = res.run
    mm = 1e3
    fig = new_figure((6, 8), shown=path is None)
    (ax, ax2) = fig.subplots(2, 1, gridspec_kw={"height_ratios": [3, 1]})
    ax.plot(*(res.path.points * mm).T, color="0.6", lw=1.5, label="path")
    cx, cy = run.x.mean(axis=1), run.y.mean(axis=1)
    period = res.metrics["period_s"]
    ts, axv = _moving_average(run.t, cx, period)
    _, ayv = _moving_average(run.t, cy, period)
    ax.plot(axv * mm, ayv * mm, color="tab:orange", lw=1.5, label="cycle-averaged centroid")
    every = max(1, int(len(run.t) / 25))
    for k in range(0, len(run.t), every):
        ax.plot(run.x[k] * mm, run.y[k] * mm, color="tab:green", lw=0.8, alpha=0.6)
        ax.annotate("", xy=(cx[k] * mm + 0.8 * np.cos(run.field_angle[k]), cy[k] * mm + 0.8 * np.sin(run.field_angle[k])),
                    xytext=(cx[k] * mm, cy[k] * mm), arrowprops=dict(arrowstyle="->", color="tab:blue", lw=0.8))
    ax.plot([], [], color="tab:green", label="body (every few s)")
    ax.plot([], [], color="tab:blue", label="field direction")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.legend(fontsize=8, loc="best")
    m = res.metrics
    ax.set_title(f"{'closed' if res.closed_loop else 'open'} loop: cross-track RMS {m['cross_track_rms_bl']:.3f} bl, "
                 f"overshoot {m['corner_overshoot_bl']:.3f} bl", fontsize=9)
    ax2.plot(run.t, np.degrees(np.unwrap(run.field_angle)), color="tab:blue")
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("field direction [deg]")
    if path is not None:
        from .._paths import save_figure_file

        save_figure_file(fig, path, dpi=140)
    return fig
