"""Figure of a fit: the data (Fig. 3e), the model at the fit and its residual, and profiles."""

from __future__ import annotations


import numpy as np

__all__ = ["plot_fit"]


def _residual(res, k: int) -> str:
    """The fit's residual in descriptor k: model - mean, relative and in SEMs (the quantity the
    fit weighs), for the panel that shows both."""
    mean, model = float(res.measured[k]), float(res.model[k])
    sem = float(np.asarray(res.sem, float)[k])
    out = f"model - mean: {100 * (model / mean - 1):+.2f} %"
    return out + (f" = {(model - mean) / sem:+.2f} SEM" if np.isfinite(sem) and sem > 0 else "")


def plot_fit(res, summary, trials, path=None, *, voltage: float | None = None):
    """Figure of a fit at ``voltage`` (default: the voltage whose means are closest to the
    fitted data): the trials and means (Fig. 3e) with the model at the fit, and each
    parameter's profile (or its 1-sigma band)."""
    from ..plotting._common import new_figure
    from matplotlib.ticker import MaxNLocator

    from .data import draw_trials

    fig = new_figure((10.5, 6.4), shown=path is None)
    axs = fig.subplots(2, 3)
    if voltage is None and not res.settings.get("voltages_V"):
        voltage = summary.voltage_V[np.argmin(np.sum(np.abs(summary.mean / res.measured - 1), axis=1))]
    joint = res.settings.get("voltages_V")
    for k in range(3):
        ax = axs[0, k]
        draw_trials(ax, k, summary, trials, res.settings.get("tip"))
        if joint:  # a joint fit over voltages: the model at each of them
            ax.plot(joint, np.asarray(res.model)[:, k], "s-", mfc="none", color="k", ms=8, lw=0.8,
                    label="model at the fit (kappa_E ~ V)")
        else:
            ax.plot([voltage], [res.model[k]], "s", mfc="none", color="k", ms=8, label="model at the fit")
            # (above the panel: inside it, it overlapped the n= labels and the trials)
            ax.set_title(_residual(res, k), fontsize=8)
    axs[0, 0].legend(fontsize=8)
    names = (("B", 1e6, "B [N mm$^2$]"), ("tau", 1.0, r"$\tau$ [s]"), ("kappa_E", 1e-3, r"$\kappa_E$ [1/mm]"))
    best = (res.B, res.tau, res.kappa_E)
    for k, (n, scale, lab) in enumerate(names):
        ax = axs[1, k]
        if res.profiles:
            pr = res.profiles[n]
            ok = np.isfinite(pr["chi2"])  # (no stroke elsewhere: not drawn)
            ax.plot(pr["values"][ok] * scale, pr["chi2"][ok] - pr["chi2"][ok].min(), "o-", color="k", ms=3,
                    label="profile")
            ax.axhline(1.0, color="tab:blue", ls=":", lw=1, label=r"$\Delta\chi^2 = 1$")
            ax.set_ylabel(r"$\Delta\chi^2$")
        else:
            ax.text(0.5, 0.5, "profiles not computed\n(--profiles, one voltage)", ha="center", va="center",
                    transform=ax.transAxes)
        ax.axvline(best[k] * scale, color="tab:red", lw=1)
        ax.axvspan(best[k] * scale * (1 - res.sigma_rel[k]), best[k] * scale * (1 + res.sigma_rel[k]),
                   color="tab:red", alpha=0.15, label=r"$\pm 1\sigma$ (Jacobian)")
        ax.set_xlabel(lab + (f" at {res.settings['v_ref_V']:g} V" if joint and n == "kappa_E" else ""))
        ax.xaxis.set_major_locator(MaxNLocator(4))  # (more overlapped on the tau axis)
        ax.legend(fontsize=7)
    head = f"fit at {voltage:g} V" if voltage is not None else "fit"
    if joint:
        st = res.settings
        head = (f"joint fit over {len(joint)} voltages, kappa_E ~ V: chi2 = {st['chi2']:.3g} for {st['dof']} "
                f"degrees of freedom (p = {st['p_value']:.3g})")
    fig.suptitle(f"{head}\n{res.card.describe()}", fontsize=9)
    if path is not None:
        from .._paths import save_figure_file

        save_figure_file(fig, path, dpi=130)
    return fig
