"""Figures that the plotting and stability packages do not draw as the paper does: the two
readings of b, Fig. 4c (one panel from onset to the limit cycle), Fig. 4d-e with the
average-velocity line and Fig. 5. Agg figures (no pyplot)."""

from __future__ import annotations

import math

import numpy as np

from ..plotting._common import FIELD_COLOR, SWIM_COLOR, TIP_COLOR, new_figure

__all__ = ["plot_b_readings", "plot_fig4c", "plot_fig4de", "plot_fig5"]


def plot_b_readings(ratios, growth: dict, out: dict, paper_ratio: float):
    fig = new_figure((6.0, 3.6))
    ax = fig.add_subplot()
    colors = {"semi-axis": "tab:blue", "full width": "tab:green"}
    for name, om in growth.items():
        o = out[name]
        ax.plot(ratios, om.real, color=colors[name],
                label=f"b = {name} ({o['b_m'] * 1e3:.3f} mm, eta_perp = {o['eta_perp']:.1f}): onset {o['onset_ratio']:.3f}")
        ax.axvline(o["onset_ratio"], color=colors[name], ls=":", lw=1)
    ax.axvline(paper_ratio, color=FIELD_COLOR, lw=1.2, ls="--", label=f"paper: ~{paper_ratio}")
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel(r"$\kappa_E/\kappa_{E,fit}$ (dimensionless)")
    ax.set_ylabel(r"Re $\omega_{max}$ (1/$\tau$)")
    ax.set_title("Two readings of b in ln(2l/b): growth rate of the straight state", fontsize=9)
    ax.legend(fontsize=7, loc="upper left")
    return fig


def plot_fig4c(tr, wins: dict, ghosts: dict, it: int, tip_label: str = "s = l"):
    import matplotlib

    cmap = matplotlib.colormaps["Greens"]
    mm = tr.scale_m * 1e3
    fig = new_figure((10.0, 5.2))
    gs = fig.add_gridspec(2, 2, height_ratios=[1.0, 1.3])
    ax = fig.add_subplot(gs[0, :])
    ax.plot(tr.x[:, it] * mm, tr.y[:, it] * mm, color=TIP_COLOR, lw=0.6, label=f"trailing tip trajectory ({tip_label})")
    for idx in ghosts.values():
        for n, i in enumerate(idx):
            ax.plot(tr.x[i] * mm, tr.y[i] * mm, color=cmap(0.35 + 0.6 * n / max(1, idx.size - 1)), lw=1.3)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"Fig. 4c: from onset to the limit cycle, t = 0–{tr.t[-1]:.1f} s (field E along +x)", fontsize=9)
    ax.legend(fontsize=7, loc="upper right", frameon=False)
    for col, name in enumerate(("onset", "limit")):
        a = fig.add_subplot(gs[1, col])
        idx = ghosts[name]
        w0, w1 = wins[name]
        sel = (tr.t >= w0) & (tr.t <= w1)
        a.plot(tr.x[sel, it] * mm, tr.y[sel, it] * mm, color=TIP_COLOR, lw=0.9)
        for n, i in enumerate(idx):
            a.plot(tr.x[i] * mm, tr.y[i] * mm, color=cmap(0.35 + 0.6 * n / max(1, idx.size - 1)), lw=1.5)
        a.set_aspect("equal", adjustable="datalim")
        a.set_xlabel("x (mm)")
        a.set_ylabel("y (mm)")
        a.set_title(("near onset" if name == "onset" else "at the limit cycle")
                    + f": one cycle, t = {w0:.2f}–{w1:.2f} s (light to dark in time)", fontsize=8)
    return fig


def plot_fig4de(tr, wins: dict, vel: dict):
    from ..plotting.figures import draw_kymographs

    fig = new_figure((13.0, 6.4))
    for row, (name, w) in enumerate(wins.items()):
        axs = [fig.add_subplot(2, 4, 4 * row + c + 1) for c in range(4)]
        draw_kymographs(axs, tr, w)
        v, _, t, uc = vel[name]
        mm = tr.scale_m * 1e3
        axs[0].plot(t, (uc[0] + v * (t - t[0])) * mm, color=SWIM_COLOR, lw=2.2,
                    label=f"average velocity {v * 1e3:.3f} mm/s")
        axs[0].annotate("", xy=(t[-1], (uc[0] + v * (t[-1] - t[0])) * mm),
                        xytext=(t[-10], (uc[0] + v * (t[-10] - t[0])) * mm),
                        arrowprops=dict(arrowstyle="-|>", color=SWIM_COLOR, lw=2))
        axs[0].legend(fontsize=7, loc="upper left")
        axs[0].set_title(("Fig. 4d, near onset\n" if name == "onset" else "Fig. 4e, at the limit cycle\n")
                         + axs[0].get_title(), fontsize=7)
    return fig


def plot_fig5(run, t_avg, xa, ya, circle, start: float):
    import matplotlib

    mm = 1e3 if run.units == "SI" else 1.0
    cmap = matplotlib.colormaps["Greens"]
    fig = new_figure((5.8, 7.4))
    gs = fig.add_gridspec(2, 1, height_ratios=[3.2, 1])
    ax = fig.add_subplot(gs[0])
    n = run.t.size
    for j, k in enumerate(np.linspace(0, n - 1, 24).astype(int)):
        ax.plot(run.x[k] * mm, run.y[k] * mm, color=cmap(0.3 + 0.65 * j / 23), lw=1)
    ax.plot(run.x[:, -1] * mm, run.y[:, -1] * mm, color=TIP_COLOR, lw=0.3, alpha=0.6, label="tip (s = l) trajectory")
    ax.plot(xa * mm, ya * mm, color=SWIM_COLOR, lw=2.4, label="trajectory averaged over each cycle")
    xc, yc, R = circle
    ph = np.linspace(0, 2 * math.pi, 200)
    ax.plot((xc + R * np.cos(ph)) * mm, (yc + R * np.sin(ph)) * mm, "k--", lw=0.8,
            label=f"fitted circle, R = {R * mm:.2f} mm")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(fontsize=7, loc="best", frameon=False)
    ax.set_title("Fig. 5: steering by a rotating field", fontsize=9)
    ax2 = fig.add_subplot(gs[1])
    ax2.plot(run.t, np.degrees(run.field_angle), color=FIELD_COLOR)
    ax2.axvline(start, color="0.5", ls=":", lw=1)
    ax2.text(start, 0.9, " field starts turning", transform=ax2.get_xaxis_transform(), fontsize=7)
    ax2.set_xlabel("t (s)")
    ax2.set_ylabel(r"$\phi_E$ (deg)")
    return fig
