"""Checks and smoothing of a tracked body across frames.

The tips of a flapping filament filmed at ~19 frames per stroke are the worst place for a
smoother in time: the trailing end whips, and a local polynomial in time over 5-9 frames of
its path (or of its position relative to the body next to it) is off by 0.3-2 px on the
paper's stroke (measured on noise-free rendered movies; see benchmarks/RESULTS.md). So the
tips are not smoothed in time. Two things are done instead, both with a small bias:

- :func:`tip_outliers`: each end is checked against its neighbouring frames. Its offset
  across the body (from the line through the body 15-45 px from that end) is predicted by a
  local quadratic in time through the 2 + 2 neighbouring good frames (the frame itself left
  out); an end whose residual exceeds ``k`` robust standard deviations of all residuals and
  ``floor_px`` is an outlier, and its frame is flagged with the reason.
- :func:`smooth_offsets`: the position of the ends along the curve (where s = 0 lies on the
  frame's curve) is the one per-frame error that the body's middle can correct: the middle
  moves slowly and smoothly, so the local polynomial in time of each middle sample
  (``degree`` 4 over ``window`` frames) predicts where the frame's samples should lie, and
  the whole frame (both ends) slides along its own curve by the mean tangential difference.
  This is a Savitzky-Golay smoothing of the end offset in time without smoothing the ends'
  paths (bias <= 0.01 px on the noise-free stroke).

Both need the motion sampled finely enough: :func:`frames_per_stroke` measures the stroke's
period in frames from the body's shape, and :func:`smoothing_allowed` lets the smoothing run
only when its Savitzky-Golay gain at the stroke frequency and its second harmonic is within
1e-4 and 5e-3 of 1 (window 7, quartic: >= 16 frames per stroke; the paper's stroke at 50 fps
has 19). The tip check needs >= 12 frames per stroke.
"""

from __future__ import annotations

import math

import numpy as np

from .tips import resample

__all__ = ["tip_outliers", "smooth_offsets", "end_offsets_across", "frames_per_stroke", "smoothing_gain_error",
           "smoothing_allowed"]


def _across(x: np.ndarray, y: np.ndarray, anchor: float, span: float) -> float:
    """Offset [px] of the s = 0 end of (x, y) across the line fitted to the curve between
    arc distances ``anchor`` and ``anchor + span`` from that end (left of the direction
    towards the end is positive)."""
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    q = np.linspace(anchor, anchor + span, 16)
    px, py = np.interp(q, s, x), np.interp(q, s, y)
    tx, ty = -np.polyfit(q, px, 1)[0], -np.polyfit(q, py, 1)[0]
    n = math.hypot(tx, ty)
    if not n > 0:
        return math.nan
    dx, dy = x[0] - px[0], y[0] - py[0]
    return (dy * tx - dx * ty) / n


def end_offsets_across(X: np.ndarray, Y: np.ndarray, ok: np.ndarray, anchor: float = 15.0,
                       span: float = 30.0) -> np.ndarray:
    """(T, 2) offsets [px] of the s = 0 and s = l ends across the body next to them
    (:func:`_across`); NaN on frames not ``ok``."""
    T = X.shape[0]
    out = np.full((T, 2), np.nan)
    for i in np.nonzero(ok)[0]:
        out[i, 0] = _across(X[i], Y[i], anchor, span)
        out[i, 1] = _across(X[i, ::-1], Y[i, ::-1], anchor, span)
    return out


def _leave_one_out(v: np.ndarray, ok: np.ndarray, half: int, degree: int,
                   positions: np.ndarray | None = None) -> np.ndarray:
    """Residual of each good v[i] from the polynomial of ``degree`` in time fitted to the good
    frames within ``half`` frame intervals of i, i left out (NaN with too few of them); time in
    frame intervals: ``positions`` (a camera's timestamps: a dropped frame leaves a step of 2),
    default the frame index."""
    idx = np.nonzero(ok)[0]
    pos = np.arange(v.shape[0], dtype=float) if positions is None else np.asarray(positions, float)
    r = np.full(v.shape, np.nan)
    for i in idx:
        d = pos[idx] - pos[i]
        nb = idx[(np.abs(d) <= half + 1e-9) & (idx != i)]
        if nb.size < degree + 2:
            continue
        c = np.polyfit(pos[nb] - pos[i], v[nb], degree)
        r[i] = v[i] - c[-1]
    return r


