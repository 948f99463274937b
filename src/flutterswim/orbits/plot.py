"""Figure of a stroke branch (the paper's Fig. 4b, done by continuation): advance per cycle
along the field (negative where the stroke swims against it), period and the lateral
excursions of both ends against the parameter, with the straight state from linear theory on
its stable side of the Hopf point (the branch may lie above or below it) and
self-intersecting strokes in red."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_branch"]


def _segments(ax, x, y, red, unstable=None, **kw):
    """Plot y(x) in black where ``red`` is false and in red where it is true; open circles on
    the ``unstable`` orbits."""
    if unstable is not None and np.any(unstable):
        ax.plot(x[unstable], y[unstable], "o", mfc="none", color="tab:orange", ms=4, zorder=3)
    label = kw.pop("label", None)
    ax.plot(x, np.where(red, np.nan, y), color=kw.pop("color", "k"), label=label, **kw)
    if np.any(red):
        # include the last black point so that the red run joins the black one
        joined = red | np.r_[red[1:], False]
        ax.plot(x, np.where(joined, y, np.nan), color="tab:red", lw=kw.get("lw", 1.8), ls=kw.get("ls", "-"))


def plot_branch(ds, path=None, *, x_range: tuple[float, float] | None = None):
    """Draw the branch Dataset of :meth:`flutterswim.orbits.Branch.to_dataset`. Returns the figure.
    ``x_range``: the requested parameter range (default: the file's ``range_start`` or
    ``range_end`` with the branch's own values); the axis spans it, the branch and the Hopf point."""
    from ..plotting._common import new_figure
    from matplotlib.lines import Line2D

    name = ds.attrs["parameter"]
    x = ds[name].values
    hopf = float(ds.attrs[f"hopf_{name}"])
    si = ds.period.attrs["units"] == "s"
    lscale, lunit = (1e3, "mm") if si else (1.0, "l")
    tunit = "s" if si else "tau"
    red = ds.self_intersecting.values.astype(bool)
    unstable = ~ds.stable.values.astype(bool)
    # the branch may lie on either side of the Hopf point; the straight state is stable on the
    # other side (supercritical) or on the branch's side (subcritical: unstable orbits)
    # (the side the branch leaves the Hopf point to: a subcritical branch may fold back past it)
    first = x[np.isfinite(x) & (x != hopf)]
    side = 1.0 if (first[0] if first.size else np.nanmedian(x)) >= hopf else -1.0
    stable_side = side if ds.attrs.get("bifurcation") == "subcritical" else -side
    if x_range is None:  # the requested range, as far as the file records it
        ends = [float(ds.attrs[k]) for k in ("range_start", "range_end") if k in ds.attrs]
        x_range = (min(ends), max(ends)) if ends else None
    pts = np.r_[hopf, x[np.isfinite(x)]]
    lo, hi = float(pts.min()), float(pts.max())
    if x_range is not None:
        lo, hi = min(lo, *x_range), max(hi, *x_range)
    elif stable_side != side:  # no range recorded: show a tenth of the branch's extent of the stable side
        pad = 0.1 * (hi - lo)
        lo, hi = (lo - pad, hi) if stable_side < 0 else (lo, hi + pad)
    straight_end = lo if stable_side < 0 else hi
    xs = np.r_[hopf, x]
    fig = new_figure((6.0, 8.8), shown=path is None)
    axes = fig.subplots(3, 1, sharex=True)
    ax = axes[0]
    ax.plot(sorted([straight_end, hopf]), [0, 0], color="0.5", lw=1.8, label="straight, stable (linear theory)")
    # the straight state past the Hopf point: still a solution, unstable (a review: left out)
    other_end = hi if stable_side < 0 else lo
    ax.plot(sorted([hopf, other_end]), [0, 0], color="0.5", lw=1.2, ls="--", label="straight, unstable")
    un = np.r_[False, unstable]
    # signed along the field: past the kappa_E fold strokes swim against it (swim_direction
    # 180 degrees); as a magnitude they looked like a second forward branch bouncing off zero
    along = np.cos(np.radians(ds.swim_direction.values)) if "swim_direction" in ds else 1.0
    _segments(ax, xs, np.r_[0.0, ds.advance.values * along * lscale], np.r_[False, red], un, lw=1.8,
              label="stroke (periodic orbit)")
    ax.set_ylabel(f"advance per cycle along the field [{lunit}]")
    ax2 = axes[1]
    _segments(ax2, xs, np.r_[ds.attrs["hopf_period"], ds.period.values], np.r_[False, red], un, lw=1.8)
    ax2.plot(hopf, ds.attrs["hopf_period"], "o", color="k", ms=4)
    ax2.set_ylabel(f"period [{tunit}]")
    ax3 = axes[2]
    # where the swimmer reverses the other end leads: the curves break there (no line from one
    # end's excursion to the other's)
    cut = np.nonzero(np.diff(ds["leading_end"].values))[0] + 2 if "leading_end" in ds else np.array([], int)
    xl, rl, ul = np.insert(xs, cut, np.nan), np.insert(np.r_[False, red], cut, False), np.insert(un, cut, False)
    for var, kw in (("lateral_leading", {"label": "leading end"}), ("lateral_trailing", {"ls": "--", "label": "trailing end"})):
        _segments(ax3, xl, np.insert(np.r_[0.0, ds[var].values * lscale], cut, np.nan), rl, ul, lw=1.8, **kw)
    ax3.set_ylabel(f"lateral peak-to-peak [{lunit}]")
    ax3.set_xlabel(f"{name} [{ds[name].attrs.get('units', '1')}]")
    for a in axes:
        a.axvline(hopf, color="0.3", ls=":", lw=1)
        a.set_xlim(lo, hi)
    # the label on the side of the Hopf line with more room, inside the axes
    right = hopf - lo < hi - hopf
    axes[0].text(hopf, 0.97, f" Hopf {hopf:.4g} ", transform=axes[0].get_xaxis_transform(), fontsize=8, va="top",
                 ha="left" if right else "right")
    handles = [Line2D([], [], color="0.5", lw=1.8, label="straight, stable (linear theory)"),
               Line2D([], [], color="0.5", lw=1.2, ls="--", label="straight, unstable"),
               Line2D([], [], color="k", lw=1.8, label="stroke (periodic orbit)"),
               Line2D([], [], color="0.3", ls=":", label="Hopf point (discrete linear stability)")]
    if np.any(red):  # (only what the branch draws: a review found the red entry on branches without it)
        handles.insert(3, Line2D([], [], color="tab:red", lw=1.8, label="self-intersecting stroke"))
    if np.any(unstable):
        handles.insert(3, Line2D([], [], marker="o", mfc="none", color="tab:orange", ls="none", ms=4,
                                 label="unstable orbit (a Floquet multiplier outside the unit circle)"))
    # below the panels: inside, "best" covered the stroke just past the onset
    fig.legend(handles=handles, fontsize=8, loc="outside lower center", ncols=2)
    h3 = [Line2D([], [], color="k", lw=1.8, label="leading end"),
          Line2D([], [], color="k", lw=1.8, ls="--", label="trailing end")]
    ax3.legend(handles=h3, fontsize=8, loc="lower right")
    l1 = ds.attrs.get("lyapunov_coefficient")
    n = ds.attrs.get("n_segments")
    # (l1's size depends on the eigenvector's normalisation, over the 2N + 1 components: ~1/N;
    # its sign decides the bifurcation, so the sign and N are given with it)
    axes[0].set_title(f"Stroke branch: {ds.attrs.get('bifurcation', '')} Hopf bifurcation"
                      + (f" (l1 = {l1:.3g} {'<' if l1 < 0 else '>'} 0" + (f", N = {n})" if n is not None else ")")
                         if l1 is not None else ""), fontsize=10)
    if path is not None:

        from .._paths import save_figure_file

        save_figure_file(fig, path, dpi=150)
    return fig
