"""The paper's kappa_E sweep figure: advancement per cycle and period against kappa_E/kappa_E_fit,
self-intersecting parts in red, the linear-stability critical ratio marked (of the discrete model
the points ran with, dashed; of the continuum, dotted)."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from .._validate import ParameterError

__all__ = ["plot_sweep", "critical_ratio", "discrete_critical_ratio"]


def _spec(ds):
    from .spec import SweepSpec

    return SweepSpec.from_dict(json.loads(ds.attrs["sweep_spec"]))


def critical_ratio(ds) -> float:
    """kappa_E,cr / kappa_E of the sweep's base (linear stability; NaN if unavailable)."""
    from ..params import Parameters

    b = _spec(ds).base
    try:
        from ..stability import critical_chi

        chi_cr, _ = critical_chi(b.groups.eta_perp if isinstance(b, Parameters) else b.eta_perp)
        return float(chi_cr / b.chi) if b.chi else math.nan
    except Exception:  # pragma: no cover - stability unavailable
        return math.nan


def discrete_critical_ratio(ds) -> tuple[float, int]:
    """(kappa_E / kappa_E of the base at the Hopf point of the discrete model the sweep's points
    ran with, its number of segments N); NaN if unavailable. The sweep's points swim from this
    ratio on, not from the continuum's (0.6835 at N = 24 against 0.6865)."""
    spec = _spec(ds)
    n = int(spec.settings.n_segments)
    try:
        from ..orbits.linear import hopf_point

        return float(hopf_point(spec.base, "kappa_E_ratio", n_segments=n).value), n
    except Exception:  # pragma: no cover - no Hopf point near the base
        return math.nan, n


def _coloured(ax, x, y, red, gaps=None, **kw):
    """Line through (x, y) in black, segments touching a red point in red; none from point i to
    i + 1 where ``gaps[i]``."""
    x, y, red = np.asarray(x, float), np.asarray(y, float), np.asarray(red, bool)
    for i in range(x.size - 1):
        if not (np.isfinite(y[i]) and np.isfinite(y[i + 1])) or (gaps is not None and gaps[i]):
            continue
        c = "tab:red" if (red[i] or red[i + 1]) else "k"
        ax.plot(x[i : i + 2], y[i : i + 2], color=c, lw=1.8, solid_capstyle="round")
    ok = np.isfinite(y)
    ax.scatter(x[ok & ~red], y[ok & ~red], s=8, color="k", zorder=3)
    ax.scatter(x[ok & red], y[ok & red], s=8, color="tab:red", zorder=3)


def plot_sweep(ds, path: str | None = None, *, x: str | None = None, branch: str | None = None,
               advance: str = "advance_per_cycle_bl", period: str = "period_s") -> Any:
    """Two panels (advancement per cycle, period) against the swept axis (default
    ``kappa_E_ratio``); returns the Figure, saved to ``path`` if given (Agg backend)."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    if "branch" in ds.dims:
        allowed = [str(b) for b in ds["branch"].values]
        if branch is not None and branch not in allowed:
            raise ParameterError(f"branch={branch!r} is not a branch of this sweep; choose one of {allowed}")
        ds = ds.sel(branch=branch or "up")
    elif branch is not None:
        raise ParameterError(f"branch={branch!r} given, but this sweep has no branches (only continuation "
                             "sweeps have 'up' and 'down'); leave it out")
    dims = [d for d in ds[advance].dims]
    if len(dims) != 1:
        raise ParameterError(f"plot_sweep needs a 1-d sweep; {advance} has dims {dims}")
    x = x or dims[0]
    xv = ds[x].values
    # settle-engine sweeps flag "limit_cycle" (descriptors from the periodic orbit)
    swim = ds["limit_cycle" if "limit_cycle" in ds else "swimming"].values.astype(bool) & ~ds["failed"].values
    straight = ds["straight"].values
    adv = np.where(swim, ds[advance].values, np.where(straight, 0.0, np.nan))
    per = np.where(swim, ds[period].values, np.nan)
    red = ds["self_intersecting"].values
    fig, axs = plt.subplots(2, 1, figsize=(5.5, 5.2), sharex=True, constrained_layout=True)
    # no line from a straight point (drawn at zero) to a swimming one: between them lies the
    # onset, and a straight line would draw advances that no point has
    st = np.asarray(straight, bool)
    _coloured(axs[0], xv, adv, red, gaps=st[:-1] != st[1:])
    _coloured(axs[1], xv, per, red)
    unit = ds.attrs.get("time_unit", "s")
    axs[0].set_ylabel("advance / cycle [body lengths]" if advance.endswith("_bl") else advance)
    axs[1].set_ylabel(f"period [{unit}]" if period == "period_s" else period)
    axs[1].set_xlabel(r"$\kappa_E/\kappa_E^{fit}$" if x == "kappa_E_ratio" else x)
    rc = critical_ratio(ds) if x == "kappa_E_ratio" else math.nan
    rd, n = discrete_critical_ratio(ds) if x == "kappa_E_ratio" else (math.nan, 0)
    if math.isfinite(rd):  # where the sweep's own model (N segments) starts to swim
        for ax in axs:
            ax.axvline(rd, color="tab:blue", ls="--", lw=1)
        note = f"; continuum {rc:.4f}" if math.isfinite(rc) else ""
        axs[0].text(rd, axs[0].get_ylim()[1], f" linear onset {rd:.4f} (N = {n}{note})", color="tab:blue", va="top",
                    fontsize=8)
    if math.isfinite(rc):
        for ax in axs:
            ax.axvline(rc, color="0.6", ls=":", lw=1)
    # legend: what the colours mean (proxy handles, not drawn on the axes)
    from matplotlib.lines import Line2D

    proxies = [Line2D([], [], marker="o", color="k", ms=3, lw=1.8, label="swimming stroke")]
    if np.any(np.asarray(red, bool) & np.isfinite(adv)):
        proxies.append(Line2D([], [], marker="o", color="tab:red", ms=3, lw=1.8, label="self-intersecting stroke"))
    failed = ds["failed"].values
    if failed.any():
        axs[0].plot(xv[failed], np.zeros(failed.sum()), "x", color="0.5", label="failed")
    growing = ds["unstable"].values & ~swim & ~failed if "unstable" in ds else np.zeros_like(failed)
    if growing.any():
        axs[0].plot(xv[growing], np.zeros(growing.sum()), "^", mfc="none", color="tab:orange", ms=5,
                    label="unstable, still growing at t_cap")
    axs[0].legend(handles=proxies + axs[0].get_legend_handles_labels()[0], fontsize=7, loc="best", frameon=False)
    reached = ds["reached_limit_cycle" if "reached_limit_cycle" in ds else "limit_cycle_reached"].values.astype(bool)
    capped = (~reached) & swim
    if capped.any():
        axs[1].plot(xv[capped], per[capped], "o", mfc="none", color="0.4", ms=6,
                    label="orbit by continuation (run not settled by t_cap)")
        axs[1].legend(fontsize=8)
    if path is not None:
        from .._paths import atomic_path, check_output_file, figure_metadata

        path = check_output_file(path, (".png", ".pdf", ".svg"), what="path")
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=150, format=path.suffix.lstrip("."), **figure_metadata(path.suffix))
    return fig
