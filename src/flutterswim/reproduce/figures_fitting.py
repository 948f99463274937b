"""Fig. 3e from a trials CSV (mean +- SEM per voltage), through flutterswim.fitting."""

from __future__ import annotations

from .io import save_figure, write_json
from .targets import Context, Outcome, Settings, compare

__all__ = ["build_fig3e", "fitting_available"]


def fitting_available() -> bool:
    try:
        import flutterswim.fitting  # noqa: F401
    except ImportError:
        return False
    return True


def fig3e_params(s: Settings) -> dict:
    from .io import sha256_file

    return {"trials": s.trials, "trials_sha256": sha256_file(s.trials) if s.trials else None,
            "fitting": fitting_available()}


def build_fig3e(ctx: Context) -> Outcome:
    trials = ctx.settings.trials
    if not fitting_available():
        return Outcome("skipped", (), ("skipped: needs the fitting module (flutterswim.fitting is not installed "
                                       "in this tree).",))
    if not trials:
        return Outcome("skipped", (), ("skipped: no trials CSV given (flutterswim reproduce --trials CSV, columns "
                                       "voltage_V, sample, period_s, advance_mm, lateral_mm); the paper's 49 trials "
                                       "are not public here, and a fit on synthetic data is `flutterswim fit`'s job.",))
    import matplotlib.pyplot as plt

    from ..fitting import plot_trials, read_trials, summarise

    tr = read_trials(trials)
    sm = summarise(tr)
    fig = plot_trials(sm, None, trials=tr)
    fig.suptitle("Fig. 3e: descriptors against voltage (mean ± SEM)", fontsize=9)
    save_figure(fig, ctx.path("fig3e.png"))
    plt.close(fig)
    write_json(ctx.path("fig3e_data.json"), {"voltage_V": sm.voltage_V, "n": sm.n, "mean": sm.mean, "sem": sm.sem,
                                             "columns": ["period_s", "advance_mm", "lateral_mm"]})
    rows = (compare("trials", 49, float(sm.n.sum()), rtol=0.0, paper_text="49 trials on 7 samples", fmt="{:.0f}"),)
    return Outcome("ok", rows, (f"{int(sm.n.sum())} trials at {len(sm.voltage_V)} voltages from {trials}.",), {})