def tip_outliers(X: np.ndarray, Y: np.ndarray, ok: np.ndarray, *, k: float = 6.0, floor_px: float = 2.0,
                 half: int = 2, degree: int = 2, positions: np.ndarray | None = None
                 ) -> list[tuple[int, int, float, float]]:
    """Ends that leave the path of their neighbouring frames: a list of (frame, end (0: s = 0,
    1: s = l), residual [px], residual in robust standard deviations), in the order found
    (the largest first, then again without it); see the module docstring. X, Y (T, P) [px]; ok (T,) the good frames;
    positions: (T,) the frames' times in frame intervals (default their indices)."""
    ok = np.array(ok, bool)
    if np.count_nonzero(ok) < 2 * half + 3:
        return []
    off = end_offsets_across(X, Y, ok)
    out: list[tuple[int, int, float, float]] = []
    # one at a time, largest first: an outlier also moves its neighbours' predictions, so the
    # residuals are computed again without it (each end's series keeps its own good frames)
    use = [ok.copy(), ok.copy()]
    while True:
        worst = None
        for e in (0, 1):
            if np.count_nonzero(use[e]) < 2 * half + 3:
                continue
            r = _leave_one_out(off[:, e], use[e], half, degree, positions)
            good = np.isfinite(r)
            if np.count_nonzero(good) < 5:
                continue
            sd = 1.4826 * float(np.median(np.abs(r[good] - np.median(r[good]))))
            if not sd > 0:
                continue
            z = np.where(good, np.abs(r), 0.0) / sd
            i = int(np.argmax(z))
            if abs(r[i]) > max(k * sd, floor_px) and (worst is None or z[i] > worst[3]):
                worst = (i, e, float(r[i]), float(z[i]))
        if worst is None:
            break
        out.append(worst)
        use[worst[1]][worst[0]] = False
    return out


