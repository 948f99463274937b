"""Shared helpers: Agg figures without pyplot, unit conversion, field arrow, saving."""

from __future__ import annotations

import contextlib
import contextvars
import math
from pathlib import Path
from typing import Any

import numpy as np

from .._validate import ParameterError

GREEN_CMAP = "Greens"
TIP_COLOR = "#d01c8b"  # magenta
FIELD_COLOR = "#d62728"  # red
SWIM_COLOR = "#e6b800"  # yellow


_OFFSCREEN = contextvars.ContextVar("flutterswim_offscreen", default=False)


@contextlib.contextmanager
def offscreen():
    """Within it, every figure is an Agg figure without pyplot, also those returned to the
    caller (a batch job that saves them itself: reproduce)."""
    token = _OFFSCREEN.set(True)
    try:
        yield
    finally:
        _OFFSCREEN.reset(token)


def new_figure(figsize: tuple[float, float], dpi: float = 150, *, shown: bool = False):
    """A matplotlib Figure, laid out constrained. One the function saves: an Agg canvas, no
    pyplot, nothing left open in a session and its backend never switched. ``shown``, one it
    returns for the screen (its ``path`` None): made by pyplot in the session's own backend, at
    its dpi, so plt.show() and a notebook display it (an Agg figure showed only as text there),
    except within :func:`offscreen`."""
    if shown and not _OFFSCREEN.get():
        import matplotlib.pyplot as plt

        return plt.figure(figsize=figsize, layout="constrained")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def figure_units(track) -> tuple[float, str, str]:
    """(factor, length unit, time unit) of a figure: track lengths times ``factor`` are in the
    length unit; mm and s, or l and tau for a dimensionless run (fs.Groups), whose lengths are
    in body lengths and times in tau (shown in mm and s they read 1000 times too long)."""
    if track.meta.get("dimensionless"):
        return track.scale_m, "l", "τ"
    return track.scale_m * 1e3, "mm", "s"


def field_arrow(ax, angle: float, *, anchor=(0.08, 0.85), length_pt: float = 28.0, label: str = "E"):
    """Red arrow in the field direction (drawn in screen space, independent of data limits).
    Returns the annotation; update with :func:`set_field_arrow`."""
    ann = ax.annotate(
        "",
        xy=anchor,
        xycoords="axes fraction",
        xytext=(-length_pt * math.cos(angle), -length_pt * math.sin(angle)),
        textcoords="offset points",
        arrowprops=dict(arrowstyle="-|>", color=FIELD_COLOR, lw=2.0, mutation_scale=14),
        annotation_clip=False,
    )
    txt = ax.annotate(
        label, xy=anchor, xycoords="axes fraction", xytext=(6, 6), textcoords="offset points",
        color=FIELD_COLOR, fontsize=10, fontweight="bold",
    )
    ann._fs_length = length_pt  # type: ignore[attr-defined]
    ann._fs_label = txt  # type: ignore[attr-defined]
    return ann


def set_field_arrow(ann, angle: float) -> None:
    L = ann._fs_length
    ann.xyann = (-L * math.cos(angle), -L * math.sin(angle))


def finish(fig, path: str | Path | None, dpi: float | None = None) -> Any:
    """Save to ``path`` (format from its suffix: png, pdf, svg) and return the path, or return
    the figure when path is None."""
    if path is None:
        return fig
    p = Path(path)
    if p.suffix.lower() not in (".png", ".pdf", ".svg", ".jpg", ".jpeg"):
        raise ParameterError(f"path={str(path)!r} has an unsupported suffix; use .png, .pdf, .svg or .jpg")
    from .._paths import atomic_path, check_output_file, figure_metadata

    check_output_file(p, (".png", ".pdf", ".svg", ".jpg", ".jpeg"), what="path")
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=dpi or fig.dpi, format=p.suffix.lower().lstrip(".").replace("jpg", "jpeg"),
                    **figure_metadata(p.suffix))
    return p


def window_indices(t: np.ndarray, window: tuple[float, float] | None) -> np.ndarray:
    if window is None:
        return np.arange(t.size)
    t0, t1 = window
    idx = np.nonzero((t >= t0) & (t <= t1))[0]
    if idx.size < 1:
        raise ParameterError(f"window={window!r} holds no frame; times run from {t[0]:.4g} to {t[-1]:.4g} s")
    return idx
