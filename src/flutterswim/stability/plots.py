"""Figures like the paper's Fig. (stability): map, bifurcation plots, eigenmodes (matplotlib; saved: Agg
figures outside pyplot; returned, path None: pyplot's, in the session's backend)."""

from __future__ import annotations


import numpy as np

__all__ = ["plot_map", "plot_bifurcation", "plot_modes"]


def _finish(fig, path):
    if path is not None:
        from .._paths import save_figure_file

        save_figure_file(fig, path, dpi=150, bbox_inches="tight")
    return fig


def plot_map(smap, *, neutral=None, path=None, ax=None, operating_point=None,
             operating_label: str = "paper's operating point"):
    """Stable vs flutter regions in (eta_perp, chi); flutter split by swimming direction (sign chi).
    smap: StabilityMap; neutral: optional NeutralCurve drawn as +-chi_cr; operating_point:
    (eta_perp, chi) marked with a star and a legend entry. Returns the figure."""
    from matplotlib.colors import ListedColormap

    from ..plotting._common import new_figure

    if ax is None:
        fig = new_figure((6, 4.5), shown=path is None)
        ax = fig.subplots()
    fig = ax.figure
    re = smap.omega.real.T
    chi = smap.chi[:, None]
    region = np.where(np.isnan(re), np.nan, np.where(re <= 0, 0, np.where(chi > 0, 1, 2)))
    ax.pcolormesh(smap.eta_perp, smap.chi, region, shading="auto",
                  cmap=ListedColormap(["#dddddd", "#f4a582", "#92c5de"]), vmin=0, vmax=2, rasterized=True)
    if neutral is not None:
        ax.plot(neutral.eta_perp, neutral.chi_cr, "k-", lw=1, label=r"neutral curve $\pm\chi_{cr}$")
        ax.plot(neutral.eta_perp, -neutral.chi_cr, "k-", lw=1)
    if operating_point is not None:
        e, c = (float(v) for v in operating_point)
        ax.plot([e], [c], marker="*", ms=13, color="gold", mec="k", mew=0.8, ls="none",
                label=f"{operating_label} ($\\eta_\\perp$ = {e:.1f}, $\\chi$ = {c:.1f})")
    if neutral is not None or operating_point is not None:
        ax.legend(fontsize=7, loc="center left", framealpha=0.9)
    ax.set_xlim(smap.eta_perp[0], smap.eta_perp[-1])
    ax.set_ylim(smap.chi[0], smap.chi[-1])
    ax.set_xlabel(r"$\eta_\perp = \mu_\perp l^4/(B\tau)$ (dimensionless)")
    ax.set_ylabel(r"$\chi = \kappa_E\, l$ (dimensionless)")
    ax.text(0.7, 0.9, "flutter, swims one way (chi>0)", transform=ax.transAxes, fontsize=7, ha="center")
    ax.text(0.7, 0.07, "flutter, swims the other way (chi<0)", transform=ax.transAxes, fontsize=7, ha="center")
    ax.text(0.7, 0.5, "stable", transform=ax.transAxes, fontsize=9, ha="center")
    return _finish(fig, path)


def plot_bifurcation(curves, *, path=None):
    """Re (blue) and Im (orange) of omega_max vs the varied parameter, one panel per Bifurcation."""
    from ..plotting._common import new_figure

    fig = new_figure((4.5 * len(curves), 3.2), shown=path is None)
    axes = fig.subplots(1, len(curves), squeeze=False)
    for ax, b in zip(axes[0], curves):
        ax.plot(b.values, b.omega.real, color="tab:blue", label=r"Re $\omega_{max}$ (growth rate)")
        ax.plot(b.values, b.omega.imag, color="tab:orange", label=r"Im $\omega_{max}$ (angular frequency)")
        ax.axhline(0, color="k", lw=0.5)
        sym = {"chi": r"$\chi$", "eta_perp": r"$\eta_\perp$"}
        other = "eta_perp" if b.parameter == "chi" else "chi"
        ax.set_xlabel(f"{sym.get(b.parameter, b.parameter)} (dimensionless)")
        ax.set_ylabel(r"$\omega_{max}$ (1/$\tau$)")
        ax.set_title(f"{sym.get(other, other)} = {b.fixed:.4g}", fontsize=9)
        ax.legend(fontsize=7)
    return _finish(fig, path)


def plot_modes(modes, *, path=None):
    """Real (blue) and imaginary (orange) parts of normalised r(s), one panel per Eigenmode."""
    from ..plotting._common import new_figure

    fig = new_figure((4.5 * len(modes), 3.0), shown=path is None)
    axes = fig.subplots(1, len(modes), squeeze=False)
    for ax, m in zip(axes[0], modes):
        ax.plot(m.s, m.r.real, color="tab:blue", label="Re r")
        ax.plot(m.s, m.r.imag, color="tab:orange", label="Im r")
        ax.set_xlabel("s / l")
        ax.set_ylabel(r"$r(s)\,/\,\max|r|$ (dimensionless)")
        ax.set_title(f"mode {m.rank}: " + r"$\omega$" + f" = {m.omega.real:.3f} + {m.omega.imag:.3f}i (1/" + r"$\tau$)",
                     fontsize=9)
        ax.legend(fontsize=7)
    return _finish(fig, path)