def smooth_offsets(X: np.ndarray, Y: np.ndarray, ok: np.ndarray, *, window: int = 7, degree: int = 4,
                   middle: tuple[float, float] = (0.2, 0.8), positions: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Slide each good frame's samples along its own curve so that the middle of the body
    (the fraction ``middle`` of the samples) sits where the local polynomial in time predicts
    it (see the module docstring). X, Y (T, P) [px] with equal arc-length samples; returns
    (X, Y, shift (T,) [px], + towards s = l; 0 where not done). Frames with fewer than
    ``window`` good frames within reach keep their samples (the window is shifted at the
    ends of the movie, as in Savitzky-Golay's 'interp' mode). ``positions``: the frames' times
    in frame intervals (a camera that dropped frames), for the polynomial in time; None: the
    frame indices (a frame next to a gap of two dropped frames was moved by 2-3 px)."""
    ok = np.asarray(ok, bool)
    T, P = X.shape
    pos = np.arange(T, dtype=float) if positions is None else np.asarray(positions, float)
    Xo, Yo = X.copy(), Y.copy()
    shift = np.zeros(T)
    idx = np.nonzero(ok)[0]
    h = window // 2
    if idx.size < window or window < degree + 2:
        return Xo, Yo, shift
    m = slice(int(middle[0] * (P - 1)), int(math.ceil(middle[1] * (P - 1))) + 1)
    for i in idx:
        lo, hi = i - h, i + h
        if lo < idx[0]:
            lo, hi = idx[0], idx[0] + 2 * h
        if hi > idx[-1]:
            lo, hi = idx[-1] - 2 * h, idx[-1]
        nb = idx[(idx >= lo) & (idx <= hi)]
        if nb.size < window:
            continue
        V = np.vander((pos[nb] - pos[i]) / max(h, 1), degree + 1, increasing=True)
        n = X[i, m].size
        c, *_ = np.linalg.lstsq(V, np.concatenate([X[nb][:, m], Y[nb][:, m]], axis=1), rcond=None)
        tx, ty = np.gradient(X[i]), np.gradient(Y[i])
        nn = np.hypot(tx, ty)
        nn[nn == 0] = 1.0
        tx, ty = tx / nn, ty / nn
        hshift = float(np.mean(tx[m] * (c[0, :n] - X[i, m]) + ty[m] * (c[0, n:] - Y[i, m])))
        L = float(np.sum(np.hypot(np.diff(X[i]), np.diff(Y[i]))))
        Xo[i], Yo[i] = resample(X[i], Y[i], hshift, L + hshift, P)
        shift[i] = hshift
    return Xo, Yo, shift


def frames_per_stroke(X: np.ndarray, Y: np.ndarray, ok: np.ndarray, positions: np.ndarray | None = None) -> float:
    """The stroke's period [frames], from the body's shape: the offsets of the samples at a
    quarter, half and three quarters of the body from the line through its ends (rigid motion
    removed), each over the good frames (gaps filled linearly) less its mean; the period of
    the highest of their dominant frequencies (the shortest period, so that a shape that
    oscillates at twice the stroke frequency errs on the safe side). NaN with fewer than 8
    good frames or no oscillation. ``positions``: the frames' times in frame intervals (a
    camera that dropped frames; three dropped of 110 put the period 4.7 % short, outside the
    periodic template's search); None: the frame indices."""
    ok = np.asarray(ok, bool)
    idx = np.nonzero(ok)[0]
    if idx.size < 8:
        return math.nan
    pos = np.arange(ok.size, dtype=float) if positions is None else np.asarray(positions, float)
    P = X.shape[1]
    cx, cy = X[idx, -1] - X[idx, 0], Y[idx, -1] - Y[idx, 0]
    n = np.hypot(cx, cy)
    n[n == 0] = 1.0
    grid = np.arange(pos[idx[0]], pos[idx[-1]] + 0.5)  # one sample per frame interval
    T = grid.size
    best = 0.0
    for j in (P // 4, P // 2, (3 * P) // 4):
        u = ((X[idx, j] - X[idx, 0]) * -cy + (Y[idx, j] - Y[idx, 0]) * cx) / n
        v = np.interp(grid, pos[idx], u)
        v = v - v.mean()
        F = np.abs(np.fft.rfft(v * np.hanning(T), n=8 * T))
        f = np.fft.rfftfreq(8 * T)
        F[f < 1.5 / T] = 0.0  # below 1.5 cycles in the movie: drift, not a stroke
        if F.max() > 0:
            best = max(best, float(f[int(np.argmax(F))]))
    return 1.0 / best if best > 0 else math.nan


def smoothing_gain_error(window: int, degree: int, f: float) -> float:
    """|1 - gain| of the centred Savitzky-Golay filter (window, degree) at frequency f [1/frame]."""
    from scipy.signal import savgol_coeffs

    c = savgol_coeffs(window, degree)
    k = np.arange(window) - (window - 1) // 2
    return abs(1.0 - float(np.sum(c * np.cos(2 * np.pi * f * k))))


def smoothing_allowed(window: int, degree: int, period_frames: float) -> bool:
    """Whether :func:`smooth_offsets` may run on a stroke of ``period_frames``: its gain at
    the stroke frequency within 1e-4 of 1 and at twice it within 5e-3."""
    if not (math.isfinite(period_frames) and period_frames > 0):
        return False
    f = 1.0 / period_frames
    return smoothing_gain_error(window, degree, f) <= 1e-4 and smoothing_gain_error(window, degree, 2 * f) <= 5e-3
