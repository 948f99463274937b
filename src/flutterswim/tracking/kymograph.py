"""Kymographs from the raw frames, as in the paper's Fig. 3c: the intensity along a horizontal
and a vertical line through the swimmer's path at every frame, with the average-velocity
line, and the intensity along the tracked body (s, t).

Pixel coordinates: x = column, y = row; the lines are a row (horizontal) and a column
(vertical) of the frame (after the ROI), each averaged over ``band`` adjacent pixels.
"""

from __future__ import annotations

import math

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage as ndi

from .._validate import ParameterError
from ..analysis.track import Track
from .io import open_frames

__all__ = ["RawKymographs", "raw_kymographs", "plot_raw_kymographs"]


@dataclass(frozen=True, eq=False)
class RawKymographs:
    """t: (T,) s; horizontal: (T, W) intensity along the row ``row``; vertical: (T, H) along the
    column ``col``; body: (T, P) intensity along the tracked centreline (NaN on failed
    frames), at s (P,) mm; velocity: (vx, vy) mm/s of the centroid (least squares over the
    tracked frames) and x0, y0 its position at t[0] [mm]; px_per_mm; frame: one raw frame
    (the middle one) for the overview."""

    t: np.ndarray
    horizontal: np.ndarray
    vertical: np.ndarray
    row: int
    col: int
    body: np.ndarray
    s: np.ndarray
    velocity: tuple[float, float]
    origin: tuple[float, float]
    px_per_mm: float
    frame: np.ndarray
    frame_index: int


