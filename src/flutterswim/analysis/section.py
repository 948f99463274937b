"""Poincare section of a scalar oscillating signal: upward crossings through its running mean.

Works on non-uniformly sampled signals, removes slow drifts with a running mean over one
period, uses a Schmitt trigger (hysteresis relative to the local amplitude and to the local
noise level) and locates each crossing to sub-frame accuracy by a local least-squares
polynomial fit.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import ParameterError

__all__ = ["estimate_period", "running_mean", "upward_crossings", "section_crossings"]


def _cumint(t: np.ndarray, f: np.ndarray) -> np.ndarray:
    out = np.zeros_like(f, dtype=float)
    out[1:] = np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(t))
    return out


def running_mean(t: np.ndarray, f: np.ndarray, window: float) -> np.ndarray:
    """Mean of f over [tc - W/2, tc + W/2]; near the ends the window is shifted to stay inside
    the data (it keeps its full width, so a periodic signal of period W is removed exactly)."""
    t = np.asarray(t, float)
    f = np.asarray(f, float)
    dur = t[-1] - t[0]
    if window >= dur:
        return np.full_like(f, np.trapezoid(f, t) / dur if hasattr(np, "trapezoid") else np.trapz(f, t) / dur)
    I = _cumint(t, f)
    tc = np.clip(t, t[0] + 0.5 * window, t[-1] - 0.5 * window)
    return (np.interp(tc + 0.5 * window, t, I) - np.interp(tc - 0.5 * window, t, I)) / window


def estimate_period(t: np.ndarray, u: np.ndarray) -> float:
    """Dominant period of u from the spectrum of its time derivative (which suppresses slow
    drifts), on a uniform resampling; at least two periods must fit in the record."""
    t = np.asarray(t, float)
    u = np.asarray(u, float)
    if t.size < 9:
        raise ParameterError(f"signal of {t.size} samples is too short for a period: two periods of at least "
                             "4 samples each are required (9 samples or more)")
    dt = float(np.median(np.diff(t)))
    n = int(np.floor((t[-1] - t[0]) / dt)) + 1
    tu = t[0] + dt * np.arange(n)
    uu = np.interp(tu, t, u)
    du = np.diff(uu) / dt
    du = du - du.mean()
    m = du.size
    nfft = 1 << int(np.ceil(np.log2(max(8 * m, 64))))
    spec = np.abs(np.fft.rfft(du * np.hanning(m), nfft))
    freqs = np.fft.rfftfreq(nfft, dt)
    dur = float(t[-1] - t[0])
    fmin = 2.0 / dur
    ok = freqs >= fmin
    if not np.any(ok) or not np.any(spec[ok] > 0):
        raise ParameterError(
            f"signal of duration {dur:.4g} s has no detectable oscillation; "
            "at least two periods are required"
        )
    i = int(np.argmax(np.where(ok, spec, -np.inf)))
    # the strongest oscillation with at least one period in the record
    j = int(np.argmax(np.where(freqs >= 1.0 / dur, spec, -np.inf)))
    if freqs[j] < fmin:
        # it has fewer than two periods. A short record: the band's maximum is that lobe's flank
        # or one of its harmonics: refuse. A swimmer turning slowly (about one turn in the
        # record) beside its stroke: the stroke is the strongest peak of its own, away from both
        short = ParameterError(
            f"signal of duration {dur:.4g} s ({t.size} samples) holds fewer than two periods of its "
            f"oscillation (about {dur * freqs[j]:.2g}); at least two periods are required")
        inner = np.zeros_like(ok)
        inner[1:-1] = (spec[1:-1] > spec[:-2]) & (spec[1:-1] > spec[2:])
        harmonic = np.zeros_like(ok)
        # a lobe's position is known to about a quarter of the resolution 1/dur; from the 4th
        # on, the bands would join and cover a turning swimmer's stroke: the refined lobe's
        # multiples, half a resolution either side
        f_slow = _refine(freqs, spec, j)
        for k in range(2, 9):
            tol = (0.5 + 0.25 * k) / dur if k <= 3 else 0.5 / dur
            harmonic |= np.abs(freqs - k * (freqs[j] if k <= 3 else f_slow)) <= tol
        own = ok & inner & ~harmonic & (freqs >= fmin + 0.5 / dur)
        if not np.any(own):
            raise short
        i = int(np.argmax(np.where(own, spec, -np.inf)))
        try:
            _check_oscillation(t, u, 1.0 / _refine(freqs, spec, i))
        except ParameterError:
            raise short from None
    f = _refine(freqs, spec, i)
    _check_oscillation(t, u, 1.0 / f)
    return 1.0 / f


def _refine(freqs: np.ndarray, spec: np.ndarray, i: int) -> float:
    """Frequency of the spectral peak at bin i, from a parabola through the log of its three bins."""
    if 0 < i < spec.size - 1:
        a, b, c = np.log(spec[i - 1 : i + 2] + 1e-300)
        den = a - 2 * b + c
        shift = 0.5 * (a - c) / den if den != 0 else 0.0
        return float(freqs[i] + float(np.clip(shift, -0.5, 0.5)) * (freqs[1] - freqs[0]))
    return float(freqs[i])


def _check_oscillation(t: np.ndarray, u: np.ndarray, period: float, harmonics: int = 3, min_f: float = 10.0) -> None:
    """Refuse a signal without a real oscillation at ``period``: its variation about the running
    mean over one period (slow drifts and turns removed) must be explained by a periodic series
    of ``harmonics`` harmonics significantly better than by nothing (F statistic >= ``min_f``;
    white noise, its best period chosen, gives about 1-4; a stroke at SNR 3, 10^3 or more)."""
    d = u - running_mean(t, u, period)
    ph = 2.0 * np.pi * (t - t[0]) / period
    B = np.column_stack([np.ones_like(t)] + [f(h * ph) for h in range(1, harmonics + 1) for f in (np.cos, np.sin)])
    coef, _, rank, _ = np.linalg.lstsq(B, d, rcond=None)
    rss1 = float(np.sum((d - B @ coef) ** 2))
    rss0 = float(np.sum((d - d.mean()) ** 2))
    dof = t.size - rank
    if rss0 <= 0.0 or dof <= 0:
        raise ParameterError(f"signal of duration {t[-1] - t[0]:.4g} s has no detectable oscillation; "
                             "at least two periods are required")
    F = ((rss0 - rss1) / max(rank - 1, 1)) / (rss1 / dof) if rss1 > 0 else math.inf
    if F < min_f:
        raise ParameterError(f"signal of duration {t[-1] - t[0]:.4g} s has no detectable oscillation: a periodic "
                             f"fit at its strongest period ({period:.4g} s) explains its variation no better than "
                             f"noise (F = {F:.2g} < {min_f:g}); is the filament swimming? If it swims in part of the "
                             "record only, give its approximate period (describe --period, or describe(..., period=...))")


def _local_root(t: np.ndarray, d: np.ndarray, m: int, half_window: float, deg: int) -> float:
    """Root of d near the bracket (t[m], t[m+1]) from a local least-squares polynomial of
    degree ``deg`` (normal equations on the scaled abscissa, Newton from the linear root;
    the root must stay inside the fitted span with the polynomial rising, else the linear
    root is returned)."""
    t0, t1, d0, d1 = t[m], t[m + 1], d[m], d[m + 1]
    tlin = t0 - d0 * (t1 - t0) / (d1 - d0) if d1 != d0 else 0.5 * (t0 + t1)
    lo = int(np.searchsorted(t, tlin - half_window, side="left"))
    hi = int(np.searchsorted(t, tlin + half_window, side="right"))
    lo, hi = min(lo, m), max(hi, m + 2)
    if hi - lo < deg + 2:
        return float(tlin)
    tt = t[lo:hi] - tlin
    sc = max(float(np.max(np.abs(tt))), 1e-300)
    v = np.vander(tt / sc, deg + 1, increasing=True)
    try:
        coef = np.linalg.solve(v.T @ v, v.T @ d[lo:hi])
    except np.linalg.LinAlgError:
        return float(tlin)
    dcoef = coef[1:] * np.arange(1, deg + 1)
    x = 0.0
    for _ in range(30):
        p = coef[-1]
        for c in coef[-2::-1]:
            p = p * x + c
        dp = dcoef[-1]
        for c in dcoef[-2::-1]:
            dp = dp * x + c
        if dp <= 0.0:
            return float(tlin)
        step = p / dp
        x -= step
        if abs(x) * sc > half_window:
            return float(tlin)
        if abs(step) < 1e-14:
            break
    dp = dcoef[-1]
    for c in dcoef[-2::-1]:
        dp = dp * x + c
    return float(tlin + x * sc) if dp > 0.0 else float(tlin)


def _local_roots(t: np.ndarray, d: np.ndarray, ms: np.ndarray, half_window: float, deg: int) -> np.ndarray:
    """:func:`_local_root` for many brackets at once (the same fits and Newton iterations,
    batched: padded windows with zero weights)."""
    ms = np.asarray(ms, int)
    t0, t1, d0, d1 = t[ms], t[ms + 1], d[ms], d[ms + 1]
    same = d1 == d0
    tlin = np.where(same, 0.5 * (t0 + t1), t0 - d0 * (t1 - t0) / np.where(same, 1.0, d1 - d0))
    lo = np.minimum(np.searchsorted(t, tlin - half_window, side="left"), ms)
    hi = np.maximum(np.searchsorted(t, tlin + half_window, side="right"), ms + 2)
    out = tlin.copy()
    if half_window <= 0.0:
        return out
    ok = hi - lo >= deg + 2
    if not np.any(ok):
        return out
    width = int(np.max(hi[ok] - lo[ok]))
    idx = lo[:, None] + np.arange(width)[None, :]
    valid = (idx < hi[:, None]) & ok[:, None]
    idx = np.minimum(idx, t.size - 1)
    tt = np.where(valid, t[idx] - tlin[:, None], 0.0)
    sc = np.maximum(np.max(np.abs(tt), axis=1), 1e-300)
    v = (tt / sc[:, None])[:, :, None] ** np.arange(deg + 1)[None, None, :] * valid[:, :, None]
    a = np.einsum("cki,ckj->cij", v, v)
    b = np.einsum("cki,ck->ci", v, np.where(valid, d[idx], 0.0))
    a[~ok] = np.eye(deg + 1)
    try:
        coef = np.linalg.solve(a, b[:, :, None])[:, :, 0]
    except np.linalg.LinAlgError:
        return np.array([_local_root(t, d, int(m), half_window, deg) for m in ms])
    dcoef = coef[:, 1:] * np.arange(1, deg + 1)
    x = np.zeros(ms.size)
    good = ok.copy()
    for _ in range(30):
        p = np.polynomial.polynomial.polyval(x, coef.T, tensor=False)
        dp = np.polynomial.polynomial.polyval(x, dcoef.T, tensor=False)
        good &= dp > 0.0
        step = np.where(good, p / np.where(dp > 0.0, dp, 1.0), 0.0)
        x = x - step
        good &= np.abs(x) * sc <= half_window
        if np.all(np.abs(step[good]) < 1e-14):
            break
    dp = np.polynomial.polynomial.polyval(x, dcoef.T, tensor=False)
    good &= dp > 0.0
    return np.where(good, tlin + x * sc, tlin)


def upward_crossings(
    t: np.ndarray,
    d: np.ndarray,
    threshold: np.ndarray | float,
    *,
    half_window: float = 0.0,
    deg: int = 3,
) -> np.ndarray:
    """Times where d rises through 0, with hysteresis: d must have gone below -threshold
    before and must reach +threshold after. Sub-frame location by a local polynomial fit of
    degree ``deg`` over +-half_window (linear interpolation when the window holds too few
    points)."""
    t = np.asarray(t, float)
    d = np.asarray(d, float)
    h = np.broadcast_to(np.asarray(threshold, float), d.shape)
    mark = np.where(d > h, 1, np.where(d < -h, -1, 0))
    idx = np.where(mark != 0, np.arange(d.size), -1)
    last = np.maximum.accumulate(idx)
    state = np.where(last >= 0, mark[np.maximum(last, 0)], 0)
    # upward transition: state goes from -1 to +1 at j
    js = np.nonzero((state[1:] == 1) & (state[:-1] == -1))[0] + 1
    # at each, the last rise through 0 (between frames i and i + 1) since the last index that
    # was below -h: i in [last[j - 1], j - 1]
    rises = np.nonzero((d[:-1] <= 0) & (d[1:] > 0))[0]
    pos = np.searchsorted(rises, js - 1, side="right") - 1
    ok = pos >= 0
    ms = rises[np.maximum(pos, 0)]
    ms = ms[ok & (ms >= last[js - 1])]
    if not ms.size:
        return np.empty(0)
    # without a window: linear interpolation (what _local_root falls back to)
    return _local_roots(t, d, ms, half_window, deg)


_ROUNDING = 1e-10  # a variation under this fraction of the record's largest is rounding, not a stroke
_REST_CONTRAST = 0.3  # "small beside the stroke": under this fraction of the record's largest amplitude


def _noise_sigma(t: np.ndarray, u: np.ndarray, window: float) -> np.ndarray:
    """Local standard deviation of white measurement noise from second differences."""
    e = np.zeros_like(u)
    e[1:-1] = u[2:] - 2 * u[1:-1] + u[:-2]
    e[0], e[-1] = e[1], e[-2]
    return np.sqrt(np.maximum(running_mean(t, e * e, window), 0.0) / 6.0)


def section_crossings(
    t: np.ndarray,
    u: np.ndarray,
    *,
    period: float | None = None,
    hysteresis: float = 0.25,
    noise_factor: float = 4.0,
    iterations: int = 2,
    locate: bool = True,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Upward crossings of u through its running mean over one period.

    Returns (crossing times, detrended signal d = u - running mean, period used for the
    running mean). The period is estimated from the spectrum unless given, then refined from
    the median spacing of the crossings ``iterations`` times. ``locate=False``: the crossings
    linearly interpolated (the period is refined on those anyway), without the final pass that
    locates them by local polynomials.
    """
    t = np.asarray(t, float)
    u = np.asarray(u, float)
    if not 0.0 <= hysteresis < 1.0:
        raise ParameterError(f"hysteresis={hysteresis!r} must be in [0, 1) (fraction of the local amplitude)")
    W = float(period) if period is not None else estimate_period(t, u)
    if not (np.isfinite(W) and W > 0):
        raise ParameterError(f"period={period!r} must be a finite number > 0")
    cross = np.empty(0)
    d = u - u.mean()
    # intervals with frames missing (a tracked movie holds the frames that were tracked)
    dt = np.diff(t)
    gi = np.nonzero(dt > 1.5 * float(np.median(dt)))[0] if t.size > 2 else np.empty(0, int)
    gap_a, gap_b = t[gi], t[gi + 1]
    # the period is refined on linearly interpolated crossings; the final crossings are
    # located by the local polynomial (one pass of it: linear in the record's length)
    final = locate and iterations <= 0 and period is not None  # a given period, not refined: the final pass only
    for it in range(max(1, iterations + 1) + 1):
        d = u - running_mean(t, u, W)
        amp = np.sqrt(2.0 * np.maximum(running_mean(t, d * d, W), 0.0))
        # the noise floor at most half the amplitude: a coarsely sampled stroke (a few frames
        # per period) has large second differences of its own, not noise
        sigma = _noise_sigma(t, u, W)
        h = np.maximum(hysteresis * amp, np.minimum(noise_factor * sigma, 0.5 * amp))
        # at rest: where the variation is no larger than the noise (amplitude under 2.5 sigma;
        # noise alone gives 1.4 sigma), its ratio to sigma well under the full stroke's and its
        # amplitude, the noise's share taken off, small beside the record's stroke: no crossings.
        # Second differences also grow with a coarse, sharp or unevenly sampled stroke's own
        # curvature, in proportion to it: a stroke of any size keeps its ratio
        ratio = amp / np.maximum(sigma, 1e-300)
        full = amp >= 0.5 * float(np.max(amp))
        r_full = float(np.median(ratio[full])) if np.any(full) else math.inf
        amp_c = np.sqrt(np.maximum(amp * amp - 2.0 * sigma * sigma, 0.0))
        rest = (amp < 2.5 * sigma) & (ratio < 0.7 * r_full) & (amp_c < _REST_CONTRAST * float(np.max(amp_c)))
        # and, with or without noise, a variation at the floating-point rounding of the stroke
        # (a clean simulation before its field is on): no stroke of its own
        rest |= amp < _ROUNDING * float(np.max(amp))
        cross = upward_crossings(t, d, np.where(rest, np.inf, h), half_window=W / 12.0 if final else 0.0)
        if cross.size < 3 and np.any(rest):  # never fewer than three crossings for the rule
            cross = upward_crossings(t, d, h, half_window=W / 12.0 if final else 0.0)
        # drop crossings closer than half a period to the previous one (harmonics)
        if cross.size > 1:
            keep = [0]
            for i in range(1, cross.size):
                if cross[i] - cross[keep[-1]] >= 0.5 * W:
                    keep.append(i)
            cross = cross[keep]
        if final:
            break
        if cross.size < 3 or it >= iterations or period is not None and it == 0 and iterations == 0:
            if not locate:
                break
            final = True
            continue
        # refine with the period of the well-developed (later) cycles, away from frames
        # missing (a gap moves the crossings within about half a period of it)
        dif = np.diff(cross)
        clear = (~np.array([np.any((gap_b > c0 - 0.6 * W) & (gap_a < c1 + 0.6 * W))
                            for c0, c1 in zip(cross[:-1], cross[1:])], bool) if gap_a.size
                 else np.ones(dif.size, bool))
        dif = dif[clear] if np.count_nonzero(clear) >= 1 else dif
        W_new = float(np.median(dif[len(dif) // 2 :]))
        if abs(W_new - W) < 1e-12 * W:
            if not locate:
                break
            final = True
            continue
        W = W_new
    return cross, d, W
