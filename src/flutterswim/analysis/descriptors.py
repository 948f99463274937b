"""Swimming descriptors averaged over the last cycles, each with its cycle-to-cycle spread."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from .._validate import ParameterError
from .cycles import (
    leading_axes,
    _MAX_RESOLVABLE,
    GAP_MARGIN,
    Cycles,
    _fourier_columns,
    body_axis_angle,
    detect_cycles,
    fourier_fit,
    fourier_harmonics,
    sample_cycle,
    tip_index,
)
from .intersection import self_intersections
from .track import Track, as_track

__all__ = ["Descriptors", "describe", "shape_modes", "stroke_area", "per_cycle"]


def _std(v: np.ndarray) -> float:
    """Sample standard deviation over the cycles; NaN (unknown) from one cycle, which has no
    spread to measure (0 read as perfect precision on a one-cycle movie)."""
    v = np.asarray(v, float)
    return float(np.std(v, ddof=1)) if v.size > 1 else math.nan


_GRID = 256
_GRID_BASIS: dict[int, np.ndarray] = {}


def _waveform_p2p(coef: np.ndarray, H: int) -> float:
    """Peak-to-peak of the Fourier series with harmonic coefficients ``coef``: each extreme on
    a 256-point grid refined by the parabola through it and its neighbours (error
    ~ (2 pi H / 256)^4 / 24 of the top harmonic's amplitude)."""
    if H not in _GRID_BASIS:
        g = np.outer(np.arange(_GRID) / _GRID, 2 * np.pi * np.arange(1, H + 1))
        _GRID_BASIS[H] = np.hstack([np.cos(g), np.sin(g)])
    f = _GRID_BASIS[H] @ coef
    ext = []
    for i in (int(np.argmax(f)), int(np.argmin(f))):
        f0, f1, f2 = f[i - 1], f[i], f[(i + 1) % _GRID]
        den = f0 - 2.0 * f1 + f2
        ext.append(f1 - (f0 - f2) ** 2 / (8.0 * den) if den != 0.0 else f1)
    return float(ext[0] - ext[1])


def _fourier_p2p(phase: np.ndarray, q: np.ndarray, harmonics: int, keep: np.ndarray | None = None) -> float:
    """Peak-to-peak of a least-squares Fourier series in phase (period 1) fitted to q; ``keep``
    (bool, harmonic h at index h - 1): only those harmonics (and the constant) are fitted."""
    if keep is None:
        return _waveform_p2p(*fourier_fit(phase, q, harmonics))
    H = fourier_harmonics(phase.size, harmonics)
    k = np.ones(H, bool)  # harmonics beyond those tested are kept
    k[: min(H, keep.size)] = keep[:H]
    use = np.concatenate([[True], k, k])
    A = _fourier_columns(phase, H)[:, use]
    coef = np.zeros(2 * H + 1)
    coef[use] = np.linalg.lstsq(A, q, rcond=None)[0]
    return _waveform_p2p(coef[1:], H)


#: fewer frames per stroke (on average) measure no lateral excursion: a cycle's Fourier fit
#: needs 4 frames
_MIN_FRAMES_PER_STROKE = 4


def start_ahead(tr: Track, direction: float) -> float:
    """How far the end s = 0 lies ahead of the end s = l along ``direction`` [rad], on average
    over the frames: > 0 when s = 0 leads a swimmer going that way."""
    e = (math.cos(direction), math.sin(direction))
    return float(np.mean((tr.x[:, 0] - tr.x[:, -1]) * e[0] + (tr.y[:, 0] - tr.y[:, -1]) * e[1]))


def _lateral_series(tr: Track, st: np.ndarray, i_end: int, ang: np.ndarray) -> list:
    """Per cycle: (phase, lateral coordinate of point ``i_end`` across direction ang[k]), or
    None for a cycle with fewer than 4 frames.

    When the directions differ between cycles (a turning swimmer) the measuring frame turns
    with the swimmer: across a direction turning at the cycles' rate (from the directions of
    the neighbouring cycles) and relative to the cycle's mean centroid path (its mean velocity
    through its mean position), so the body's own turn within a cycle is not read as lateral motion."""
    K = st.size - 1
    lo = np.searchsorted(tr.t, st[:-1], side="left")
    hi = np.searchsorted(tr.t, st[1:], side="left")  # frames with st[k] <= t < st[k+1]
    turning = K >= 2 and float(np.ptp(ang)) > 0.0
    if turning:
        tm = 0.5 * (st[:-1] + st[1:])
        omega = np.gradient(np.unwrap(ang), tm)
        xc, yc = tr.centroid()
        vx, vy = np.diff(np.interp(st, tr.t, xc)) / np.diff(st), np.diff(np.interp(st, tr.t, yc)) / np.diff(st)
    out = []
    for k in range(K):
        if hi[k] - lo[k] < 4:
            out.append(None)
            continue
        sl = slice(lo[k], hi[k])
        if turning:
            dt = tr.t[sl] - tm[k]
            a = ang[k] + omega[k] * dt
            # the cycle's mean centroid path: its mean velocity (net displacement / period), through
            # the cycle's mean position (a fitted line would absorb part of the stroke's own wobble)
            px, py = xc[sl] - vx[k] * dt, yc[sl] - vy[k] * dt
            q = (-(tr.x[sl, i_end] - px.mean() - vx[k] * dt) * np.sin(a)
                 + (tr.y[sl, i_end] - py.mean() - vy[k] * dt) * np.cos(a))
        else:
            q = -tr.x[sl, i_end] * math.sin(ang[k]) + tr.y[sl, i_end] * math.cos(ang[k])
        out.append(((tr.t[sl] - st[k]) / (st[k + 1] - st[k]), q))
    return out


# harmonics the lateral waveforms of the stroke need (the paper's: 3 at the leading end, 5 at
# the trailing end for 0.01 %, 4 for 0.4 %); a cycle sampled too coarsely for them borrows the
# missing ones from all the cycles together (with 4, the paper's 50 fps left its trailing end
# 0.36 % short: 19 frames per stroke hold 4 of their own)
# a track whose centroid moves less than this per cycle does not swim: 1e-6 body lengths (a
# simulation's round-off and solver tolerance; the paper's swimmer advances 0.1), or for a tracked
# movie 0.05 px (its centroid's noise over the body's hundreds of pixels is about 0.01 px)
_STILL_BL = 1e-6
_FADED = 1e-3  # described cycles this small beside the record's largest: the stroke stopped
_STILL_PX = 0.05
# and one whose cycles' displacements turn from one cycle to the next by angles so unalike that
# the mean of the turns as unit vectors is below this (steady swimming or turning: 1)
_ALIGNED_TURNS = 0.5
# a swimmer more than about 5.7 degrees off the field's line (the advance along it 0.5 %
# short of the advance along the path) is noted: the field's direction given is likely wrong
# (the paper's swims within 0.001 degree of it), or the field turns
_ALONG_FIELD_COS = 0.995

_POOLED_HARMONICS = 5
_POOLED_MIN_F = 10.0
# against a tracked movie's template noise: at SNR 3 the trailing end's 5th harmonic (0.4 % of
# its excursion) gave F 2.4-15 and came and went at 10; noise alone (the leading end's) gave at
# most 4.5 over 16 movies (chance of 5 or more for noise alone: exp(-5) = 0.7 %)
_POOLED_MIN_F_TEMPLATE = 5.0
# the pooled phases must resolve the harmonics: the smallest eigenvalue of the harmonic block's
# normalised Gram matrix (1 for phases spread evenly over the cycle, 0 when a whole number of
# frames per stroke puts every cycle's frames at the same few phases) at least this
_POOLED_MIN_COVERAGE = 0.25
# and the missing harmonics may change a cycle's peak-to-peak by at most this factor (the
# paper's trailing end needs 1.06; more is a fit gone wrong, not a waveform)
_POOLED_MAX_FACTOR = 1.25


def _pooled_p2p(series: list, H: int) -> tuple[float, float, int]:
    """Peak-to-peak of one Fourier series of H harmonics fitted to all cycles' (phase, q) at
    once, with an offset per cycle, its residual sum of squares and degrees of freedom; NaN if
    the pooled samples are too few or their phases do not resolve H harmonics."""
    cyc = [c for c in series if c is not None]
    n = sum(c[0].size for c in cyc)
    if not cyc or n - len(cyc) - 1 < 4 * H:
        return math.nan, math.nan, 0
    who, harm, q = _pooled_design(cyc, np.arange(1, H + 1))
    # coverage: the harmonic columns with each cycle's mean removed (what the offsets leave)
    means = np.stack([np.bincount(who, col) for col in harm.T], 1) / np.bincount(who)[:, None]
    centred = harm - means[who]
    if np.linalg.eigvalsh(centred.T @ centred / (0.5 * n))[0] < _POOLED_MIN_COVERAGE:
        return math.nan, math.nan, 0
    coef, rss, A = _pooled_lstsq(who, harm, q, len(cyc))
    return _waveform_p2p(coef[len(cyc):], H), rss, n - A.shape[1]


def _pooled_design(cyc: list, harmonics: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All cycles' (phase, q) together: each sample's cycle, the cos then sin columns of the
    given harmonics, and q."""
    ph = np.concatenate([c[0] for c in cyc])
    who = np.repeat(np.arange(len(cyc)), [c[0].size for c in cyc])
    arg = np.outer(ph, 2 * np.pi * np.asarray(harmonics, float))
    return who, np.hstack([np.cos(arg), np.sin(arg)]), np.concatenate([c[1] for c in cyc])


def _pooled_lstsq(who: np.ndarray, harm: np.ndarray, q: np.ndarray, n_cycles: int):
    """Least squares of q on an offset per cycle and the harmonic columns: (coefficients,
    residual sum of squares, design matrix)."""
    A = np.hstack([(who[:, None] == np.arange(n_cycles)[None, :]).astype(float), harm])
    coef = np.linalg.lstsq(A, q, rcond=None)[0]
    return coef, float(np.sum((q - A @ coef) ** 2)), A


# a tracked movie's lateral waveform keeps a harmonic beyond the first only when the pooled cycles
# hold it above the periodic template's coefficient noise (module comment at _template_harmonics)
_TEMPLATE_MIN_F = 2.0


def _pooled_rss(steady: list, harmonics: np.ndarray) -> tuple[float, int]:
    """Residual sum of squares of the Fourier series of the given harmonics fitted to all
    cycles' (phase, q) at once, with an offset per cycle, and the number of samples."""
    cyc = [c for c in steady if c is not None]
    who, harm, q = _pooled_design(cyc, harmonics)
    return _pooled_lstsq(who, harm, q, len(cyc))[1], int(q.size)


def _template_harmonics(steady: list, H: int, se: float) -> np.ndarray | None:
    """Which of harmonics 1..H a tracked movie's lateral waveform keeps (bool (H,)), or None
    (all) when the pooled cycles cannot resolve them.

    Every frame of a templated movie is the one periodic template at its phase, so the
    template's coefficient noise (standard error ``se`` per coefficient) is a waveform that
    every cycle repeats: a harmonic the stroke does not hold still adds 4 se^2 to the
    peak-to-peak's variance, while leaving out a harmonic of amplitude a costs at most
    (2 a)^2, 2 a^2 on average over its phase. So each harmonic beyond the first is kept only
    when its amplitude in all the cycles together, ahat^2 ~ a^2 + 2 se^2, exceeds 4 se^2 (its
    share of the residual, n ahat^2 / 2, over n se^2: F > 2). On the paper's stroke the
    leading end is a pure sine (3rd harmonic 0.034 px of 14.4 px; leaving it out changes
    the peak-to-peak by 0.03 %), and at SNR 3 its 3rd harmonic in the template was noise of
    about 0.045 px per coefficient (0.28 % RMS of the peak-to-peak); the trailing end's 3rd and
    5th (2.6 and 0.16 px) stay."""
    cyc = [c for c in steady if c is not None]
    n = sum(c[0].size for c in cyc)
    if not cyc or H < 2 or n - len(cyc) - 2 * H < 4 * H:
        return None
    full = np.arange(1, H + 1)
    rss, n = _pooled_rss(cyc, full)
    keep = np.ones(H, bool)
    for h in range(2, H + 1):
        rss_h, _ = _pooled_rss(cyc, full[full != h])
        keep[h - 1] = (rss_h - rss) > _TEMPLATE_MIN_F * n * se**2
    return keep


def _template_se(tr: Track, i_end: int, key: str = "template_coef_se") -> float:
    """Standard error of the harmonic coefficients of a tracked movie's periodic template at
    point ``i_end`` (an end; track units), 0 where there is none (a simulation, an untemplated
    movie, an inner point). ``key``: "template_coef_se", the white-noise scale the harmonic
    tests use, or "template_coef_stderr", with the template's degrees of freedom and the
    ends' correlation from frame to frame (for standard errors; the former where absent)."""
    meta = getattr(tr, "meta", None) or {}
    se = meta.get(key)
    if se is None or len(se) != 2 or not all(math.isfinite(float(v)) for v in se):
        se = meta.get("template_coef_se")  # (a track written before template_coef_stderr)
    if se is None or len(se) != 2:
        return 0.0
    n = np.shape(tr.x)[1]
    return float(se[0] if i_end % n == 0 else se[1] if i_end % n == n - 1 else 0.0)


def _steady(series: list, st: np.ndarray) -> list:
    """The cycles' (phase, q) on one steady phase over the cycles (their mean period): the
    crossings of a coarsely sampled stroke carry timing errors that per-cycle phases would fold in."""
    mean_period = (st[-1] - st[0]) / (st.size - 1)
    return [None if c is None else ((st[k] + c[0] * (st[k + 1] - st[k]) - st[0]) / mean_period, c[1])
            for k, c in enumerate(series)]


def _template_p2p_se(tr: Track, i_end: int, harmonics: int, fit: dict) -> float:
    """Standard error of a templated movie's lateral peak-to-peak at point ``i_end`` from the
    periodic template's coefficient noise, which every cycle shares (so the cycles' spread does
    not show it); 0 without a template.

    The peak-to-peak w(phi+) - w(phi-) of the waveform w = sum_h a_h cos 2 pi h phi + b_h sin
    2 pi h phi moves with the coefficients by cos 2 pi h phi+ - cos 2 pi h phi-, and sin alike:
    for coefficients of standard error se each, over the harmonics kept, its standard error
    is se sqrt(sum_h (2 - 2 cos 2 pi h (phi+ - phi-))), 2 se for a sine (each odd harmonic
    kept adds as much again). ``fit``: what :func:`_lateral_p2p` filled in for this end (the
    cycles on one steady phase, the harmonics kept, each cycle's own count, and the count the
    pooled cycles lend a cycle of each own count); the lent harmonics count too.

    It runs a little low: a harmonic at the noise level is kept just when its noise happens to be
    large (F > 2), so kept harmonics carry more than their nominal variance (Monte Carlo of a
    sine with noise in every harmonic: the p2p's scatter 1.04-1.26 times this), and the
    template's error uses the noise's correlation from frame to frame at zero frequency for
    every harmonic (:func:`flutterswim.tracking.periodic._coef_stderr`)."""
    se = _template_se(tr, i_end, "template_coef_stderr")
    if not se > 0:
        return 0.0
    steady = [c for c in fit["steady"] if c is not None]
    need = min(int(harmonics), _POOLED_HARMONICS)
    n = sum(c[0].size for c in steady)
    owns = [h for h, c in zip(fit["own"], fit["steady"]) if c is not None]
    own = max(set(owns), key=owns.count) if owns else 0  # the cycles' usual count
    H = min(need, own) if own else 0
    if H < 1:
        return math.nan
    # the harmonics the cycles' fits keep: of 1..min(harmonics, 5) those the template's test
    # kept, all beyond (a cycle of 25 frames or more fits the 6th), and those beyond a coarsely
    # sampled cycle's own count that the pooled cycles lend it (all, up to top)
    keep = fit["keep"]
    h = np.arange(1, H + 1)[np.ones(H, bool) if keep is None else keep[:H]]
    top = fit["lent"].get(own, H)
    h = np.concatenate([h, np.arange(need + 1, own + 1), np.arange(H + 1, top + 1)])
    if n - len(steady) < 2 * h.size + 1:
        return math.nan
    who, harm, q = _pooled_design(steady, h)
    coef = _pooled_lstsq(who, harm, q, len(steady))[0][len(steady):]
    ph = np.linspace(0.0, 1.0, 2048, endpoint=False)
    arg = np.outer(ph, 2 * np.pi * h)
    w = np.hstack([np.cos(arg), np.sin(arg)]) @ coef
    d = ph[int(np.argmax(w))] - ph[int(np.argmin(w))]
    return se * math.sqrt(float(np.sum(2.0 - 2.0 * np.cos(2 * np.pi * h * d))))


def _lateral_p2p(tr: Track, st: np.ndarray, i_end: int, ang: np.ndarray, harmonics: int,
                 fit: dict | None = None) -> np.ndarray:
    """Per cycle: peak-to-peak of point ``i_end`` across direction ang[k] (Fourier fit of the
    cycle's frames, at most (frames - 1) / 4 harmonics). A cycle of too few frames for
    min(harmonics, 5) harmonics (below 21 frames per stroke) gets the share of the
    peak-to-peak its missing harmonics add, measured on all the cycles together (one steady
    phase, an offset per cycle), when the pooled data hold them: as many harmonics as their
    phases resolve (a whole number n of frames per stroke resolves (n - 1) / 2), a nested F
    test >= 10 (not noise or timing jitter; a stroke still growing fails it and keeps its own
    fits), and a factor within 1/1.25 .. 1.25. At 25 fps the paper's trailing end was 5.8 % short,
    at 50 fps 0.36 % (4 harmonics); now both within 0.1 % of 200 fps. On a tracked movie with a
    periodic template, the cycles' fits keep only the harmonics the pooled cycles hold above the
    template's noise (:func:`_template_harmonics`). ``fit``: a dict to fill in with what
    :func:`_template_p2p_se` needs ("steady", "keep", "own", "lent")."""
    series = _lateral_series(tr, st, i_end, ang)
    steady = _steady(series, st)  # pooled on one steady phase over the cycles
    need = min(int(harmonics), _POOLED_HARMONICS)
    se = _template_se(tr, i_end)
    keep = _template_harmonics(steady, need, se) if se > 0 else None
    out = np.array([_fourier_p2p(*c, harmonics, keep) if c is not None else np.nan for c in series])
    own = [fourier_harmonics(c[0].size, harmonics) if c is not None else need for c in series]
    lent: dict = {}  # {a cycle's own harmonic count: the count the pooled cycles lend it}
    if fit is not None:
        fit.update(steady=steady, keep=keep, own=own, lent=lent)
    resolved = need
    if min(own, default=need) < need:
        # as many harmonics as the pooled phases resolve: a whole number n of frames per
        # stroke puts them on n phases, which resolve (n - 1) / 2 harmonics
        top, full = need, math.nan
        while top > min(own) and not math.isfinite(full):
            full, rss, dof = _pooled_p2p(steady, top)
            top -= 1
        top += 1
        resolved = top if math.isfinite(full) else min(own)
        if math.isfinite(full):
            factor = {}
            n_pooled = sum(c[0].size for c in steady if c is not None)
            for h in sorted(set(h for h in own if h < top)):
                low, rss_h, _ = _pooled_p2p(steady, h)
                # only harmonics the data hold (nested F test), not noise or timing jitter
                F = ((rss_h - rss) / (2 * (top - h))) / (rss / dof) if rss > 0 else math.inf
                # nor the noise of a tracked movie's periodic template, which every cycle shares:
                # an added harmonic's rss drop, n/2 (a^2 + b^2), against its coefficients'
                # variance se^2 (mean 1 for noise alone), for the strongest of them (their mean
                # let a real 3rd harmonic be outvoted by the 4th and 5th's noise: a 2.5 mm swimmer
                # at 10 frames per stroke, the leading end's 3rd 0.9 % of its p2p, read 0.87 % RMS
                # short at SNR 6 instead of 0.62 %; the paper's stroke: unchanged)
                hs = np.arange(1, top + 1)
                F_se = max((_pooled_rss(steady, hs[hs != j])[0] - rss) / (n_pooled * se**2)
                           for j in range(h + 1, top + 1)) if se > 0 else math.inf
                if (F >= _POOLED_MIN_F and F_se >= _POOLED_MIN_F_TEMPLATE and low > 0
                        and 1 / _POOLED_MAX_FACTOR <= full / low <= _POOLED_MAX_FACTOR):
                    factor[h] = full / low
            for k, h in enumerate(own):
                out[k] *= factor.get(h, 1.0)  # in proportion: a growing stroke keeps its shape
            lent.update({h: top for h in factor})
    if fit is not None:
        fit["resolved"] = resolved  # the harmonics the cycles' frames resolve, own or pooled
    return out


def shape_modes(obj: Any, t0: float | None = None, t1: float | None = None, n_modes: int = 2):
    """Principal shape modes of the body-frame shape theta(s, t) - mean_s theta over [t0, t1].

    Returns (coefficients (T_w, n_modes), modes (n_modes, N), mean shape (N,), times (T_w,)).
    """
    tr = as_track(obj)
    if t0 is not None or t1 is not None:
        tr = tr.window(tr.t[0] if t0 is None else t0, tr.t[-1] if t1 is None else t1)
    _, th = tr.tangent_angle()
    sh = th - th.mean(axis=1, keepdims=True)
    mean = sh.mean(axis=0)
    X = sh - mean
    modes = leading_axes(X, n_modes)
    # deterministic orientation: largest component of mode 1 positive, and mode 2 oriented so
    # that sum(m1 dm2/ds) > 0; then a shape wave travelling towards s = l runs the (a1, a2)
    # loop counter-clockwise (positive area), whatever signs the SVD returned
    if modes.shape[0] >= 1 and modes[0, np.argmax(np.abs(modes[0]))] < 0:
        modes[0] *= -1
    if modes.shape[0] >= 2 and float(np.sum(modes[0] * np.gradient(modes[1]))) < 0:
        modes[1] *= -1
    return X @ modes.T, modes, mean, tr.t


def stroke_area(a1: np.ndarray, a2: np.ndarray) -> float:
    """Signed area enclosed by the closed loop (a1, a2), normalised by pi (var a1 + var a2):
    +-1 for a circle run once, 0 for a path that retraces itself (a reciprocal stroke)."""
    a1 = np.asarray(a1, float) - np.mean(a1)
    a2 = np.asarray(a2, float) - np.mean(a2)
    area = 0.5 * float(np.sum(a1 * np.roll(a2, -1) - np.roll(a1, -1) * a2))
    den = math.pi * float(np.mean(a1 * a1) + np.mean(a2 * a2))
    return area / den if den > 0 else 0.0


@dataclass(frozen=True)
class Descriptors:
    """Swimming descriptors over the last ``n_cycles_used`` cycles (``*_std``: cycle-to-cycle
    standard deviation). Lengths in mm and in body lengths (bl); angles in degrees. A record
    without net swimming (see ``note``) has no swimming direction (NaN), no end that leads
    (``leading_end`` "none"; its ends' lateral excursions are still given, named as s = l
    leading) and ``towards_field`` False."""

    n_cycles_used: int
    n_cycles_detected: int
    window_start_s: float
    window_end_s: float
    body_length_mm: float
    period_s: float
    period_std_s: float
    frequency_hz: float
    frequency_std_hz: float
    advance_per_cycle_mm: float
    advance_per_cycle_std_mm: float
    advance_per_cycle_bl: float
    advance_per_cycle_std_bl: float
    advance_total_mm: float
    advance_total_bl: float
    speed_mm_s: float
    speed_std_mm_s: float
    speed_bl_s: float
    speed_std_bl_s: float
    tip_lateral_p2p_mm: float
    tip_lateral_p2p_std_mm: float
    tip_lateral_p2p_bl: float
    swim_direction_deg: float
    swim_direction_std_deg: float
    field_direction_deg: float
    direction_to_field_deg: float
    towards_field: bool
    leading_end: str
    nonreciprocity: float
    nonreciprocity_std: float
    reciprocal: bool
    self_intersecting: bool
    self_intersection_fraction: float
    limit_cycle: bool
    limit_cycle_time_s: float
    onset_time_s: float
    transient_duration_s: float
    growth_rate_per_s: float
    growth_rate_stderr_per_s: float
    leading_lateral_p2p_mm: float = math.nan
    leading_lateral_p2p_bl: float = math.nan
    trailing_lateral_p2p_mm: float = math.nan
    trailing_lateral_p2p_bl: float = math.nan
    # standard errors of the two ends' lateral peak-to-peak [mm]: the cycles' spread / sqrt(n), and
    # on a tracked movie with a periodic template its coefficient noise, which all cycles share
    # and the spread cannot show (the cycles' std understated it up to tenfold). On movies rendered
    # from four strokes at SNR 3 (12 each; one at SNR 5 and one at 10: 8) the errors over it had RMS
    # 0.75-1.65 per stroke and end, 1.17 over the 128 ends of the 64 movies: the noise's bias is
    # not in it (twice the threshold's kappa_E: -0.45 % at the leading end, -0.27 % at the
    # trailing one, at SNR 3)
    leading_lateral_p2p_se_mm: float = math.nan
    trailing_lateral_p2p_se_mm: float = math.nan
    # a turning field (NaN otherwise): cycle-averaged path, see flutterswim.steering.turning
    turning_radius_mm: float = math.nan
    turning_circle_fit_rms_mm: float = math.nan
    heading_lag_deg: float = math.nan
    heading_lag_std_deg: float = math.nan
    field_turn_rate_deg_s: float = math.nan
    heading_turn_rate_deg_s: float = math.nan
    turning_speed_mm_s: float = math.nan
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict: floats (None for NaN), ints, bools and strings."""
        out: dict[str, Any] = {}
        for k, v in asdict(self).items():
            if isinstance(v, (bool, np.bool_)):
                out[k] = bool(v)
            elif isinstance(v, (int, np.integer)):
                out[k] = int(v)
            elif isinstance(v, str):
                out[k] = v
            else:
                fv = float(v)
                out[k] = fv if math.isfinite(fv) else None
        return out


def _centroid_at(tr: Track, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The centroid (x, y) at ``times``: a cubic spline through every frame's."""
    xc, yc = tr.centroid()
    return CubicSpline(tr.t, xc)(times), CubicSpline(tr.t, yc)(times)


def per_cycle(obj: Any, cycles: Cycles | None = None, *, tip: int | str = "end", harmonics: int = 6,
              swim_angle: float | None = None, end: int | str | None = None,
              crossing: np.ndarray | None = None, centroid_at_starts: tuple | None = None) -> dict[str, np.ndarray]:
    """Per-cycle measurements, each (K,) (``swim_angle``: direction(s) across which the tip's
    lateral peak-to-peak is measured, scalar or (K,); default the mean displacement): period, advance along the field, displacement,
    speed, tip lateral peak-to-peak, nonreciprocity, self_intersecting (any frame of the
    cycle crosses itself); lengths in track units. ``end``: the end whose lateral peak-to-peak
    is measured ("start" s=0 or "end" s=l; default the section tip of the cycles). ``crossing``:
    per-frame self-intersection flags of the frames from the first cycle's start to the last
    one's end, if already known; ``centroid_at_starts``: the centroid (x, y) at the cycles'
    starts, if already known (a cubic spline through every frame's)."""
    tr = as_track(obj)
    cyc = detect_cycles(tr, tip=tip) if cycles is None else cycles
    i_end = cyc.tip if end is None else tip_index(tr, end)
    st = cyc.starts
    K = st.size - 1
    cx, cy = centroid_at_starts if centroid_at_starts is not None else _centroid_at(tr, st)
    dx, dy = np.diff(cx), np.diff(cy)
    fa = np.unwrap(tr.field_angle)
    fa_c = np.array([np.interp(0.5 * (st[k] + st[k + 1]), tr.t, fa) for k in range(K)])
    adv = dx * np.cos(fa_c) + dy * np.sin(fa_c)
    disp = np.hypot(dx, dy)
    if swim_angle is None:
        swim_angle = math.atan2(float(dy.sum()), float(dx.sum())) if K else 0.0
    ang = np.broadcast_to(np.asarray(swim_angle, float), (K,))
    p2p = _lateral_p2p(tr, st, i_end, ang, harmonics)
    nrec = np.full(K, np.nan)
    if K:
        coef, _, _, tw = shape_modes(tr, st[0], st[-1])
        for k in range(K):
            a = sample_cycle(tw, coef, st[k], st[k + 1] - st[k], 64)
            nrec[k] = stroke_area(a[:, 0], a[:, 1]) if a.shape[1] >= 2 else 0.0
    # frames of the cycles only, each cycle's [start, end] by index ranges: linear in the run
    inter = np.zeros(K, bool)
    if K:
        lo = np.searchsorted(tr.t, st[:-1], side="left")
        hi = np.searchsorted(tr.t, st[1:], side="right")
        if crossing is None:
            crossing = self_intersections(tr.window(st[0], st[-1])) > 0 if hi[-1] - lo[0] >= 2 else np.zeros(0, bool)
        c = np.concatenate(([0], np.cumsum(crossing)))
        inter = (c[np.clip(hi - lo[0], 0, crossing.size)] - c[np.clip(lo - lo[0], 0, crossing.size)]) > 0
    return {
        "self_intersecting": inter,
        "start": st[:-1], "period": np.diff(st), "advance": adv, "dx": dx, "dy": dy,
        "displacement": disp, "speed": disp / np.diff(st), "tip_p2p": p2p, "nonreciprocity": nrec,
    }


def _dropped_frames_hint(tr) -> str:
    """The tracker's hint for a movie whose stroke did not repeat frame by frame (a camera that
    dropped frames and no timestamps given), or ""."""
    periodic = str(((getattr(tr, "meta", None) or {}).get("temporal") or {}).get("periodic", ""))
    return periodic[periodic.index("if the camera dropped frames"):] if "if the camera dropped frames" in periodic else ""


#: most changes of the field's strength in a record for which describe picks the last stretch of
#: one strength (more: a strength that varies throughout, described as it is)
MAX_FIELD_STEPS = 10


def _last_field_stretch(tr: Track) -> tuple[float, float, str, float] | None:
    """(t0, t1, cause, strength): the record's last stretch of one field strength, without the field
    switched off, when the strength steps within the record (a simulation's schedule); else
    None. Cycles across a step of the strength, or after the field is switched off, are no
    strokes of one field: a field off from 10 s of a 30 s run was described over the cycles the
    switch cut (period 4 % short, advance 20 % low, and 'simulate longer')."""
    f = tr.field_strength
    if f is None:
        return None
    steps = np.nonzero(f[1:] != f[:-1])[0] + 1
    if steps.size == 0 or steps.size > MAX_FIELD_STEPS:
        return None
    bounds = np.r_[0, steps, f.size]
    parts = [(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if f[a] != 0 and b - a >= 2]
    if not parts:
        return None
    a, b = parts[-1]
    off = b < f.size and np.all(f[b:] == 0)
    cause = (f"the field is switched off at t = {float(tr.t[b]):.4g} s" if off else
             f"the field's strength steps {steps.size} time(s) in the record")
    return float(tr.t[a]), float(tr.t[b - 1]), cause, float(f[a])


#: describe says a swimmer stepped out when, while the field turns, it moves at less than this
#: fraction of its speed before the turn (the step-out of the steering model: half the speed)
STEPPED_OUT = 0.5


def describe(
    obj: Any,
    *,
    n_last: int = 5,
    tip: int | str = "end",
    cycles: Cycles | None = None,
    harmonics: int = 6,
    reciprocal_threshold: float = 0.1,
    max_gap: float = 0.25,
    **cycle_kwargs: Any,
) -> Descriptors:
    """Descriptors averaged over the last ``n_last`` detected cycles (consecutive cycles without
    missing frames over more than ``max_gap`` periods: no interval between frames longer than
    1.5 median intervals and ``max_gap`` periods, and none longer than 1.5 times the median
    period of its 6 nearest neighbours, where the section skipped strokes, unless it is one of
    3 or more consecutive cycles of one period, a new stroke; the last such run, fewer cycles
    if it is shorter, ``n_cycles_used``).

    Swimming direction: net centroid displacement over those cycles; advancement: its
    projection on the field direction (per cycle, field at mid-cycle; the total uses the mean
    field direction); tip lateral peak-to-peak: of the tip coordinate perpendicular to the
    swimming direction (each cycle's own direction for a turning swimmer), from a Fourier fit (``harmonics``) per cycle
    (robust to noise), averaged pooled over cycles. Nonreciprocity: signed area of the
    stroke loop in the plane of the first two principal shape modes (:func:`stroke_area`,
    modes oriented by :func:`shape_modes`): about +1 for a shape wave travelling towards
    s = l, -1 towards s = 0, 0 for a reciprocal stroke; |value| < ``reciprocal_threshold``
    is reported reciprocal. self_intersecting: some frame in the window crosses itself.
    """
    tr: Track = as_track(obj)
    if tr.meta.get("dimensionless"):
        raise ParameterError(
            "the run is dimensionless (simulated with fs.Groups: lengths in body lengths l, times in tau), and "
            "the descriptors are in mm and s; simulate with physical parameters (fs.Parameters, e.g. fs.PAPER; "
            "the groups alone fix the stroke in l and tau), or take the stroke in l and tau from the periodic "
            "orbit: fs.periodic_orbit(groups).descriptors()")
    if isinstance(n_last, bool) or not isinstance(n_last, (int, np.integer)) or n_last < 1:
        raise ParameterError(f"n_last={n_last!r} must be an integer >= 1")
    stretch = _last_field_stretch(tr) if cycles is None else None
    field_note = ""
    if stretch is not None:
        t0, t1, cause, strength = stretch
        tr = tr.window(t0, t1)
        field_note = (f"{cause}: described over t = {t0:.4g}-{t1:.4g} s, the last stretch of one field strength "
                      f"({strength:.4g} x kappa_E)")
    try:
        cyc = detect_cycles(tr, tip=tip, **cycle_kwargs) if cycles is None else cycles
    except ParameterError as exc:
        if stretch is None:
            raise
        # (the stretch after a late step is short: say so, not only that the signal is)
        raise ParameterError(f"{stretch[2]}, and its last stretch of one strength, t = {stretch[0]:.4g}-"
                             f"{stretch[1]:.4g} s, is too short to describe ({exc}); simulate longer after the "
                             "step") from None
    K = cyc.n_cycles
    if K < 1:
        raise ParameterError(
            f"the track ({tr.n_frames} frames over {tr.t[-1] - tr.t[0]:.4g} s) holds no complete "
            "stroke cycle; at least one cycle (two section crossings) is required"
        )
    # the last n_last consecutive cycles without missing frames: no interval with frames missing
    # longer than max_gap periods (a track from a movie holds only the frames that were tracked)
    if not (isinstance(max_gap, (int, float)) and max_gap > 0):
        raise ParameterError(f"max_gap={max_gap!r} must be a number > 0 (periods)")
    # (near a cycle, too: a gap there moves its crossings)
    gaps = cyc.frame_gaps(tr.t, margin=GAP_MARGIN)
    # and no cycle over 1.5 times the median period of its neighbours: the section skipped a
    # stroke there (its amplitude fell into the noise). Local, so that
    # a record whose period changes (the field changed) is described by its own last strokes
    # (a full window of 7 shifted inward at the record's ends, without the cycle itself: two
    # skipped strokes among the last four cycles must not make the median their own)
    def _near(k: int) -> float:
        a = min(max(0, k - 3), max(0, K - 7))
        w = np.delete(cyc.periods[a : a + 7], k - a)
        return float(np.median(w)) if w.size else float(cyc.periods[k])
    near = np.array([_near(k) for k in range(K)])
    long_ = cyc.periods > 1.5 * near
    # but a run of 3 or more consecutive cycles of one period (each within 25 % of the one
    # before) is a new period (the field changed), not skipped strokes: those come and go
    # with the noise and do not repeat at one period
    r = cyc.periods[1:] / cyc.periods[:-1]
    link = (r >= 0.8) & (r <= 1.25)
    same = np.zeros(K, bool)
    run = 1  # length of the run of linked cycles ending at cycle k
    for k in range(1, K):
        run = run + 1 if link[k - 1] else 1
        if run >= 3:
            same[k - run + 1 : k + 1] = True
    # a cycle missing frames is left out and the window goes on past it (the same stroke);
    # skipped strokes end the window (before them, the stroke was another or under the noise)
    skip = gaps > max_gap
    # a cycle that holds two or more strokes (the section missed a crossing between them) ends
    # the window like a skipped stroke (passed, in a sparse record without a limit cycle the
    # window ran on into the onset: the advance 60-80 % low)
    merged = cyc.merged if cyc.merged.size == K else np.zeros(K, bool)
    ends = ((long_ & ~same) | merged) & ~skip  # a cycle long because frames are missing skipped no stroke
    good = ~skip & ~ends
    if np.count_nonzero(merged) * 2 >= K:
        raise ParameterError(
            f"{np.count_nonzero(merged)} of the track's {K} stroke cycles hold two or more strokes each: its frames "
            f"({tr.n_frames} over {tr.t[-1] - tr.t[0]:.4g} s) are too few or too uneven "
            "for the section to see every stroke; descriptors need at least 4 frames in each stroke (a higher "
            "frame rate, or fewer frames dropped)")
    if not np.any(good):
        raise ParameterError(
            f"every one of the track's {K} stroke cycles misses frames, in it or within {GAP_MARGIN:g} period of it, "
            f"over more than {max_gap:g} period "
            f"(the shortest such gap {np.min(gaps):.2f} periods), for example frames that failed tracking; "
            "descriptors need cycles without such gaps (max_gap, describe --max-gap)")
    k1 = int(np.nonzero(good)[0][-1])
    # a settled record is described over its settled cycles only: the onset's growing strokes
    # before the limit cycle are another stroke (they took the advance 1.7 % low). The cycle
    # just before the first converged one is within tol of it (that is what converged says),
    # so it counts: a record settled from its start keeps its first cycle.
    k_first = max(int(np.searchsorted(cyc.starts, cyc.limit_cycle_time)) - 1, 0) if cyc.limit_cycle else 0
    k_first = min(k_first, k1)
    k0, n_good = k1, 1
    while k0 > k_first and not ends[k0 - 1] and n_good < n_last:
        k0 -= 1
        n_good += int(good[k0])
    while not good[k0]:
        k0 += 1
    use = good[k0 : k1 + 1]  # the window's cycles that are described
    idx = np.arange(k0, k1 + 1)[use]
    sub = Cycles(**{**cyc.__dict__, "starts": cyc.starts[k0 : k1 + 2]})
    # swimming direction over the window
    xc, yc = tr.centroid()
    t0, t1 = float(sub.starts[0]), float(sub.starts[-1])
    at_starts = _centroid_at(tr, sub.starts)
    sx, sy = at_starts[0][[0, -1]], at_starts[1][[0, -1]]
    swim = math.atan2(float(sy[1] - sy[0]), float(sx[1] - sx[0]))
    w = tr.window(t0, t1)
    movie = "px_per_mm" in tr.meta
    # a track that does not advance (a decaying wobble below the flutter threshold, a filament
    # held in place) has no swimming direction: its cycles' displacements are round-off or
    # noise and their directions scatter, and a measuring frame turning with them read the
    # body's own length as lateral motion (2.3 mm for a 30 nm wobble). Its lateral excursions
    # are measured across the mean body axis.
    drift = math.hypot(float(sx[1] - sx[0]), float(sy[1] - sy[0])) / (sub.starts.size - 1)
    floor = _STILL_BL * tr.length
    if movie:
        floor = max(floor, _STILL_PX * 1e-3 / (float(tr.meta["px_per_mm"]) * tr.scale_m))
    still = not drift >= floor
    # nor does a track whose cycles' displacements turn every which way from one cycle to the
    # next (a noisy record of a filament that does not swim, given without a movie's pixel size
    # to judge its noise by): a swimmer's turn alike, by 0 when it swims straight and by the
    # same angle when it turns steadily (the mean of the turns as unit vectors about 1; for
    # noise about 1 / sqrt(n))
    dxy = np.diff(np.stack(at_starts, axis=1), axis=0)
    if not still and dxy.shape[0] >= 3:
        z = (dxy[:, 0] + 1j * dxy[:, 1]) / np.maximum(np.hypot(dxy[:, 0], dxy[:, 1]), 1e-300)
        still = abs(complex(np.mean(z[1:] * np.conj(z[:-1])))) < _ALIGNED_TURNS
    if still:
        swim = body_axis_angle(w)
    inter = self_intersections(w) > 0
    pc = per_cycle(tr, sub, tip=tip, harmonics=harmonics, swim_angle=swim, crossing=inter, centroid_at_starts=at_starts)
    pc_angle = np.asarray(swim, float)
    # a turning swimmer (cycle directions spread by more than a degree): measure the tip's
    # lateral excursion across each cycle's own displacement
    chord = np.arctan2(pc["dy"], pc["dx"])
    if not still and use.sum() > 1 and np.max(np.abs(np.angle(np.exp(1j * (chord[use] - swim))))) > math.radians(1.0):
        pc = per_cycle(tr, sub, tip=tip, harmonics=harmonics, swim_angle=chord, crossing=inter, centroid_at_starts=at_starts)
        pc_angle = chord
    pc = {k: v[use] for k, v in pc.items()}
    mm = tr.scale_m * 1e3
    L = tr.length
    per = pc["period"]
    freq = 1.0 / per
    adv = pc["advance"]
    spd = pc["speed"]
    p2p = pc["tip_p2p"]
    dirs = np.arctan2(pc["dy"], pc["dx"])
    dir_spread = float(np.degrees(np.sqrt(max(0.0, -2 * math.log(max(1e-300, abs(np.mean(np.exp(1j * dirs))))))))) if dirs.size > 1 else 0.0
    fa = float(np.angle(np.mean(np.exp(1j * w.field_angle))))
    rel = math.atan2(math.sin(swim - fa), math.cos(swim - fa))
    ahead = start_ahead(w, swim)
    nrec = pc["nonreciprocity"]
    nrec_mean = float(np.mean(nrec))
    # lateral peak-to-peak of both ends, named by the swimming direction
    p2p_end, se_end = {}, {}
    resolved = min(int(harmonics), _POOLED_HARMONICS)
    ang_k = np.broadcast_to(np.asarray(pc_angle, float), (sub.starts.size - 1,))
    for e_name in ("start", "end"):
        i_e = tip_index(tr, e_name)
        fit: dict = {}  # (the section tip's end again: the standard error needs the fit's details)
        pe = _lateral_p2p(tr, sub.starts, i_e, ang_k, harmonics, fit)[use]
        resolved = min(resolved, fit.get("resolved", resolved))
        fin = pe[np.isfinite(pe)]
        p2p_end[e_name] = float(np.mean(fin)) if fin.size else math.nan
        spread = _std(fin) / math.sqrt(fin.size) if fin.size > 1 else math.nan
        shared = _template_p2p_se(tr, i_e, harmonics, fit) if fin.size > 1 else math.nan
        # (one cycle: its spread is unknown, and so is the error)
        se_end[e_name] = math.hypot(spread, shared) if fin.size > 1 else math.nan
    # below 4 frames per stroke on average no lateral excursion is measured, even where some
    # cycles hold 4 frames (3.1-3.8 frames per stroke had read the trailing end 8-11 % short);
    # the frames the cycles described hold, not the median interval (frames dropped at random,
    # 3.3 per stroke left of 8.3, were still measured, 3-7 % short)
    st_used = np.c_[sub.starts[:-1], sub.starts[1:]][use]
    held = np.searchsorted(tr.t, st_used[:, 1], side="left") - np.searchsorted(tr.t, st_used[:, 0], side="left")
    per_stroke = float(np.mean(held)) if held.size else math.inf
    if per_stroke < _MIN_FRAMES_PER_STROKE:
        p2p = np.full_like(p2p, np.nan)
        p2p_end = dict.fromkeys(p2p_end, math.nan)
        se_end = dict.fromkeys(se_end, math.nan)
    lead, trail = ("end", "start") if still else ("start", "end") if ahead > 0 else ("end", "start")
    settled = bool(cyc.limit_cycle)
    # a turning field has no one direction to swim along: the turning figures describe it
    turned = float(np.ptp(np.unwrap(np.asarray(w.field_angle, float))))
    field_turns = turned > math.radians(5.0)
    note = "" if settled else (
        "no limit cycle: the stroke is still changing from cycle to cycle (onset or transient), so the "
        "averages describe unsettled cycles and the limit-cycle time, transient duration and onset time "
        "are unknown; " + ("record longer" if movie else "simulate longer (run_to_limit_cycle)")) if not field_turns else (
        f"no limit cycle: the field turns by {math.degrees(turned):.3g} deg over the cycles described and the "
        "stroke changes with it, so the averages describe a turning swimmer's cycles and the limit-cycle "
        "time, transient duration and onset time are unknown")
    last = cyc.tol_used[-min(cyc.n_cycles - 1, 3):, :2] if cyc.n_cycles > 1 else np.empty((0, 2))
    if not settled and last.size and np.nanmax(last) > _MAX_RESOLVABLE:
        note = (f"no limit cycle found: the noise hides changes from cycle to cycle of up to "
                f"{100.0 * np.nanmax(last):.3g} % in period or amplitude, over {100 * _MAX_RESOLVABLE:g} %, so "
                "whether the stroke has settled is not known")
    amp = cyc.amplitudes[k0 : k1 + 1]
    fall = cyc.d_amplitude[k0 + 1 : k1 + 1]
    if (not settled and amp.size >= 3 and np.all(np.diff(amp) < 0)
            and np.all(fall > np.nan_to_num(cyc.tol_used[k0 + 1 : k1 + 1, 1], nan=0.0))):
        rate = (amp[-1] / amp[0]) ** (1.0 / (amp.size - 1))
        note = (f"the oscillation decays: its amplitude fell every cycle, by {100 * (1 - rate):.2g} % per cycle "
                f"over the last {amp.size}: no sustained stroke (below the flutter threshold the straight state "
                "is stable); the figures describe a dying transient")
    # an oscillation a thousandth of the record's largest in the cycles described: the stroke
    # stopped (a filament trapped in a bent equilibrium, or at rest: the integrator's or the
    # camera's noise makes the cycles), which no limit cycle of a stroke describes
    faded = cyc.n_cycles > 0 and float(np.mean(amp)) < _FADED * float(np.max(cyc.amplitudes))
    if faded and not note.startswith("the oscillation decays"):  # (that says more)
        settled = False
        note = (f"the stroke stopped: the oscillation over the cycles described is "
                f"{float(np.mean(amp)) / float(np.max(cyc.amplitudes)):.2g} of the record's largest (at rest, "
                "or trapped in a bent equilibrium), so no limit cycle and these figures describe no stroke")
    hint = _dropped_frames_hint(tr)
    if note.startswith("no limit cycle") and hint:
        note = f"{note}; {hint}"
    if still:
        note = (note + "; " if note else "") + (
            f"no net swimming: the centroid moves {drift / tr.length:.2g} body lengths per cycle, under "
            f"{floor / tr.length:.2g} (round-off or noise), so the swimming direction, the leading end and the "
            "advance mean nothing; the lateral excursions are measured across the mean body axis")
    if settled:
        # the trailing run of converged cycles, judged within what the frames resolve where
        # that exceeds tol (a tracked movie's noise, a stroke's harmonics beyond a coarse frame
        # rate): say what change from cycle to cycle would go unseen
        k_lc = int(np.searchsorted(cyc.starts, cyc.limit_cycle_time))  # the verdict's run, gaps and all
        run = cyc.n_cycles - k_lc
        used = cyc.tol_used[k_lc:]
        if used.size and np.nanmax(used) > 1.2 * cyc.tol:
            worst = 100.0 * np.nanmax(used, axis=0)
            note = (note + "; " if note else "") + (f"limit cycle within what the frames resolve (noise, or harmonics too fast for the frame "
                    f"rate): over its last {run} cycles, changes from cycle "
                    f"to cycle of up to {worst[0]:.2g} % in period, {worst[1]:.2g} % in amplitude and "
                    f"{worst[2]:.2g} % in shape would go unseen (tol {100.0 * cyc.tol:.2g} %)")
    if idx.size < n_last:
        why = []
        if K < n_last:
            why.append(f"the track holds {K} complete cycle{'s' if K != 1 else ''} between section crossings (a "
                       "record of n strokes from an arbitrary phase holds n - 1)")
        if k0 == k_first > 0 and idx.size < min(K, n_last):
            before = np.asarray(tr.field_angle, float)[tr.t < cyc.limit_cycle_time] if np.ndim(tr.field_angle) else []
            what = ("the onset or the field's turn" if np.size(before) > 1 and np.ptp(np.unwrap(before)) > math.radians(5.0)
                    else "the onset")
            why.append(f"the stroke settles at t = {cyc.limit_cycle_time:.4g} s (limit_cycle_time_s): the {k_first} "
                       f"cycle{'s' if k_first != 1 else ''} before {'are' if k_first != 1 else 'is'} {what}, "
                       "not the stroke")
        elif idx.size < min(K, n_last):
            why.append(f"{K - idx.size} of its {K} cycles are left out for missing frames (max_gap, --max-gap), "
                       "for holding two strokes (a crossing missed between them: few frames per stroke) or "
                       "cut off at skipped strokes")
        note = (note + "; " if note else "") + (
            f"described over {idx.size} cycle{'s' if idx.size != 1 else ''}, fewer than the {n_last} asked for "
            f"(n_last, --last): {'; '.join(why)}")
    behind = float(cyc.starts[-1] - sub.starts[-1])
    span = float(sub.starts[-1] - sub.starts[0])
    if not settled and span > (idx.size + 2) * float(np.median(cyc.periods)):
        # (the window passes cycles missing frames: spread thin, it reached back into the onset)
        note = (note + "; " if note else "") + (
            f"the {idx.size} cycle{'s' if idx.size != 1 else ''} described {'are' if idx.size != 1 else 'is'} spread "
            f"over {span:.3g} s from t = {float(sub.starts[0]):.4g} s (those between miss frames): without a limit "
            "cycle the earliest may be an earlier stroke (the onset)")
    if not settled and behind > 2.0 * float(np.median(cyc.periods)):
        # (a sparse record whose later cycles all miss frames was described over its onset: the
        # advance 60-80 % low, with the period right)
        note = (note + "; " if note else "") + (
            f"the cycles described end at t = {float(sub.starts[-1]):.4g} s, {behind:.3g} s before the record's "
            "last: the later ones miss frames or hold skipped strokes, and without a limit cycle these figures "
            "may describe an earlier stroke (the onset)")
    if cyc.growth_note:
        note = (note + "; " if note else "") + cyc.growth_note
    if tr.meta.get("run_failed"):
        note = (note + "; " if note else "") + (f"the simulation failed ({tr.meta['run_failed']}): described over "
                                               "the frames before the failure")
    # (the cycles' phases drift by the fraction of a frame per stroke: over the cycles described
    # they cover the frame interval unless that fraction times their number is below 1)
    ratio = float(np.mean(per)) / float(np.median(np.diff(tr.t)))
    bunched = per.size * abs(ratio - round(ratio)) < 1.0
    if np.any(np.isfinite(p2p)) and bunched and resolved < min(int(harmonics), _POOLED_HARMONICS):
        # a nearly whole number of frames per stroke puts every cycle's frames on the same few
        # phases: the harmonics beyond are never seen (the paper's trailing end at 5.0 and 6.0
        # frames per stroke: 5.7 and 6.1 % short, with a standard error of 1e-5 mm)
        note = (note + "; " if note else "") + (
            f"the frames fall on few phases of the stroke ({ratio:.3g} frames per stroke, nearly a whole "
            f"number): they resolve {resolved} harmonic{'s' if resolved != 1 else ''} of it, and the lateral "
            "excursions may be several % short (their standard errors do not hold it); record at a frame rate that "
            "is not a whole multiple of the stroke's, or a higher one")
    if not np.any(np.isfinite(p2p)):
        note = (note + "; " if note else "") + (
            f"the lateral excursions are not measured: {per_stroke:.2g} frames per stroke, a cycle needs at "
            f"least {_MIN_FRAMES_PER_STROKE} (a higher frame rate)")
    if np.any(inter):  # the paper's red strokes, or a swimmer curled up by a field turning too fast
        note = (note + "; " if note else "") + (
            f"the centreline crosses itself in {100 * float(np.mean(inter)):.2g} % of the frames described: "
            + ("the tracked shape joins two parts of the body there" if movie else
               "the model has no contact between parts of the body, so those shapes are not physical"))
    if not still and not field_turns and abs(math.cos(rel)) < _ALONG_FIELD_COS:  # (along its line, either way)
        note = (note + "; " if note else "") + (
            f"swims at {math.degrees(rel):.3g} deg to the field direction taken ({math.degrees(fa):.3g} deg in the "
            f"image): the advance is measured along the field, {100 * (1 - abs(math.cos(rel))):.2g} % less than "
            "along the path; a swimmer in a steady field swims along its line, so if the field points elsewhere, "
            "give its direction (field_angle, --field-angle-deg)")
    adv_total = (xc[-1] - xc[0]) * math.cos(float(np.mean(tr.field_angle))) + (yc[-1] - yc[0]) * math.sin(
        float(np.mean(tr.field_angle))
    )
    p2p_mean = float(np.nanmean(p2p)) if np.any(np.isfinite(p2p)) else math.nan
    from ..steering.turning import turning_summary

    turn = turning_summary(tr.t, tr.x.mean(axis=1), tr.y.mean(axis=1), tr.field_angle, float(np.mean(per)))
    whole_turn = float(np.ptp(np.unwrap(np.asarray(tr.field_angle, float))))
    if whole_turn > math.radians(5.0) and not math.isfinite(turn["turning_radius"]):
        note = (note + "; " if note else "") + (
            f"the field turns by {math.degrees(whole_turn):.3g} deg in the record, but not steadily over more than "
            "5 periods (a step, or a short turn): the turning figures (radius, heading lag, turn rates) need such "
            "a turn, and are NaN")
    if turn["turning_speed"] < STEPPED_OUT * turn["speed_before_turning"]:
        note = (note + "; " if note else "") + (
            f"stepped out: while the field turns ({math.degrees(turn['field_turn_rate']):.3g} deg/s) the swimmer "
            f"moves at {turn['turning_speed'] / turn['speed_before_turning']:.2g} of its speed before the turn: the "
            "field turns faster than the stroke can steer it, and the turning figures describe a filament turning "
            "nearly in place")
    if field_note:
        note = field_note + ("; " + note if note else "")
    return Descriptors(
        turning_radius_mm=turn["turning_radius"] * mm,
        turning_circle_fit_rms_mm=turn["circle_fit_rms"] * mm,
        heading_lag_deg=math.degrees(turn["heading_lag"]),
        heading_lag_std_deg=math.degrees(turn["heading_lag_std"]),
        field_turn_rate_deg_s=math.degrees(turn["field_turn_rate"]),
        heading_turn_rate_deg_s=math.degrees(turn["heading_turn_rate"]),
        turning_speed_mm_s=turn["turning_speed"] * mm,
        n_cycles_used=int(idx.size),
        n_cycles_detected=int(K),
        window_start_s=t0,
        window_end_s=t1,
        body_length_mm=L * mm,
        period_s=float(np.mean(per)),
        period_std_s=_std(per),
        frequency_hz=float(np.mean(freq)),
        frequency_std_hz=_std(freq),
        advance_per_cycle_mm=float(np.mean(adv)) * mm,
        advance_per_cycle_std_mm=_std(adv) * mm,
        advance_per_cycle_bl=float(np.mean(adv)) / L,
        advance_per_cycle_std_bl=_std(adv) / L,
        advance_total_mm=float(adv_total) * mm,
        advance_total_bl=float(adv_total) / L,
        speed_mm_s=float(np.mean(spd)) * mm,
        speed_std_mm_s=_std(spd) * mm,
        speed_bl_s=float(np.mean(spd)) / L,
        speed_std_bl_s=_std(spd) / L,
        tip_lateral_p2p_mm=p2p_mean * mm,
        tip_lateral_p2p_std_mm=_std(p2p[np.isfinite(p2p)]) * mm,
        tip_lateral_p2p_bl=p2p_mean / L,
        # (no net swimming: no swimming direction, and no end leads; the note says so)
        swim_direction_deg=math.nan if still else math.degrees(swim),
        swim_direction_std_deg=math.nan if still else dir_spread,
        field_direction_deg=math.degrees(fa),
        direction_to_field_deg=math.nan if still else math.degrees(rel),
        towards_field=bool(not still and math.cos(rel) > 0),
        leading_end="none" if still else ("s=0" if ahead > 0 else "s=l"),
        nonreciprocity=nrec_mean,
        nonreciprocity_std=_std(nrec),
        reciprocal=bool(abs(nrec_mean) < reciprocal_threshold),
        self_intersecting=bool(np.any(inter)),
        self_intersection_fraction=float(np.mean(inter)),
        limit_cycle=settled,
        limit_cycle_time_s=cyc.limit_cycle_time if settled else math.nan,
        onset_time_s=cyc.onset_time if settled else math.nan,
        transient_duration_s=cyc.transient_duration if settled else math.nan,
        growth_rate_per_s=cyc.growth_rate,
        growth_rate_stderr_per_s=cyc.growth_rate_stderr,
        leading_lateral_p2p_mm=p2p_end[lead] * mm,
        leading_lateral_p2p_bl=p2p_end[lead] / L,
        trailing_lateral_p2p_mm=p2p_end[trail] * mm,
        trailing_lateral_p2p_bl=p2p_end[trail] / L,
        leading_lateral_p2p_se_mm=se_end[lead] * mm,
        trailing_lateral_p2p_se_mm=se_end[trail] * mm,
        note=note,
    )