def raw_kymographs(source: Any, tr: Track, *, row: int | None = None, col: int | None = None,
                   band: int = 3) -> RawKymographs:
    """Kymographs of the movie ``source`` (as given to :func:`track`, same ROI) for its track
    ``tr``. Default lines: the row of the mean centroid, and the column of the centroid at
    the middle of the record (as :func:`flutterswim.analysis.kymograph.line_kymograph`)."""
    info = tr.meta.get("frames")
    if info is None:
        raise ParameterError("track has no per-frame record (meta['frames']); track the movie with "
                             "flutterswim.tracking.track first")
    ppm = float(tr.meta["px_per_mm"])
    frames = open_frames(source, tr.meta.get("roi"))
    H, W = frames.shape
    T = len(frames)
    if T != len(info["ok"]):
        raise ParameterError(f"the movie has {T} frames but the track {len(info['ok'])}; give the same input")
    xc, yc = tr.centroid()
    if row is None:
        row = int(round(float(np.mean(yc)) * ppm))
    if col is None:
        col = int(round(float(np.interp(0.5 * (tr.t[0] + tr.t[-1]), tr.t, xc)) * ppm))
    if not (0 <= row < H and 0 <= col < W):
        raise ParameterError(f"row={row}, col={col} lie outside the frame ({H} x {W} pixels)")
    hb = max(int(band), 1)
    r0, r1 = max(row - hb // 2, 0), min(row + hb - hb // 2, H)
    c0, c1 = max(col - hb // 2, 0), min(col + hb - hb // 2, W)
    Xp, Yp = info["x_px"], info["y_px"]
    P = Xp.shape[1]
    hor = np.empty((T, W), np.float32)
    ver = np.empty((T, H), np.float32)
    body = np.full((T, P), np.nan)
    mid = T // 2
    frame = None
    for i, img in enumerate(frames):
        hor[i] = img[r0:r1].mean(axis=0)
        ver[i] = img[:, c0:c1].mean(axis=1)
        if info["ok"][i]:
            body[i] = ndi.map_coordinates(img, [Yp[i], Xp[i]], order=1, mode="nearest")
        if i == mid:
            frame = np.array(img)
    t = np.asarray(info["t"], float)
    A = np.stack([np.ones_like(tr.t), tr.t - t[0]], -1)
    (x0, vx), *_ = np.linalg.lstsq(A, xc, rcond=None)
    (y0, vy), *_ = np.linalg.lstsq(A, yc, rcond=None)
    return RawKymographs(t=t, horizontal=hor, vertical=ver, row=row, col=col, body=body, s=np.asarray(tr.s),
                         velocity=(float(vx), float(vy)), origin=(float(x0), float(y0)), px_per_mm=ppm,
                         frame=frame, frame_index=mid)


def plot_raw_kymographs(k: RawKymographs, path: str | Path | None = None, *, tr: Track | None = None):
    """Fig. 3c layout: the middle frame with the two lines (red) and the tracked centreline;
    below it the horizontal-line kymograph (x across, time down), to its right the
    vertical-line kymograph (time across, y up the frame), each with the average-velocity
    line (yellow); and the intensity along the tracked body (s across, time down)."""
    from ..plotting._common import new_figure

    ppm = k.px_per_mm
    H, W = k.frame.shape
    t0, t1 = float(k.t[0]), float(k.t[-1])
    ext_x, ext_y = (-0.5 / ppm, (W - 0.5) / ppm), (-0.5 / ppm, (H - 0.5) / ppm)
    fig = new_figure((11, 7.5), shown=path is None)
    gs = fig.add_gridspec(2, 3, width_ratios=[W / max(H, 1) * 1.0, 1.0, 1.0], height_ratios=[1.0, 1.6])
    ax0 = fig.add_subplot(gs[0, 0])
    ax0.imshow(k.frame, cmap="gray", extent=(*ext_x, ext_y[1], ext_y[0]))
    ax0.axhline(k.row / ppm, color="r", lw=0.8)
    ax0.axvline(k.col / ppm, color="r", lw=0.8)
    if tr is not None:
        info = tr.meta["frames"]
        j = k.frame_index
        if info["ok"][j]:
            ax0.plot(info["x_px"][j] / ppm, info["y_px"][j] / ppm, "c-", lw=0.8, label="tracked")
            ax0.plot(info["x_px"][j][0] / ppm, info["y_px"][j][0] / ppm, "co", ms=3, label="s = 0")
            ax0.legend(fontsize=7, loc="upper right")
    ax0.set(xlabel="x [mm]", ylabel="y [mm]", title=f"frame {k.frame_index} (t = {k.t[k.frame_index]:.2f} s)")
    vx, vy = k.velocity
    x0, y0 = k.origin
    tt = np.array([t0, t1])
    # horizontal line: x across, time downwards
    ax1 = fig.add_subplot(gs[1, 0], sharex=ax0)
    ax1.imshow(k.horizontal, cmap="gray", aspect="auto", extent=(*ext_x, t1, t0))
    ax1.plot(x0 + vx * (tt - t0), tt, "y-", lw=1.2, label=f"average velocity, x: {vx:.3g} mm/s (speed {math.hypot(vx, vy):.3g})")
    ax1.set(xlabel="x [mm]", ylabel="t [s]", title=f"along the horizontal line (row {k.row})")
    ax1.set_ylim(t1, t0)
    ax1.legend(fontsize=7, loc="lower right")
    # vertical line: time across, y as in the frame
    ax2 = fig.add_subplot(gs[0, 1:], sharey=ax0)
    ax2.imshow(k.vertical.T, cmap="gray", aspect="auto", extent=(t0, t1, ext_y[1], ext_y[0]))
    ax2.plot(tt, y0 + vy * (tt - t0), "y-", lw=1.2, label=f"average velocity, y: {vy:.3g} mm/s (speed {math.hypot(vx, vy):.3g})")
    ax2.set(xlabel="t [s]", title=f"along the vertical line (column {k.col})")
    ax2.legend(fontsize=7, loc="lower right")
    ax3 = fig.add_subplot(gs[1, 1])
    im3 = ax3.imshow(np.ma.masked_invalid(k.body), cmap="magma", aspect="auto",
                     extent=(float(k.s[0]), float(k.s[-1]), t1, t0))
    ax3.set(xlabel="s [mm]", ylabel="t [s]", title="intensity along the body")
    fig.colorbar(im3, ax=ax3, label="intensity [grey levels]", shrink=0.9)
    if tr is not None:
        from ..analysis.kymograph import body_kymograph

        bk = body_kymograph(tr)
        ax4 = fig.add_subplot(gs[1, 2], sharey=ax3)
        lim = float(np.nanpercentile(np.abs(bk.kappa), 99)) or 1.0
        pm = ax4.pcolormesh(bk.s, bk.t, bk.kappa, cmap="RdBu_r", vmin=-lim, vmax=lim, shading="nearest")
        ax4.set(xlabel="s [mm]", title="curvature along the body")
        fig.colorbar(pm, ax=ax4, label="curvature [1/mm]", shrink=0.9)
        ax4.set_ylim(t1, t0)
    if path is not None:
        from .._paths import save_figure_file

        save_figure_file(fig, path, dpi=120)
    return fig
