"""Animation export (MP4 through imageio-ffmpeg's bundled ffmpeg, GIF through imageio).

One figure is drawn once; each frame only updates line data, the time stamp and the field
arrow, restores the static background (blitting) and grabs the Agg buffer.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from .._validate import ParameterError
from ..analysis.cycles import tip_index
from ..analysis.track import as_track
from ._common import SWIM_COLOR, TIP_COLOR, field_arrow, figure_units, new_figure, set_field_arrow

__all__ = ["animate", "frame_times", "MAX_FPS", "MAX_VIDEO_FRAMES"]

#: Highest frame rate of a video (a GIF's frame delays are whole hundredths of a second:
#: at most 100 frames per second).
MAX_FPS = {".mp4": 240.0, ".gif": 100.0}
#: Most video frames (duration / speed x fps), checked before anything is allocated.
MAX_VIDEO_FRAMES = 1_000_000


def frame_times(t: np.ndarray, fps: float, speed: float, max_frames: int | None) -> np.ndarray:
    """Indices of the saved frames to show: one per 1/fps of video at ``speed`` x real time."""
    dur = (t[-1] - t[0]) / speed
    n = max(2, int(math.floor(dur * fps)) + 1)
    if max_frames is not None:
        n = min(n, int(max_frames))
    tq = t[0] + np.arange(n) * speed / fps
    tq = tq[tq <= t[-1] + 1e-12]
    idx = np.clip(np.searchsorted(t, tq), 0, t.size - 1)
    prev = np.clip(idx - 1, 0, t.size - 1)
    closer = np.abs(t[prev] - tq) < np.abs(t[idx] - tq)
    return np.where(closer, prev, idx)


def animate(
    obj: Any,
    path: str | Path,
    *,
    fps: float = 25.0,
    speed: float = 1.0,
    max_frames: int | None = None,
    size: tuple[int, int] = (640, 360),
    dpi: float = 100.0,
    trail: bool = True,
    quality: int = 7,
    tip: int | str = "end",
    progress: bool = False,
) -> Path:
    """Write an animation of the swimmer to ``path`` (.mp4 or .gif) and return the path.

    One video frame per 1/fps s of video; ``speed`` is simulated seconds per video second
    (frames are the nearest saved times). ``size``: (width, height) pixels, made even for
    MP4. Shows the filament, the trajectory so far of the tip (``tip``: "end" = s=l or
    "start" = s=0; magenta), the centroid path
    (yellow), the field arrow (red, follows a rotating field) and a time stamp; the view
    holds the whole trajectory. ``progress``: a bar over the video frames. The file is
    written under a temporary name in the same folder and renamed when complete.
    """
    tr = as_track(obj)
    p = Path(path)
    fmt = p.suffix.lower()
    if fmt not in (".mp4", ".gif"):
        raise ParameterError(f"path={str(path)!r} has an unsupported suffix; use .mp4 or .gif")
    if not (fps > 0 and math.isfinite(fps)):
        raise ParameterError(f"fps={fps!r} must be a finite number > 0")
    if fps > MAX_FPS[fmt]:  # fps=1e9 ran out of memory building the frame list
        raise ParameterError(f"fps={fps!r} is too high for {fmt[1:].upper()}; a frame rate in (0, {MAX_FPS[fmt]:g}] "
                             "frames per second is required")
    if fmt == ".gif":
        # a GIF stores each frame's delay in whole hundredths of a second: fps 15 played at 16.7,
        # 60 at 100 (and browsers slow delays under 2/100 s to 10/100)
        k = round(100.0 / fps)
        if k < 2 or abs(100.0 / fps - k) > 0.005 * (100.0 / fps):
            near = sorted({100.0 / j for j in (max(2, k - 1), max(2, k), max(2, k + 1))}, reverse=True)
            raise ParameterError(f"fps={fps!r} cannot be stored in a GIF, whose frame delays are whole hundredths of a "
                                 f"second (at least 2): use 100/k frames per second ({', '.join(f'{v:.4g}' for v in near)}), "
                                 "or an MP4")
    if not (speed > 0 and math.isfinite(speed)):
        raise ParameterError(f"speed={speed!r} must be a finite number > 0")
    n_video = (tr.t[-1] - tr.t[0]) / speed * fps
    if n_video > MAX_VIDEO_FRAMES and (max_frames is None or max_frames > MAX_VIDEO_FRAMES):
        raise ParameterError(f"speed={speed!r} and fps={fps!r} make a video of {n_video:.3g} frames "
                             f"({tr.t[-1] - tr.t[0]:.6g} simulated s); at most {MAX_VIDEO_FRAMES} are written: "
                             "raise speed, lower fps, or give max_frames")
    w, h = (int(size[0]), int(size[1]))
    if w < 64 or h < 64:
        raise ParameterError(f"size={size!r} must be at least (64, 64) pixels")
    if fmt == ".mp4":
        w, h = w + (w % 2), h + (h % 2)
    from .._paths import atomic_path, check_output_file, mark_gif

    check_output_file(p, (".mp4", ".gif"), what="path")

    f, L, T = figure_units(tr)
    it = tip_index(tr, tip)
    X, Y = tr.x * f, tr.y * f
    xc, yc = tr.centroid()
    xc, yc = xc * f, yc * f
    idx = frame_times(tr.t, fps, speed, max_frames)

    fig = new_figure((w / dpi, h / dpi), dpi)
    fig.set_layout_engine(None)
    ax = fig.add_axes([0.1, 0.14, 0.86, 0.78])
    xmin, xmax, ymin, ymax = X.min(), X.max(), Y.min(), Y.max()
    pad = 0.05 * max(xmax - xmin, ymax - ymin, 1e-12)
    xmin, xmax, ymin, ymax = xmin - pad, xmax + pad, ymin - pad, ymax + pad
    # equal aspect: widen the smaller range to the axes box ratio so everything stays in view
    box = 0.78 * h / (0.86 * w)
    dx, dy = xmax - xmin, ymax - ymin
    if dy < dx * box:
        c = 0.5 * (ymin + ymax)
        ymin, ymax = c - 0.5 * dx * box, c + 0.5 * dx * box
    else:
        c = 0.5 * (xmin + xmax)
        xmin, xmax = c - 0.5 * dy / box, c + 0.5 * dy / box
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"x ({L})")
    ax.set_ylabel(f"y ({L})")
    tip_line, = ax.plot([], [], color=TIP_COLOR, lw=0.8, animated=True)
    cen_line, = ax.plot([], [], color=SWIM_COLOR, lw=1.0, animated=True)
    body, = ax.plot([], [], color="#1a7f37", lw=2.5, solid_capstyle="round", animated=True)
    stamp = ax.text(0.98, 0.92, "", transform=ax.transAxes, ha="right", fontsize=9, animated=True)
    arrow = field_arrow(ax, float(tr.field_angle[0]))
    arrow.set_animated(True)
    if trail:  # legend from proxy handles (the animated lines are drawn by hand)
        from matplotlib.lines import Line2D

        ax.legend(handles=[Line2D([], [], color=TIP_COLOR, lw=0.8,
                                  label=f"tip ({'s = l' if it == tr.n_points - 1 else 's = 0'}) trajectory"),
                           Line2D([], [], color=SWIM_COLOR, lw=1.0, label="centroid trajectory")],
                  fontsize=7, loc="lower right", frameon=False)
    canvas = fig.canvas
    canvas.draw()
    bg = canvas.copy_from_bbox(fig.bbox)

    def render(i: int) -> np.ndarray:
        canvas.restore_region(bg)
        if trail:
            tip_line.set_data(X[: i + 1, it], Y[: i + 1, it])
            cen_line.set_data(xc[: i + 1], yc[: i + 1])
            ax.draw_artist(tip_line)
            ax.draw_artist(cen_line)
        body.set_data(X[i], Y[i])
        stamp.set_text(f"t = {tr.t[i]:6.2f} {T}")
        set_field_arrow(arrow, float(tr.field_angle[i]))
        ax.draw_artist(body)
        ax.draw_artist(stamp)
        ax.draw_artist(arrow)
        buf = np.asarray(canvas.buffer_rgba())
        return np.ascontiguousarray(buf[:h, :w, :3])

    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=int(idx.size), desc="animate", unit="frame", leave=False)

    def frames():
        for i in idx:
            yield render(int(i))
            if bar is not None:
                bar.update(1)

    try:
        with atomic_path(p) as tmp:
            if fmt == ".mp4":
                import imageio_ffmpeg

                it_frames = frames()
                first = next(it_frames)
                hh, ww = first.shape[:2]
                wr = imageio_ffmpeg.write_frames(str(tmp), (ww, hh), fps=fps, quality=quality, macro_block_size=1,
                                                 codec="libx264", pix_fmt_out="yuv420p", ffmpeg_log_level="error",
                                                 output_params=["-metadata", "comment=flutterswim animation"])
                wr.send(None)
                try:
                    wr.send(first)
                    for fr in it_frames:
                        wr.send(fr)
                finally:
                    wr.close()
            else:
                import imageio.v2 as iio

                with iio.get_writer(str(tmp), mode="I", format="GIF", duration=1000.0 / fps, loop=0) as wr:
                    for fr in frames():
                        wr.append_data(fr)
                mark_gif(tmp)
    finally:
        if bar is not None:
            bar.close()
    return p
