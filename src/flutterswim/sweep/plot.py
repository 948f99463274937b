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


def discrete_critical_ratio(ds, axis: str = "kappa_E_ratio") -> tuple[float, int]:
    """(kappa_E / kappa_E of the base, or the value of another swept ``axis`` in the store's
    units, at the Hopf point of the discrete model the sweep's points ran with, its number of
    segments N); NaN if unavailable. The sweep's points swim from this value on, not from the
    continuum's (0.6835 at N = 24 against 0.6865)."""
    if "sweep_spec" not in ds.attrs:  # (a Dataset built by hand: no model to ask)
        return math.nan, 0
    spec = _spec(ds)
    n = int(spec.settings.n_segments)
    try:
        from ..orbits.linear import hopf_point

        return float(hopf_point(spec.base, axis, n_segments=n).value), n
    except Exception:  # noqa: BLE001 - no Hopf point near the base, or an axis hopf_point does not take
        return math.nan, n


def _coloured(ax, x, y, red, gaps=None, *, color="k", ls="-", marker="o", jumps=None, red_lines=True):
    """Line through (x, y) in ``color``, segments touching a red point in red (``red_lines``;
    else only the red points' markers); none from point i to i + 1 where ``gaps[i]``, a thin
    dotted one where ``jumps[i]`` (a continuation's jump to another stroke: no stroke lies
    between)."""
    x, y, red = np.asarray(x, float), np.asarray(y, float), np.asarray(red, bool)
    for i in range(x.size - 1):
        if not (np.isfinite(y[i]) and np.isfinite(y[i + 1])) or (gaps is not None and gaps[i]):
            continue
        c = "tab:red" if red_lines and (red[i] or red[i + 1]) else color
        if jumps is not None and jumps[i]:
            ax.plot(x[i : i + 2], y[i : i + 2], color=c, lw=0.8, ls=":")
            continue
        ax.plot(x[i : i + 2], y[i : i + 2], color=c, lw=1.8, ls=ls, solid_capstyle="round")
    ok = np.isfinite(y)
    ax.scatter(x[ok & ~red], y[ok & ~red], s=10, color=color, marker=marker, zorder=3)
    ax.scatter(x[ok & red], y[ok & red], s=10, color="tab:red", marker=marker, zorder=3)


def _jumps(per: np.ndarray) -> np.ndarray:
    """Between neighbouring strokes of a continuation branch, a jump to another stroke: the
    period changes by over 5 % and by over 3 times as much as between the neighbouring points
    on either side (a branch followed point to point changes smoothly)."""
    per = np.asarray(per, float)
    d = np.abs(np.diff(per)) / np.maximum(np.abs(per[1:]), 1e-300)
    d = np.where(np.isfinite(d), d, np.nan)
    side = np.fmax(np.r_[np.nan, d[:-1]], np.r_[d[1:], np.nan])  # the larger neighbouring change
    with np.errstate(invalid="ignore"):
        return (d > 0.05) & ~(d <= 3.0 * side)  # (no neighbour: the 5 % alone)


#: outcomes without a stroke other than straight and failed: (variable, marker, colour, label)
_OTHER_OUTCOMES = (("bent_equilibrium", "v", "tab:purple", "bent equilibrium (no stroke)"),
                   ("not_periodic", "D", "tab:orange", "not periodic (no periodic orbit found)"),
                   ("capped", "^", "tab:brown", "capped (unsettled at t_cap, no orbit)"))


def _branch_values(ds, advance: str, period: str):
    """(swimming, straight, advance drawn (0 where straight), period) of a 1-d sweep."""
    # settle-engine sweeps flag "limit_cycle" (descriptors from the periodic orbit)
    # (failed is stored as int8: ~ of it is -1 / -2, and bool & int8 an int8 that indexes by position)
    swim = ds["limit_cycle" if "limit_cycle" in ds else "swimming"].values.astype(bool) & ~ds["failed"].values.astype(bool)
    straight = ds["straight"].values.astype(bool)
    adv = np.where(swim, ds[advance].values, np.where(straight, 0.0, np.nan))
    per = np.where(swim, ds[period].values, np.nan)
    return swim, straight, adv, per


