"""Publication figures: ghosts of one stroke, the swimmer, descriptors over time, kymographs.

Every function takes a Track or a result-like object and ``path``: with a path the figure is
saved (PNG/PDF/SVG from the suffix) and the path is returned; without, the matplotlib Figure
is returned. Lengths are shown in mm, times in s (a dimensionless run's in l and tau).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from .._validate import ParameterError
from ..analysis.cycles import Cycles, detect_cycles, tip_index
from ..analysis.descriptors import per_cycle
from ..analysis.kymograph import body_kymograph, kymograph_windows, line_kymograph
from ..analysis.track import as_track
from ._common import (
    FIELD_COLOR, GREEN_CMAP, SWIM_COLOR, TIP_COLOR, field_arrow, finish, figure_units, new_figure, window_indices,
)

__all__ = ["plot_ghosts", "plot_swimmer", "plot_descriptors", "plot_kymographs", "plot_summary", "draw_ghosts",
           "draw_kymographs", "path_sections"]


def _cycle_window(tr, cycles: Cycles | None, cycle: int | None, window):
    if window is not None:
        return tuple(window)
    cyc = detect_cycles(tr) if cycles is None else cycles
    if cyc.n_cycles == 0:
        return (float(tr.t[0]), float(tr.t[-1]))
    k = cyc.n_cycles - 1 if cycle is None else int(cycle)
    if not -cyc.n_cycles <= k < cyc.n_cycles:
        raise ParameterError(f"cycle={cycle!r} is out of range; {cyc.n_cycles} cycles were detected")
    k %= cyc.n_cycles
    return (float(cyc.starts[k]), float(cyc.starts[k + 1]))


def draw_ghosts(ax, obj: Any, window: tuple[float, float], *, n_ghosts: int = 8, tip_trail=None,
                field: bool = True, title: str | None = None, tip: int | str = "end") -> None:
    """Draw ``n_ghosts`` configurations over ``window`` in shades of green, the tip trajectory
    over ``tip_trail`` (default: the window) in magenta and the field arrow on ``ax``."""
    import matplotlib

    tr = as_track(obj)
    f, L, T = figure_units(tr)
    idx = window_indices(tr.t, window)
    pick = idx[np.unique(np.linspace(0, idx.size - 1, max(2, n_ghosts)).round().astype(int))]
    cmap = matplotlib.colormaps[GREEN_CMAP]
    for n, i in enumerate(pick):
        c = cmap(0.35 + 0.6 * n / max(1, pick.size - 1))
        ax.plot(tr.x[i] * f, tr.y[i] * f, color=c, lw=1.6, solid_capstyle="round")
    tidx = window_indices(tr.t, window if tip_trail is None else tip_trail)
    it = tip_index(tr, tip)
    ax.plot(tr.x[tidx, it] * f, tr.y[tidx, it] * f, color=TIP_COLOR, lw=1.0,
            label=f"tip ({'s = l' if it == tr.n_points - 1 else 's = 0'}) trajectory")
    from matplotlib.lines import Line2D

    shapes = Line2D([], [], color=cmap(0.7), lw=1.6, label="filament, light to dark in time")
    ax.legend(handles=ax.get_legend_handles_labels()[0] + [shapes], fontsize=6, loc="best", frameon=False)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x ({L})")
    ax.set_ylabel(f"y ({L})")
    if field:
        field_arrow(ax, float(np.mean(tr.field_angle[idx])))
    ax.set_title(title or f"t = {window[0]:.2f}–{window[1]:.2f} {T}", fontsize=9)


def plot_ghosts(obj: Any, path: str | Path | None = None, *, cycle: int | None = None,
                window: tuple[float, float] | None = None, cycles: Cycles | None = None, n_ghosts: int = 8,
                tip: int | str = "end", figsize=(6.0, 3.0), dpi: float = 150) -> Any:
    """Ghosts of one stroke cycle (default: the last detected) in greens with the trajectory
    of the tip (``tip``: "end" = s=l, "start" = s=0) in magenta and the field arrow in red."""
    tr = as_track(obj)
    win = _cycle_window(tr, cycles, cycle, window)
    fig = new_figure(figsize, dpi, shown=path is None)
    ax = fig.add_subplot()
    draw_ghosts(ax, tr, win, n_ghosts=n_ghosts, tip=tip)
    return finish(fig, path)


def plot_swimmer(obj: Any, path: str | Path | None = None, *, time: float | None = None, trail: bool = True,
                 tip: int | str = "end", figsize=(6.0, 3.0), dpi: float = 150) -> Any:
    """The filament at ``time`` (default: the last frame), with the tip trajectory up to that
    time, the centroid path and the field arrow."""
    tr = as_track(obj)
    f, L, T = figure_units(tr)
    i = tr.n_frames - 1 if time is None else int(np.argmin(np.abs(tr.t - float(time))))
    it = tip_index(tr, tip)
    fig = new_figure(figsize, dpi, shown=path is None)
    ax = fig.add_subplot()
    if trail:
        ax.plot(tr.x[: i + 1, it] * f, tr.y[: i + 1, it] * f, color=TIP_COLOR, lw=0.8,
                label=f"tip ({'s = l' if it == tr.n_points - 1 else 's = 0'}) trajectory")
        xc, yc = tr.centroid()
        ax.plot(xc[: i + 1] * f, yc[: i + 1] * f, color=SWIM_COLOR, lw=1.2, label="centroid trajectory")
    ax.plot(tr.x[i] * f, tr.y[i] * f, color="#1a7f37", lw=2.5, solid_capstyle="round")
    ax.plot(tr.x[i, it] * f, tr.y[i, it] * f, "o", color=TIP_COLOR, ms=3)
    field_arrow(ax, float(tr.field_angle[i]))
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x ({L})")
    ax.set_ylabel(f"y ({L})")
    ax.set_title(f"t = {tr.t[i]:.3f} {T}", fontsize=9)
    if trail:
        ax.legend(fontsize=7, loc="lower right", frameon=False)
    return finish(fig, path)


def _end_label(tr, i_end: int, pc: dict) -> str:
    """Legend of the measured end's lateral peak-to-peak: which end (s = 0 or s = l), and whether
    it leads or trails, when the cycles advance by more than 1 % of the body length."""
    at = "s = 0" if i_end == 0 else ("s = l" if i_end in (-1, tr.x.shape[1] - 1) else f"sample {i_end}")
    dx, dy = float(np.sum(pc["dx"])), float(np.sum(pc["dy"]))
    d = math.hypot(dx, dy)
    if at == f"sample {i_end}" or not d > 0.01 * tr.length:
        return f"lateral p-p at {at}"
    from ..analysis.descriptors import start_ahead  # (describe's rule for the leading end)

    leads = (start_ahead(tr, math.atan2(dy, dx)) > 0) == (at == "s = 0")
    return f"lateral p-p, {'leading' if leads else 'trailing'} end ({at})"


def plot_descriptors(obj: Any, path: str | Path | None = None, *, cycles: Cycles | None = None,
                     figsize=(6.5, 6.0), dpi: float = 150) -> Any:
    """Per-cycle descriptors against time: amplitude envelope (log) with the exponential fit,
    period, advancement per cycle along the field, the measured end's lateral peak-to-peak
    (named leading or trailing) and
    nonreciprocity; the transient is shaded and the limit-cycle time marked."""
    tr = as_track(obj)
    cyc = detect_cycles(tr) if cycles is None else cycles
    f, L, T = figure_units(tr)
    fig = new_figure(figsize, dpi, shown=path is None)
    axs = fig.subplots(4, 1, sharex=True)
    if cyc.n_cycles == 0:
        for ax in axs:
            ax.text(0.5, 0.5, "no complete cycle", transform=ax.transAxes, ha="center")
        axs[-1].set_xlabel(f"t ({T})")
        return finish(fig, path)
    pc = per_cycle(tr, cyc)
    tm = cyc.mids
    ax = axs[0]
    ax.semilogy(tm, cyc.amplitudes * f, "o-", ms=3, color="#1a7f37", label="section amplitude")
    if math.isfinite(cyc.growth_rate):
        a, b = cyc.growth_fit_window
        sel = (tm >= a) & (tm <= b)
        la = np.log(cyc.amplitudes[sel] * f)
        c0 = float(np.mean(la - cyc.growth_rate * tm[sel]))
        tt = np.linspace(a, b, 20)
        ax.semilogy(tt, np.exp(c0 + cyc.growth_rate * tt), "--", color="k", lw=1,
                    label=f"fit: {cyc.growth_rate:.3g} ± {cyc.growth_rate_stderr:.1g} 1/{T}")
    ax.set_ylabel(f"amplitude ({L})")
    ax.legend(fontsize=7, frameon=False)
    axs[1].plot(tm, pc["period"], "o-", ms=3, color="#1f77b4")
    axs[1].set_ylabel(f"period ({T})")
    axs[2].plot(tm, pc["advance"] * f, "o-", ms=3, color=SWIM_COLOR, label="advance / cycle")
    axs[2].plot(tm, pc["tip_p2p"] * f, "s-", ms=3, color=TIP_COLOR, label=_end_label(tr, cyc.tip, pc))
    axs[2].set_ylabel(f"length ({L})")
    axs[2].legend(fontsize=7, frameon=False)
    axs[3].plot(tm, pc["nonreciprocity"], "o-", ms=3, color="0.3")
    axs[3].axhline(0, color="0.7", lw=0.8)
    axs[3].set_ylabel("nonreciprocity (–)")
    axs[3].set_xlabel(f"t ({T})")
    for ax in axs:
        if cyc.limit_cycle:
            ax.axvspan(tr.t[0], cyc.limit_cycle_time, color="0.9", zorder=0)
            ax.axvline(cyc.limit_cycle_time, color="0.4", lw=0.8, ls=":")
        if math.isfinite(cyc.onset_time):
            ax.axvline(cyc.onset_time, color=FIELD_COLOR, lw=0.8, ls=":")
    axs[0].set_title("shaded: transient; red dotted: onset; grey dotted: limit cycle reached", fontsize=8)
    return finish(fig, path)


def path_sections(obj: Any):
    """Kymographs of two sections placed where the swimmer is: the line through its mean path
    (the straight fit to the centroid path; positions along it) and the section across the
    path that moves with the centroid (positions across the path). Returns
    (along, across, path angle [rad]) as :class:`LineKymograph` in path coordinates."""
    from ..analysis.track import Track

    tr = as_track(obj)
    xc, yc = tr.centroid()
    # mean path: least-squares line through the centroid positions (direction of largest spread,
    # or the net displacement when the swimmer hardly moves)
    X = np.c_[xc - xc.mean(), yc - yc.mean()]
    if np.ptp(xc) + np.ptp(yc) > 0:
        _, _, vt = np.linalg.svd(X, full_matrices=False)
        e = vt[0]
        if e @ np.r_[xc[-1] - xc[0], yc[-1] - yc[0]] < 0:
            e = -e
    else:
        e = np.r_[1.0, 0.0]
    ang = math.atan2(e[1], e[0])
    c, s_ = math.cos(ang), math.sin(ang)
    u = (tr.x - xc.mean()) * c + (tr.y - yc.mean()) * s_  # along the path
    w = -(tr.x - xc.mean()) * s_ + (tr.y - yc.mean()) * c  # across it
    uc = (xc - xc.mean()) * c + (yc - yc.mean()) * s_
    path = Track(t=tr.t, x=u, y=w, s=tr.s, length=tr.length, units=tr.units)
    along = line_kymograph(path, "horizontal", 0.0)  # the mean path itself: w = 0
    moving = Track(t=tr.t, x=u - uc[:, None], y=w, s=tr.s, length=tr.length, units=tr.units)
    across = line_kymograph(moving, "vertical", 0.0)  # the section through the centroid
    return along, across, ang


def draw_kymographs(axs, obj: Any, window: tuple[float, float] | None = None, *, h_level=None, v_level=None) -> None:
    """Fill four axes with: crossings of the swimmer's mean path (positions along it against t),
    of the section across the path moving with the centroid (positions across the path), the
    curvature of the shape theta_s(s, t) and body-frame tangent angle theta(s, t). With ``h_level`` /
    ``v_level`` the sections are the fixed lab lines y = h_level and x = v_level instead."""
    tr = as_track(obj)
    if window is not None:
        tr = tr.window(*window)
    f, L, T = figure_units(tr)
    along, across, ang = path_sections(tr)
    panels = [(along, f"position along the path ({L})",
               f"crossings of the mean path ({int(round(math.degrees(ang))) + 0}° to x)"),
              (across, f"position across the path ({L})", "crossings of the section moving with the centroid")]
    if h_level is not None:
        k = line_kymograph(tr, "horizontal", h_level)
        panels[0] = (k, f"x ({L})", f"crossings of y = {k.level * f:.3g} {L}")
    if v_level is not None:
        k = line_kymograph(tr, "vertical", v_level)
        panels[1] = (k, f"y ({L})", f"crossings of x = {k.level * f:.3g} {L}")
    for ax, (k, ylab, title) in zip(axs[:2], panels):
        tt = np.broadcast_to(k.t[:, None], k.positions.shape)
        ok = np.isfinite(k.positions)
        sc = ax.scatter(tt[ok], k.positions[ok] * f, c=k.s[ok] / tr.length, s=2, cmap="viridis", vmin=0, vmax=1,
                        linewidths=0)
        ax.set_title(title, fontsize=8)
        ax.set_xlabel(f"t ({T})")
        ax.set_ylabel(ylab)
        ax.set_xlim(tr.t[0], tr.t[-1])
    axs[1].figure.colorbar(sc, ax=axs[1], label="s / l of the crossing point (both panels)")
    bk = body_kymograph(tr)
    kap = bk.kappa / f  # 1/mm (1/l)
    lim = float(np.max(np.abs(kap))) or 1.0
    im = axs[2].pcolormesh(bk.t, bk.s / tr.length, kap.T, cmap="RdBu_r", vmin=-lim, vmax=lim, shading="nearest",
                           rasterized=True)
    axs[2].figure.colorbar(im, ax=axs[2], label=f"θ_s (1/{L})")  # (κ is the spontaneous curvature)
    axs[2].set_ylabel("s / l")
    axs[2].set_xlabel(f"t ({T})")
    axs[2].set_title("curvature of the shape", fontsize=8)
    lim = float(np.max(np.abs(bk.theta))) or 1.0
    im = axs[3].pcolormesh(bk.t, bk.s_mid / tr.length, bk.theta.T, cmap="PuOr_r", vmin=-lim, vmax=lim,
                           shading="nearest", rasterized=True)
    axs[3].figure.colorbar(im, ax=axs[3], label="θ − ⟨θ⟩ (rad)")
    axs[3].set_ylabel("s / l")
    axs[3].set_xlabel(f"t ({T})")
    axs[3].set_title("tangent angle (body frame)", fontsize=8)


def plot_kymographs(obj: Any, path: str | Path | None = None, *, window: tuple[float, float] | None = None,
                    h_level: float | None = None, v_level: float | None = None, figsize=(7.5, 5.5),
                    dpi: float = 150) -> Any:
    """Kymographs over ``window`` (default: the whole track): lab-frame line crossings (dots
    coloured by arc length) and body-frame curvature / tangent-angle maps."""
    tr = as_track(obj)
    fig = new_figure(figsize, dpi, shown=path is None)
    axs = fig.subplots(2, 2).ravel()
    draw_kymographs(axs, tr, window, h_level=h_level, v_level=v_level)
    return finish(fig, path)


def plot_summary(obj: Any, path: str | Path | None = None, *, cycles: Cycles | None = None, n_cycles: int = 3,
                 figsize=(10.0, 8.0), dpi: float = 150) -> Any:
    """Paper-style overview: ghosts of a cycle near onset and at the limit cycle (with the tip
    trajectory over the whole run), and kymographs of both windows."""
    tr = as_track(obj)
    cyc = detect_cycles(tr) if cycles is None else cycles
    wins = kymograph_windows(tr, n_cycles=n_cycles, cycles=cyc)
    fig = new_figure(figsize, dpi, shown=path is None)
    gs = fig.add_gridspec(3, 4, height_ratios=[1.0, 1.0, 1.0])
    full = (float(tr.t[0]), float(tr.t[-1]))
    # the windows named by what the run did: a run without an onset or a limit cycle (describe's
    # verdicts) has its first and last cycles, not "onset" and "limit" (a review: a run below
    # settling titled its last cycles "limit")
    said = {"onset": "onset" if math.isfinite(cyc.onset_time) else "first cycles (no onset found)",
            "limit": "limit cycle" if cyc.limit_cycle else "last cycles (no limit cycle)"}
    for col, (name, (a, b)) in enumerate(wins.items()):
        ax = fig.add_subplot(gs[0, 2 * col : 2 * col + 2])
        per = (b - a) / max(1, n_cycles)
        draw_ghosts(ax, tr, (a, min(b, a + per)), tip_trail=full,
                    title=f"{said.get(name, name)}: t = {a:.2f}–{a + per:.2f} {figure_units(tr)[2]}")
        axs = [fig.add_subplot(gs[1 + r, 2 * col + c]) for r in range(2) for c in range(2)]
        draw_kymographs(axs, tr, (a, b))
    return finish(fig, path)