def _once(handles: list) -> list:
    """Legend handles, each label once (both branches of a continuation sweep mark their failed
    or unsettled points under one label)."""
    seen: set = set()
    return [h for h in handles if not (h.get_label() in seen or seen.add(h.get_label()))]


def _axis_label(ds, x: str) -> str:
    """The swept axis's label with its units (from the store's coordinate)."""
    if x == "kappa_E_ratio":
        return r"$\kappa_E/\kappa_E^{fit}$"
    units = str(ds[x].attrs.get("units", "")).strip()
    return f"{x} [{units}]" if units and units != "1" else x


def _branch_orders(ds) -> tuple[str, str]:
    """How a continuation's branches ran: "up" in increasing value, "down" back; a store made
    before stop 46 with its axis not in increasing order ran "up" in the order given (its
    figure had said "increasing")."""
    try:
        legacy = _spec(ds).legacy_up_order
    except (KeyError, TypeError, ValueError):  # (a Dataset not read from a store)
        legacy = False
    return ("in the order given", "in reverse order") if legacy else ("increasing", "decreasing")


def plot_sweep(ds, path: str | None = None, *, x: str | None = None, branch: str | None = None,
               advance: str = "advance_per_cycle_bl", period: str = "period_s") -> Any:
    """Two panels (advancement per cycle, period) against the swept axis (default
    ``kappa_E_ratio``); returns the Figure, saved to ``path`` if given (Agg backend). A
    continuation sweep draws both its branches ("up", then "down"; ``branch``: one of them),
    a jump to another stroke dotted; points without a stroke are marked by their outcome."""
    from ..plotting._common import new_figure
    from matplotlib.lines import Line2D

    if "branch" in ds.dims:
        allowed = [str(b) for b in ds["branch"].values]
        if branch is not None and branch not in allowed:
            raise ParameterError(f"branch={branch!r} is not a branch of this sweep; choose one of {allowed}")
        branches = [(b, ds.sel(branch=b)) for b in ([branch] if branch else allowed)]
    elif branch is not None:
        raise ParameterError(f"branch={branch!r} given, but this sweep has no branches (only continuation "
                             "sweeps have 'up' and 'down'); leave it out")
    else:
        branches = [(None, ds)]
    dims = [d for d in branches[0][1][advance].dims]
    if len(dims) != 1:
        raise ParameterError(
            f"the sweep has {len(dims)} axes ({', '.join(dims)}); its figure draws one axis: select a row, e.g. "
            f"plot_sweep(ds.isel({dims[0]}=0)), or read the store with xarray.open_zarr for a map")
    x = x or dims[0]
    xv = np.asarray(ds[x].values, float)
    rising, falling = _branch_orders(ds)
    fig = new_figure((5.5, 5.2), shown=path is None)
    axs = fig.subplots(2, 1, sharex=True)
    styles = {None: ("k", "-", "o"), "up": ("k", "-", "o"), "down": ("tab:blue", "--", "s")}
    proxies = []
    any_red = False
    for name, d in branches:
        color, ls, marker = styles.get(name, ("k", "-", "o"))
        swim, straight, adv, per = _branch_values(d, advance, period)
        red = np.asarray(d["self_intersecting"].values, float) == 1.0  # (NaN, no stroke: not red)
        any_red |= bool(np.any(red & np.isfinite(adv)))
        jumps = _jumps(per) if name is not None else None
        # no line from a straight point (drawn at zero) to a swimming one: between them lies the
        # onset, and a straight line would draw advances that no point has
        # two branches: their own colours, the self-intersecting strokes by red markers alone
        kw = dict(color=color, ls=ls, marker=marker, jumps=jumps, red_lines=len(branches) == 1)
        _coloured(axs[0], xv, adv, red, gaps=straight[:-1] != straight[1:], **kw)
        _coloured(axs[1], xv, per, red, **kw)
        label = {None: "swimming stroke", "up": f"up: {x} {rising}, each point from the one before",
                 "down": f"down: {x} {falling}"}.get(name, str(name))
        proxies.append(Line2D([], [], marker=marker, color=color, ms=3, lw=1.8, ls=ls, label=label))
        if jumps is not None and jumps.any() and not any(h.get_label().startswith("jump") for h in proxies):
            proxies.append(Line2D([], [], color="0.3", lw=0.8, ls=":", label="jump to another stroke"))
        # points that settled into neither a stroke nor the straight state, and failed ones: on the
        # zero line, by outcome (a sweep whose upper points all ended so was drawn as if it
        # stopped at its last straight point)
        for var, mk, col, lab in _OTHER_OUTCOMES:
            hit = d[var].values.astype(bool) if var in d else np.zeros(xv.size, bool)
            if hit.any():
                axs[0].plot(xv[hit], np.zeros(hit.sum()), mk, mfc="none", color=col, ms=5, label=lab)
        failed = d["failed"].values.astype(bool)
        if failed.any():
            axs[0].plot(xv[failed], np.zeros(failed.sum()), "x", color="0.5", label="failed")
        if "swim_direction_deg" in d:
            # past the fold of the kappa_E branch (ratio > 2.1) the stroke swims the other way;
            # the advance drawn is its size: marked, so that the reversal is not hidden
            back = swim & (np.cos(np.radians(np.asarray(d["swim_direction_deg"].values, float))) < 0)
            if back.any():
                axs[0].plot(xv[back], adv[back], "v", color="tab:purple", ms=6, mfc="none",
                            label="swims against the field (advance drawn as its size)")
        reached = d["reached_limit_cycle" if "reached_limit_cycle" in d else "limit_cycle_reached"].values.astype(bool)
        unsettled = (~reached) & swim
        if unsettled.any():
            axs[1].plot(xv[unsettled], per[unsettled], "o", mfc="none", color="0.4", ms=6,
                        label="orbit by continuation (run not settled by t_cap)")
    if any_red:
        proxies.append(Line2D([], [], marker="o", color="tab:red", ms=3, lw=1.8 if len(branches) == 1 else 0,
                              label="self-intersecting stroke"))
    pad = 0.02 * float(np.ptp(xv)) if xv.size > 1 else 0.5
    axs[1].set_xlim(float(xv.min()) - pad, float(xv.max()) + pad)  # every point, drawn or not
    unit = ds.attrs.get("time_unit", "s")
    axs[0].set_ylabel("advance / cycle [body lengths]" if advance.endswith("_bl") else advance)
    axs[1].set_ylabel(f"period [{unit}]" if period == "period_s" else period)
    axs[1].set_xlabel(_axis_label(ds, x))
    for ax in axs:
        ax.ticklabel_format(axis="y", useOffset=False)
    rc = critical_ratio(ds) if x == "kappa_E_ratio" and "sweep_spec" in ds.attrs else math.nan
    rd, n = discrete_critical_ratio(ds, x)
    lo, hi = axs[1].get_xlim()
    rc = rc if lo <= rc <= hi else math.nan  # (outside the range swept: not drawn)
    rd = rd if lo <= rd <= hi else math.nan
    if math.isfinite(rd):  # where the sweep's own model (N segments) starts to swim
        for ax in axs:
            ax.axvline(rd, color="tab:blue", ls="--", lw=1)
        note = f"; continuum {rc:.4g}" if math.isfinite(rc) else ""
        axs[0].annotate(f" linear onset {rd:.4g} (N = {n}{note})", (rd, 1.0), xycoords=("data", "axes fraction"),
                        xytext=(2, -3), textcoords="offset points", color="tab:blue", va="top", fontsize=8)
    if math.isfinite(rc):
        for ax in axs:
            ax.axvline(rc, color="0.6", ls=":", lw=1)
    axs[0].legend(handles=_once(proxies + axs[0].get_legend_handles_labels()[0]), fontsize=7, loc="best",
                  frameon=False)
    if axs[1].get_legend_handles_labels()[0]:
        axs[1].legend(handles=_once(axs[1].get_legend_handles_labels()[0]), fontsize=8)
    if path is not None:
        from .._paths import save_figure_file

        save_figure_file(fig, path, dpi=150, suffixes=(".png", ".pdf", ".svg"))
    return fig
