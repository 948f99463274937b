"""Stroke cycles: Poincare section of the tip's lateral displacement, limit-cycle detection,
onset time and growth rate of the oscillation envelope."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validate import ParameterError
from .section import _noise_sigma, estimate_period, running_mean, section_crossings
from .track import Track, as_track

__all__ = ["Cycles", "body_axis_angle", "local_axis_angle", "lateral_signal", "detect_cycles", "sample_cycle", "tip_index"]


def tip_index(track: Track, tip: int | str) -> int:
    """Point index of the tip: -1/"end" (s = l, default) or 0/"start" (s = 0)."""
    if tip in (-1, "end", track.n_points - 1):
        return track.n_points - 1
    if tip in (0, "start"):
        return 0
    raise ParameterError(f"tip={tip!r} is not allowed; use 'end' (s=l, index -1) or 'start' (s=0, index 0)")


def body_axis_angle(track: Track) -> float:
    """Mean direction of the body axis (s=0 -> s=l end-to-end vector summed over frames)."""
    ex = float(np.sum(track.x[:, -1] - track.x[:, 0]))
    ey = float(np.sum(track.y[:, -1] - track.y[:, 0]))
    if math.hypot(ex, ey) == 0.0:
        return 0.0
    return math.atan2(ey, ex)


def local_axis_angle(track: Track, window: float) -> np.ndarray:
    """Body-axis angle at each frame: the end-to-end direction (unwrapped) averaged over a
    running window of ``window`` s (one stroke period removes the stroke's own wobble and
    follows a slowly turning swimmer)."""
    t = track.t
    ang = np.unwrap(np.arctan2(track.y[:, -1] - track.y[:, 0], track.x[:, -1] - track.x[:, 0]))
    sm = running_mean(t, ang, window)
    # a window reaching into frames missing (a gap in a tracked movie) averages part of the
    # stroke's wobble: the axis there is interpolated between the windows clear of gaps (it
    # turns slowly), else the gap's error reaches a period beyond it through the section
    dt = np.diff(t)
    big = np.nonzero(dt > 1.5 * float(np.median(dt)))[0] if t.size > 2 else np.empty(0, int)
    hit = np.zeros(t.size, bool)
    for i in big:
        hit |= (t + 0.5 * window > t[i]) & (t - 0.5 * window < t[i + 1])
    if np.any(hit) and np.count_nonzero(~hit) >= 2:
        sm[hit] = np.interp(t[hit], t[~hit], sm[~hit])
    # within half a window of the ends the centred mean is not available: extrapolate the
    # interior linearly (exact for a steady turn, constant for a straight swimmer)
    a, b = t[0] + 0.5 * window, t[-1] - 0.5 * window
    inner = (t >= a) & (t <= b) & ~hit
    if np.count_nonzero(inner) >= 4:
        for edge, near in ((t < a, inner & (t <= a + 0.5 * window)), (t > b, inner & (t >= b - 0.5 * window))):
            if np.any(edge) and np.count_nonzero(near) >= 2:
                c = np.polyfit(t[near] - t[near].mean(), sm[near], 1)
                sm[edge] = np.polyval(c, t[edge] - t[near].mean())
    return sm


def lateral_signal(track: Track, *, tip: int | str = "end", axis_angle: float | np.ndarray | None = None,
                   ) -> tuple[np.ndarray, float | np.ndarray]:
    """Lateral displacement of the tip relative to the centroid, perpendicular to the body axis
    (drift-free). ``axis_angle``: scalar, per-frame array, or None for the mean body axis.
    Returns (u (T,), axis angle used)."""
    a = body_axis_angle(track) if axis_angle is None else np.asarray(axis_angle, float)
    i = tip_index(track, tip)
    xc, yc = track.centroid()
    u = -(track.x[:, i] - xc) * np.sin(a) + (track.y[:, i] - yc) * np.cos(a)
    return u, (float(a) if np.ndim(a) == 0 else a)


def sample_cycle(t: np.ndarray, f: np.ndarray, t0: float, period: float, n: int, endpoint: bool = False) -> np.ndarray:
    """Linear interpolation of f (T, ...) at n equally spaced phases of the cycle starting at t0."""
    tq = t0 + period * np.linspace(0.0, 1.0, n, endpoint=endpoint)
    j = np.clip(np.searchsorted(t, tq) - 1, 0, t.size - 2)
    w = ((tq - t[j]) / (t[j + 1] - t[j]))
    w = np.clip(w, 0.0, 1.0).reshape((-1,) + (1,) * (f.ndim - 1))
    return (1 - w) * f[j] + w * f[j + 1]


def leading_axes(X: np.ndarray, n: int) -> np.ndarray:
    """The ``n`` leading right singular vectors of X (F, N) (rows: frames), as rows (n, N), from
    the eigenvectors of the N x N matrix X^T X: an SVD of the F frames cost a sixth of describe.
    Their signs are arbitrary, as an SVD's."""
    _, v = np.linalg.eigh(X.T @ X)
    return v[:, ::-1][:, :n].T.copy()


def _fourier_columns(phase: np.ndarray, H: int) -> np.ndarray:
    """Columns 1, cos(2 pi h phase) for h = 1..H, sin(2 pi h phase) for h = 1..H."""
    arg = np.outer(phase, 2 * np.pi * np.arange(1, H + 1))
    return np.hstack([np.ones((np.size(phase), 1)), np.cos(arg), np.sin(arg)])


def fourier_harmonics(n: int, harmonics: int) -> int:
    """The harmonics :func:`fourier_fit` fits to n samples: at most (n - 1) / 4, at least 1."""
    return int(min(harmonics, max(1, (n - 1) // 4)))


def fourier_fit(phase: np.ndarray, q: np.ndarray, harmonics: int, *, constant: bool = False, cov: bool = False,
                design: bool = False):
    """Least-squares Fourier series in phase (period 1) of q (n,) or (n, M), with at most
    (n - 1) / 4 harmonics (at least 1): (coefficients, H), and with ``cov`` the inverse of the
    normal matrix (2H + 1, 2H + 1) (the coefficients' covariance per unit noise variance).
    The coefficients are the harmonics' (2H, ...): cos 1..H, then sin 1..H; with
    ``constant``, the constant first ((2H + 1, ...)). ``design`` (with ``cov``): the columns
    (n, 2H + 1) too, last."""
    H = fourier_harmonics(phase.size, harmonics)
    A = _fourier_columns(phase, H)
    G = A.T @ A
    try:
        coef = np.linalg.solve(G, A.T @ q)
    except np.linalg.LinAlgError:
        coef = np.linalg.lstsq(A, q, rcond=None)[0]
    coef = coef if constant else coef[1:]
    if not cov:
        return coef, H
    try:  # (G is symmetric positive definite when solve succeeded: pinv's SVD cost 15 % of describe)
        inv = np.linalg.inv(G)
    except np.linalg.LinAlgError:
        inv = np.linalg.pinv(G)
    return (coef, H, inv, A) if design else (coef, H, inv)


@dataclass(frozen=True, eq=False)
class Cycles:
    """Stroke cycles found by the Poincare section and the limit-cycle verdict.

    starts: (K+1,) section times; cycle k spans [starts[k], starts[k+1]].
    periods, amplitudes: (K,) duration and half peak-to-peak of the detrended section signal.
    d_period, d_amplitude, d_shape: (K,) relative change from the previous cycle (nan for k=0)
    of the period, the amplitude of the fitted lateral waveform (root mean square) and the shape.
    converged: (K,) all three changes below their tolerance: tol, plus what the measurement
    noise alone makes of the change (``tol_used``, (K, 3): period, amplitude, shape; nan for
    k=0; close to tol for a clean, finely sampled simulation).
    limit_cycle_time: start of the record's final run of converged cycles (each within tol of
    the one before it in period, amplitude and shape), from the record alone. Not the same
    measure as a simulation's ``settings["limit_cycle_time"]`` (a sweep's
    ``time_to_limit_cycle_s``): the first time from which every cycle's period and
    peak-to-peak lie within 1 % of the exact periodic orbit, usually a cycle or two earlier
    (the paper's run: 6.70 s against 7.38 s), as a cycle can be that close to the orbit while
    its shape still changes from the one before by more than tol.
    growth_note: why the growth rate is not given where the onset is in the record ("" else).
    merged: (K,) the cycle holds two or more strokes, the section's crossings between them
    missed (a few frames per stroke, some dropped); the limit-cycle run and describe leave
    such cycles out like those missing frames.
    """

    starts: np.ndarray
    periods: np.ndarray
    amplitudes: np.ndarray
    d_period: np.ndarray
    d_amplitude: np.ndarray
    d_shape: np.ndarray
    converged: np.ndarray
    limit_cycle: bool
    limit_cycle_time: float
    onset_time: float
    transient_duration: float
    growth_rate: float
    growth_rate_stderr: float
    growth_fit_window: tuple[float, float]
    axis_angle: float | np.ndarray
    section_t: np.ndarray
    section_signal: np.ndarray
    tol: float
    tip: int
    tol_used: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))
    growth_note: str = ""
    merged: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    @property
    def n_cycles(self) -> int:
        return int(self.periods.size)

    @property
    def mids(self) -> np.ndarray:
        return 0.5 * (self.starts[1:] + self.starts[:-1])

    def last(self, n: int) -> np.ndarray:
        """Indices of the last n cycles (fewer if fewer exist)."""
        return np.arange(max(0, self.n_cycles - n), self.n_cycles)

    def frame_gaps(self, t: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """(K,) the longest interval with frames missing (longer than 1.5 times the median
        interval between consecutive frame times ``t``) that overlaps each cycle, widened by
        ``margin`` of its period at both ends, as a fraction of that cycle's period; 0 where
        none is missing (a track from a movie holds only the frames that were tracked). Evenly
        sampled frames, however coarse, have no gap."""
        return _frame_gaps(self.starts, t, margin)

    def to_dict(self) -> dict[str, Any]:
        f = lambda v: None if not np.isfinite(v) else float(v)  # noqa: E731
        return {
            "n_cycles": self.n_cycles,
            "limit_cycle": bool(self.limit_cycle),
            "limit_cycle_time_s": f(self.limit_cycle_time),
            "onset_time_s": f(self.onset_time),
            "transient_duration_s": f(self.transient_duration),
            "growth_rate_per_s": f(self.growth_rate),
            "growth_rate_stderr_per_s": f(self.growth_rate_stderr),
            "cycle_starts_s": [float(v) for v in self.starts],
        }


def _frame_gaps(starts: np.ndarray, t: np.ndarray, margin: float) -> np.ndarray:
    """:meth:`Cycles.frame_gaps` for cycles [starts[k], starts[k+1]]."""
    t = np.asarray(t, float)
    K = starts.size - 1
    out = np.zeros(max(K, 0))
    if t.size < 2:
        return out
    dt = np.diff(t)
    dt = np.where(dt > 1.5 * float(np.median(dt)), dt, 0.0)
    if not dt.any():  # no frames missing (every simulation)
        return out
    for k in range(K):
        a, b = starts[k], starts[k + 1]
        over = (t[1:] > a - margin * (b - a)) & (t[:-1] < b + margin * (b - a))
        out[k] = float(dt[over].max()) / (b - a) if np.any(over) else 0.0
    return out


# frames missing over more than this fraction of a period, within GAP_MARGIN periods of a
# cycle (the section's running mean reaches half a period beyond its crossings, and their
# local fits a twelfth more), leave the cycle's crossings and fits uncertain
MAX_GAP = 0.25
GAP_MARGIN = 0.6


def _noise_variance(t: np.ndarray, u: np.ndarray, d: np.ndarray, W: float) -> float:
    """Variance of stationary measurement noise in u. The local second-difference estimate
    (over one period) is that variance plus a share of the stroke's own power that grows as
    the sampling coarsens: fitted over the record against the local power (mean of d^2),
    the intercept (relative residuals: the quiet frames weigh as much as the loud ones),
    within [0, the record's 10th percentile]."""
    s2 = _noise_sigma(t, u, W) ** 2
    p = running_mean(t, d * d, W)
    floor = float(np.percentile(s2, 10))
    ok = s2 > 0.0
    if np.count_nonzero(ok) < 3 or np.ptp(p[ok]) <= 0.0:
        return floor
    w = 1.0 / s2[ok]
    a = float(np.linalg.lstsq(np.column_stack([w, p[ok] * w]), np.ones(w.size), rcond=None)[0][0])
    return min(max(a, 0.0), floor)


def _envelope_onset(t: np.ndarray, d: np.ndarray, var: np.ndarray, W: float, t_final: float, t_end: float,
                    fraction: float) -> float:
    """Time the stroke's envelope (root mean square of d over one period, the noise's variance
    taken off) rises through ``fraction`` of its median over the last cycles [t_final, t_end]
    for the last time before them (log-linear between frames; the record start if it is above
    all along): noise under that level crosses it early and falls back. NaN where the noise
    hides that level."""
    env = np.sqrt(2.0 * np.maximum(running_mean(t, d * d, W) - var, 0.0))
    late = env[(t >= t_final) & (t <= t_end)]
    if late.size == 0 or not np.median(late) > 0:
        return math.nan
    thr = fraction * float(np.median(late))
    # unresolved: the threshold's power under twice the scatter of the envelope's (2 var
    # sqrt(2 / n) over n frames a period; 0.5 noise sigma for the paper's stroke at 200 fps)
    n = max(W / float(np.median(np.diff(t))), 1.0)
    if thr * thr < 2.0 * 2.0 * float(np.max(var)) * math.sqrt(2.0 / n):
        return math.nan
    below = np.nonzero((env < thr) & (t < t_final))[0]
    if below.size == 0:
        return float(t[0])
    i = int(below[-1]) + 1
    a, b = float(env[i - 1]), float(env[i])
    frac = math.log(thr / a) / math.log(b / a) if a > 0 and b > a else (thr - a) / (b - a) if b > a else 0.0
    return float(t[i - 1] + frac * (t[i] - t[i - 1]))


_Z_999 = 3.29  # two-sided 99.9 % point of the normal distribution
_MAX_RESOLVABLE = 0.2  # a limit cycle needs comparisons that resolve a change of this (relative)


def _merged_strokes(t: np.ndarray, d: np.ndarray, starts: np.ndarray, periods: np.ndarray,
                    W0: float | None) -> np.ndarray:
    """(K,) True for a cycle that holds m >= 2 strokes: the section missed the crossings between
    them (a few frames per stroke, some dropped, leave strokes with no frame beyond the
    hysteresis band). Such a cycle lasts about m periods of the stroke (``W0``, the spectrum's,
    which sees the stroke however coarse and uneven the frames: the paper's stroke at 2.1 frames
    per stroke, half dropped, within 0.1 %; else the cycles' median), and over its own phase its
    frames swing m times: the m-th harmonic of the detrended lateral signal d above the first.
    A stroke whose period changed (the field changed) swings once. A cycle of fewer than 6
    frames cannot tell: in a record of under 6 frames per stroke it counts as merged (there
    missed crossings are what make long cycles), else it is kept."""
    K = periods.size
    out = np.zeros(K, bool)
    if K < 1:
        return out
    ref = float(W0) if W0 is not None and math.isfinite(W0) and W0 > 0 else float(np.median(periods))
    sparse = (t[-1] - t[0]) / max(t.size - 1, 1) > ref / 6.0
    f0 = np.searchsorted(t, starts[:-1], side="left")
    f1 = np.searchsorted(t, starts[1:], side="left")
    for k in np.nonzero(periods > 1.5 * ref)[0]:
        m = max(int(round(periods[k] / ref)), 2)
        if f1[k] - f0[k] < 6:
            out[k] = sparse
            continue
        ph = 2.0 * np.pi * (t[f0[k] : f1[k]] - starts[k]) / periods[k]
        A = np.column_stack([np.ones_like(ph), np.cos(ph), np.sin(ph), np.cos(m * ph), np.sin(m * ph)])
        c = np.linalg.lstsq(A, d[f0[k] : f1[k]], rcond=None)[0]
        out[k] = bool(np.hypot(c[3], c[4]) > np.hypot(c[1], c[2]))
    return out


def _chi2_quantile(q: float, p: float) -> float:
    """The q point of the chi-square distribution with p degrees of freedom, per degree."""
    from scipy.special import chdtri  # the inverse upper tail: chi2.ppf(q, p) without its
    # argument checks, which cost 10 % of describe (a few dozen calls)

    return float(chdtri(p, 1.0 - q)) / p


def _chi2_999(p: float) -> float:
    """The 99.9 % point of the chi-square distribution with p degrees of freedom, per degree."""
    return _chi2_quantile(0.999, p)


def _fourier_phase_derivative(n: int, H: int) -> np.ndarray:
    """d/d(phase) of :func:`_fourier_columns` at the phases i / n, i < n."""
    h = 2 * np.pi * np.arange(1, H + 1)
    arg = np.outer(np.arange(n) / n, h)
    return np.hstack([np.zeros((n, 1)), -np.sin(arg) * h, np.cos(arg) * h])


def _phase_free(delta: np.ndarray, shape_phase: np.ndarray) -> np.ndarray:
    """A change ``delta`` (n_shape, modes) between cycles' shapes at the phases i / n_shape, less
    its least-squares part a S' + b phase S' (``shape_phase`` = S', the shape's derivative in
    phase): the change a shift and a uniform stretch of the phase make. Those come from the
    section's crossing times, whose noise moves a cycle's phase (start and end: shift and
    stretch) and which the period comparison tests. Left in, they made the settled shape's
    change from cycle to cycle 3-10 times (in mean square) what the frames' noise explains on
    movies of the paper's stroke tracked at SNR 5 (1.8-3 times without the periodic template,
    0.2-0.9 times with it, once removed), so that a movie holding the onset was read as
    never settling. The noise allowance keeps the two degrees of freedom removed (slightly
    generous)."""
    ph = np.arange(delta.shape[0]) / delta.shape[0]
    a, b = shape_phase.ravel(), (shape_phase * ph[:, None]).ravel()
    # the 2 x 2 normal equations (np.linalg.lstsq's SVD cost 10-20 % of detect_cycles)
    g = np.array([[a @ a, a @ b], [a @ b, b @ b]])
    d = delta.ravel()
    try:
        coef = np.linalg.solve(g, np.array([a @ d, b @ d]))
    except np.linalg.LinAlgError:  # (no stroke: S' = 0, nothing to remove)
        return delta
    return (d - coef[0] * a - coef[1] * b).reshape(delta.shape)


_LINEAR_ANGLE = 0.1  # rad: a shape within this of straight grows as the linearisation says


def _before_cut(sel: np.ndarray, ramps: np.ndarray, cut: float) -> np.ndarray:
    """The selection kept to the growing part before the envelope first reaches the cut."""
    first_big = np.nonzero(ramps > cut)[0]
    return sel & (np.arange(sel.size) < first_big[0]) if first_big.size else sel


def _log_linear_rate(tm: np.ndarray, la: np.ndarray) -> tuple[float, float]:
    """Slope of the log amplitudes ``la`` against the cycle times ``tm`` (least squares) and its
    standard error: the scatter about the line, and in quadrature the line's misfit to a log
    envelope that bends (the linear regime ending, the start's transient still in it): the
    curvature b of a quadratic fit makes the slope at either end of the window differ from
    the line's by b times its span (b^2 less its noise variance; with 3 cycles, which the
    quadratic goes through, all of b^2)."""
    x = tm - tm.mean()
    n = x.size
    sxx = float(x @ x)
    # (x is centred: the normal equations are diagonal; one time: no slope, as lstsq's minimum norm)
    coef = (float(x @ la) / sxx if sxx > 0 else 0.0, float(la.mean()))
    resid = la - coef[0] * x - coef[1]
    var = float(resid @ resid) / max(n - 2, 1) / sxx if n > 2 else math.nan
    if n >= 3:
        Q = np.vstack([x * x - sxx / n, x, np.ones_like(x)]).T
        cq = np.linalg.lstsq(Q, la, rcond=None)[0]
        b2 = float(cq[0]) ** 2
        if n > 3:
            rq = la - Q @ cq
            try:
                g00 = float(np.linalg.inv(Q.T @ Q)[0, 0])
            except np.linalg.LinAlgError:
                g00 = float(np.linalg.pinv(Q.T @ Q)[0, 0])
            b2 -= float(rq @ rq) / (n - 3) * g00
        var += max(b2, 0.0) * float(np.ptp(x)) ** 2
    return float(coef[0]), math.sqrt(var) if math.isfinite(var) else math.nan


def _enough(sel: np.ndarray, ramps: np.ndarray, noise_amp: np.ndarray) -> bool:
    """Whether the fit's selection holds 4 cycles (2 degrees of freedom for its standard
    error), or 3 each far above the noise (a clean, fast onset)."""
    n_sel = np.count_nonzero(sel)
    return bool(n_sel >= 4 or n_sel == 3 and np.all(ramps[sel] > 30.0 * noise_amp[sel]))


def detect_cycles(
    obj: Any,
    *,
    tip: int | str = "end",
    period: float | None = None,
    hysteresis: float = 0.25,
    tol: float = 1e-2,
    n_consecutive: int = 3,
    n_shape: int = 24,
    n_shape_modes: int = 4,
    onset_fraction: float = 0.1,
    fit_after: float | None = None,
    fit_max_fraction: float = 0.1,
    axis: str = "local",
) -> Cycles:
    """Find stroke cycles and decide whether a limit cycle has been reached.

    Section: upward crossings of the tip's lateral displacement (relative to the centroid,
    perpendicular to the body axis) through its running mean over one period. The body axis
    is the end-to-end direction averaged over one period around each frame (``axis="local"``,
    follows a turning swimmer) or over the whole track (``axis="global"``).
    Each cycle is fitted by a Fourier series in its phase at the frames it has (at most 6
    harmonics, (frames - 1) / 4 of the cycle with fewest frames, the same for all, except cycles
    with missing frames, which fit fewer). A cycle is *converged* when its period, amplitude (root mean
    square of the fitted lateral waveform) and shape (tangent angle minus its mean along s, at
    ``n_shape`` phases, projected on the ``n_shape_modes`` leading principal modes, 0 for no
    projection; its change less the part a shift and a uniform stretch of the cycle's phase
    make, which the section's crossing times move and the period tests) each change by less
    than ``tol`` (relative) from the previous cycle, plus what
    the measurement noise alone makes of that change (``tol_used``): the noise variance, the
    lower quartile of the cycles' residual variances over its chi-square expectation (residuals
    also hold harmonics too fast for a coarse frame rate), propagated to 3.29 standard errors
    (period, amplitude) or the 99.9 % point of the shape change's chi-square; a change of 20 %
    in period or amplitude that the noise could hide converges never. The limit cycle is
    reached if the last ``n_consecutive`` comparisons between cycles clear of missing frames
    (none over 0.25 period within 0.6 period of them) converge, the cycles either side of such
    frames compared directly; it starts at the first cycle of that run.

    Onset time: when the cycle amplitude first reaches ``onset_fraction`` of the final
    amplitude (log-linear interpolation); after a quiet stretch (no cycles over more than 1.5
    periods from the record start: at rest, or the stroke under the noise), when the envelope
    less the noise's variance last rises through that fraction (NaN if the noise hides it).
    Growth rate: least-squares fit of the log of the cycles' root-mean-square amplitude (less
    the noise's variance) against time over at least 4 cycles (3 if each is above 30 noise
    sigma) after ``fit_after`` (default: two relaxation times when the source knows tau, from
    the first cycle after a quiet stretch longer than that; else after the second cycle, or
    from the record start after a quiet stretch), above 3 noise sigma, more than a period
    from the record's ends, below ``fit_max_fraction`` of the final amplitude and within the
    linear regime: cycles whose stroke deflects the tangent angle by at most 0.1 rad (the
    fundamental's amplitude over the cycle, in the leading shape modes: a static bend and the
    angle's noise do not count). Of those, the fit starts at the cycle (leaving enough) that
    gives the smallest standard error, which holds the scatter about the line and its misfit:
    the curvature of a quadratic fit times the window's span (the start's transient or the
    end of the linear regime bending the log envelope). Where too few cycles are left in the
    linear regime but the onset has enough beyond it, the rate is NaN and ``growth_note``
    says why (a fit there is biased by far more than its scatter). A record that ends while
    the stroke still grows exponentially (its last two cycles each grow by over 10 % and at
    over 0.8 of the fastest growth, none before was larger, and the last period's cycles
    still grow at over half that) holds no final amplitude: no onset (NaN), and no cut at a
    fraction of it. Variation under 1e-10 of the record's largest
    (floating-point rounding) is no stroke; in a noisy record the fit starts two relaxation
    times after the record start where two after the first cycle leave too few cycles.
    """
    tr = as_track(obj)
    if not 0 < tol < 1:
        raise ParameterError(f"tol={tol!r} must be in (0, 1)")
    if isinstance(n_consecutive, bool) or not isinstance(n_consecutive, (int, np.integer)) or n_consecutive < 1:
        raise ParameterError(f"n_consecutive={n_consecutive!r} must be an integer >= 1")
    if not 0 < onset_fraction < 1:
        raise ParameterError(f"onset_fraction={onset_fraction!r} must be in (0, 1)")
    if axis not in ("local", "global"):
        raise ParameterError(f"axis={axis!r} is not allowed; use 'local' or 'global'")
    itip = tip_index(tr, tip)
    u, ax_angle = lateral_signal(tr, tip=itip)
    t = tr.t
    if axis == "local":
        W0 = float(period) if period is not None else estimate_period(t, u)
        u, ax_angle = lateral_signal(tr, tip=itip, axis_angle=local_axis_angle(tr, W0))
        period = W0
    if axis == "local":
        # the period refined on linear crossings; then, with the axis averaged over it, the
        # one final pass that locates the crossings
        starts, d, W = section_crossings(t, u, period=period, hysteresis=hysteresis, locate=False)
        if starts.size >= 3 and abs(W - period) > 1e-9 * W:
            u, ax_angle = lateral_signal(tr, tip=itip, axis_angle=local_axis_angle(tr, W))
        starts, d, W = section_crossings(t, u, period=W, hysteresis=hysteresis, iterations=0)
    else:
        W0 = float(period) if period is not None else estimate_period(t, u)
        starts, d, W = section_crossings(t, u, period=W0, hysteresis=hysteresis)
    K = max(starts.size - 1, 0)
    periods = np.diff(starts)
    amps = np.empty(K)
    lo = np.searchsorted(t, starts[:-1], side="left")  # frames of cycle k: starts[k] <= t <= starts[k+1]
    hi = np.searchsorted(t, starts[1:], side="right")
    # the measurement noise's variance (second differences, over one period): the growth fit
    # and the envelope use amplitudes corrected for it (the root mean square of d less the
    # noise's: unbiased, where the peak to peak grows with the noise)
    var = np.full_like(u, _noise_variance(t, u, d, W))
    ramps = np.zeros(K)
    noise_amp = np.zeros(K)
    for k in range(K):
        seg = d[lo[k] : hi[k]] if hi[k] > lo[k] else np.zeros(1)
        amps[k] = 0.5 * (seg.max() - seg.min())
        if hi[k] > lo[k]:
            v = float(np.mean(var[lo[k] : hi[k]]))
            ramps[k] = math.sqrt(2.0 * max(float(np.mean(seg * seg)) - v, 0.0))
            noise_amp[k] = math.sqrt(v)
    # each cycle as a Fourier series in its phase, fitted to its frames [starts[k], starts[k+1])
    # (frames missing from a tracked movie leave no interpolated corner): the stroke's lateral
    # waveform and its shape (tangent angle minus its mean along s, in the leading principal
    # shape modes: filters noise), compared from cycle to cycle at n_shape phases
    _, th = tr.tangent_angle()
    th = th - th.mean(axis=1, keepdims=True)
    f0 = np.searchsorted(t, starts[:-1], side="left")
    f1 = np.maximum(np.searchsorted(t, starts[1:], side="left"), f0 + 1)
    basis = None
    if K >= 2 and n_shape_modes:
        basis = leading_axes(th[f0[0] : f1[-1]], int(n_shape_modes)).T
    modes = th @ basis if basis is not None else th
    E_grid = {}
    shapes, shape_cov, shapes_phase = [], [], []
    fit_amp, amp_gain, slope = np.zeros(K), np.zeros(K), np.zeros(K)
    theta_amp = np.zeros(K)
    # residual sums of squares and degrees of freedom of each cycle's fits: the measurement
    # noise, what no periodic waveform explains (lateral; per shape mode)
    rss_u, rss_m, dof = np.zeros(K), np.zeros((K, modes.shape[1])), np.zeros(K)
    # one harmonic count for the cycles, that of the one with fewest frames (of those with at
    # least 3/4 of the median: a cycle with missing frames fits fewer on its own): at 12.8
    # frames per stroke cycles of 12 and 13 frames fitted 2 and 3 harmonics, and the third
    # harmonic's power, in some cycles only, read as a change from cycle to cycle ("no limit
    # cycle" on a settled stroke)
    n_fr = f1 - f0
    H_all = fourier_harmonics(int(n_fr[n_fr >= 0.75 * np.median(n_fr)].min()), 6) if K else 6
    for k in range(K):
        sl = slice(f0[k], f1[k])
        ph = (t[sl] - starts[k]) / periods[k]
        # the lateral signal and the shape modes in one solve, with the same design
        cc, H, C, A = fourier_fit(ph, np.column_stack([d[sl], modes[sl]]), H_all, cov=True, constant=True,
                                  design=True)
        c, cm = cc[:, 0], cc[:, 1:]
        ch = c[1:]
        rss_u[k] = float(np.sum((d[sl] - A @ c) ** 2))
        dof[k] = max(ph.size - (2 * H + 1), 0)
        fit_amp[k] = math.sqrt(float(ch @ ch) / 2.0)
        g = ch / (2.0 * fit_amp[k]) if fit_amp[k] > 0 else np.zeros_like(ch)
        amp_gain[k] = float(g @ C[1:, 1:] @ g)  # the amplitude's variance per unit noise variance
        slope[k] = float(2 * np.pi * np.arange(1, H + 1) @ ch[H:]) / periods[k]
        rss_m[k] = np.sum((modes[sl] - A @ cm) ** 2, axis=0)
        if H not in E_grid:
            E_grid[H] = _fourier_columns(np.arange(n_shape) / n_shape, H), _fourier_phase_derivative(n_shape, H)
        E, E_phase = E_grid[H]
        shapes.append(E @ cm)
        shapes_phase.append(E_phase @ cm)
        shape_cov.append(E @ C @ E.T)
        # the stroke's tangent-angle deflection: the fundamental's amplitude, its largest
        # along s, in the leading shape modes (a static bend is the zeroth harmonic: no stroke;
        # the measurement noise of a tracked filament's angle averages out)
        cs = np.stack([cm[1], cm[1 + H]])
        cs = cs @ basis.T if basis is not None else cs
        theta_amp[k] = float(np.max(np.hypot(cs[0], cs[1])))
    # a change between two cycles converges under tol, or under what the measurement noise
    # alone makes of it (a tracked movie): 3.29 standard errors for the period and the
    # amplitude, the 99.9 % point of the shape change's (weighted) chi-square. The noise is
    # stationary: its variance is the lower quartile of the cycles' residual variances (a
    # cycle's own growth or a harmonic it cannot hold is no noise, and makes the quartile no
    # larger than the most periodic cycles'). A comparison that could not resolve a change of
    # _MAX_RESOLVABLE in period or amplitude converges never
    has = dof > 0
    # (over the lower quartile's expectation for noise alone, a chi-square of the cycles' dof)
    q25 = _chi2_quantile(0.25, float(np.median(dof[has]))) if np.any(has) else 1.0
    v_u = float(np.percentile(rss_u[has] / dof[has], 25)) / q25 if np.any(has) else 0.0
    v_m = (np.percentile(rss_m[has] / dof[has, None], 25, axis=0) / q25 if np.any(has)
           else np.zeros(modes.shape[1]))
    # the crossing times' noise: the signal's noise over its slope there
    sig_x = math.sqrt(v_u) / np.maximum(np.abs(np.append(slope, slope[-1:])), 1e-300) if K else np.zeros(1)

    # per cycle, once (each is compared with its neighbours and across gaps): the shape's norm,
    # its covariance's trace and squared Frobenius norm
    sum_vm, sum_vm2 = float(np.sum(v_m)), float(np.sum(v_m**2))
    shape_norm = [float(np.linalg.norm(S)) for S in shapes]
    cov_trace = [float(np.trace(P)) for P in shape_cov]
    cov_sq = [float(np.vdot(P, P)) for P in shape_cov]

    def compare(j: int, k: int):
        """(change of period, amplitude, shape, their tolerances (3,), converged) from cycle j to k."""
        dp = abs(periods[k] - periods[j]) / max(abs(periods[k]), 1e-300)
        da = abs(fit_amp[k] - fit_amp[j]) / max(fit_amp[k], 1e-300)
        num = float(np.linalg.norm(_phase_free(shapes[k] - shapes[j], 0.5 * (shapes_phase[k] + shapes_phase[j]))))
        den = max(shape_norm[k], 1e-300)
        # the summed covariance P_k + P_j: its trace, and its squared norm
        tr_s = sum_vm * (cov_trace[k] + cov_trace[j])
        tr_s2 = sum_vm2 * (cov_sq[k] + cov_sq[j] + 2.0 * float(np.vdot(shape_cov[k], shape_cov[j])))
        # (a covariance's trace from a cycle of few frames can come out below 0 by round-off: a
        # movie with 60 % of its frames dropped raised "math domain error" here)
        noise_s = math.sqrt(_chi2_999(tr_s * tr_s / tr_s2) * tr_s) if tr_s2 > 0 and tr_s > 0 else 0.0
        # P_k - P_j = s[k+1] - s[k] - s[j+1] + s[j] (the middle crossing twice when adjacent)
        coef: dict[int, float] = {}
        for i, c in ((k + 1, 1.0), (k, -1.0), (j + 1, -1.0), (j, 1.0)):
            coef[i] = coef.get(i, 0.0) + c
        noise_p = _Z_999 * math.sqrt(sum((c * sig_x[i]) ** 2 for i, c in coef.items()))
        noise_a = _Z_999 * math.sqrt(max(v_u * (amp_gain[k] + amp_gain[j]), 0.0))
        row = np.array([tol + noise_p / periods[k], tol + noise_a / max(fit_amp[k], 1e-300), tol + noise_s / den])
        change = np.array([dp, da, num / den])
        return change, row, bool(np.all(change < row) and np.all(row[:2] <= _MAX_RESOLVABLE))

    merged = _merged_strokes(t, d, starts, periods, W0)
    d_period, d_amp, d_shape = np.full(K, np.nan), np.full(K, np.nan), np.full(K, np.nan)
    conv = np.zeros(K, bool)
    tol_used = np.full((K, 3), np.nan)
    for k in range(1, K):
        (d_period[k], d_amp[k], d_shape[k]), tol_used[k], conv[k] = compare(k - 1, k)
    # trailing run of converged comparisons between the cycles clear of missing frames (a
    # tracked movie's failed frames), each with the one before it clear of them, across a gap
    # if need be (a change hidden in the gap shows there)
    clear = np.nonzero(~(_frame_gaps(starts, t, GAP_MARGIN) > MAX_GAP) & ~merged)[0]
    run, k_run = 0, K
    for i in range(clear.size - 1, 0, -1):
        j, k = int(clear[i - 1]), int(clear[i])
        ok = conv[k] if j == k - 1 else compare(j, k)[2]
        if not ok:
            break
        run, k_run = run + 1, k
    limit = run >= n_consecutive
    # the first converged cycle of the run is compared with its (unconverged) predecessor:
    # the limit cycle starts at that cycle
    lc_time = float(starts[k_run]) if limit else math.nan
    transient = lc_time - float(t[0]) if limit else math.nan

    # onset time and growth rate from the amplitude envelope
    mids = 0.5 * (starts[1:] + starts[:-1]) if K else np.empty(0)
    onset = math.nan
    rate = rate_err = math.nan
    win = (math.nan, math.nan)
    growth_note = ""
    # a quiet stretch before the first cycle: the filament at rest or its stroke under the
    # noise (the section finds no crossings there); the onset is in it, or at the record start
    quiet = K >= 1 and float(starts[0] - t[0]) > 1.5 * W
    if K >= 1:
        a_final = float(np.median(amps[-min(K, max(n_consecutive, 3)) :]))
        r_final = float(np.median(ramps[-min(K, max(n_consecutive, 3)) :]))
        # still growing at the record's end (the last two cycles each grow by more than 10 %,
        # at over 0.8 of the record's fastest growth): the final amplitude is not in the
        # record, so neither is the onset, and the growth fit has no cut from above.
        # Cycles within a period of the record's ends are left out of both: the body axis is
        # extrapolated over the last half period and the running mean's window reaches half a
        # period further, which biases a growing stroke's amplitude there
        inner = (starts[:-1] >= t[0] + W) & (starts[1:] <= t[-1] - W)
        ok = (ramps > 3.0 * noise_amp) & (ramps > 0) & inner
        growing = False
        if not limit and np.count_nonzero(ok) >= 3 and np.all(ok[np.nonzero(inner)[0][-3:]]):
            lg = np.diff(np.log(np.where(ok, ramps, 1.0)))[ok[1:] & ok[:-1]]
            growing = lg.size >= 2 and bool(np.all(lg[-2:] > max(0.1, 0.8 * float(np.max(lg)))))
            # and the stroke was never larger before: a saturated stroke whose amplitude is
            # modulated (rising at the record's end) is not growing out of its onset
            k_last = int(np.nonzero(ok)[0][-1])
            growing = growing and bool(np.all(ramps[:k_last] < ramps[k_last]))
            # and the cycles of the last period (left out of the fit: biased, but not by half)
            # do not show the growth slowing to under half its fastest: the record ends in the
            # saturation, its linear growth hidden under the noise
            tail = ramps[k_last:]
            if growing and tail.size >= 2 and np.all(tail > 3.0 * noise_amp[k_last:]):
                growing = bool(np.all(np.diff(np.log(tail)) > 0.5 * float(np.max(lg))))
        if growing:
            # no final amplitude to cut at
            r_final = math.inf
        # the fit keeps to cycles whose stroke is still within the linear regime: its
        # tangent-angle deflection, theta_amp, at most _LINEAR_ANGLE (a tenth of the final
        # lateral amplitude is far beyond it: the simulated stroke's lateral amplitude grows
        # 3-13 % faster than the linear rate there, its deflection 0.2-0.5 rad)
        onset_ok = ok.copy()
        ok &= theta_amp <= _LINEAR_ANGLE
        cut = fit_max_fraction * r_final
        above = np.nonzero(amps >= onset_fraction * a_final)[0] if not growing else np.empty(0, int)
        if above.size:
            k = int(above[0])
            if k == 0 and quiet:
                onset = _envelope_onset(t, d, var, W, float(starts[max(K - 3, 0)]), float(starts[K]), onset_fraction)
            elif k == 0:
                onset = float(t[0])
            else:
                la, lb = math.log(amps[k - 1]), math.log(amps[k])
                lt = math.log(onset_fraction * a_final)
                frac = (lt - la) / (lb - la) if lb != la else 0.0
                onset = float(mids[k - 1] + frac * (mids[k] - mids[k - 1]))
        if fit_after is None:
            tau = tr.tau
            # the first cycles carry the initial condition's transient, unless a quiet
            # stretch held it (a stroke growing out of the noise); where the source knows tau,
            # two relaxation times after the record start or, after a quiet stretch longer
            # than that (the field switched on late), after its first cycle
            # (a noisy record's quiet stretch may hide a stroke growing since the record start,
            # whose first cycle is where it leaves the noise: there, where two tau after that
            # cycle leave too few cycles to fit, the fit starts two tau after the record start)
            if tau is None:
                t_after = float(t[0]) if quiet else float(starts[min(2, K)])
            elif quiet and starts[0] > t[0] + 2.0 * tau:
                t_after = float(starts[0]) + 2.0 * tau
                clean = math.sqrt(float(var[0])) < 1e-6 * float(np.max(ramps))
                if not clean and not _enough(_before_cut((mids >= t_after) & (ramps <= cut) & ok, ramps, cut),
                                             ramps, noise_amp):
                    t_after = float(t[0]) + 2.0 * tau
            else:
                t_after = float(t[0]) + 2.0 * tau
        else:
            t_after = float(t[0]) + float(fit_after)
        # cycles above 3 noise sigma, away from the ends, below the cut
        sel = _before_cut((mids >= t_after) & (ramps <= cut) & ok, ramps, cut)
        if _enough(sel, ramps, noise_amp):
            # the start's transient (the other modes, beating with the leading one) may outlast
            # two relaxation times: the fit starts at the cycle that leaves the smallest standard
            # error, misfit included (early cycles off the line are dropped, not averaged in)
            idx = np.nonzero(sel)[0]
            best = (math.inf, math.nan, 0)
            for i in range(idx.size):
                sub = np.zeros_like(sel)
                sub[idx[i:]] = True
                if not _enough(sub, ramps, noise_amp):
                    break
                r, e = _log_linear_rate(mids[idx[i:]], np.log(ramps[idx[i:]]))
                if i == 0 or e < best[0]:
                    best = (e, r, i)
            rate_err, rate, i0 = best
            win = (float(mids[idx[i0]]), float(mids[idx[-1]]))
        elif _enough(_before_cut((mids >= t_after) & (ramps <= cut) & onset_ok, ramps, cut), ramps, noise_amp):
            # the onset's cycles would hold a fit, but not within the linear regime: no rate
            # (beyond it the rate is biased far beyond its scatter)
            n_lin = int(np.count_nonzero(sel))
            growth_note = (
                f"growth rate not measured: {n_lin} cycle{'s' if n_lin != 1 else ''} of the onset "
                f"{'lie' if n_lin != 1 else 'lies'} clear of its start's transient (after t = {t_after:.3g} s), "
                f"above the noise and within the linear regime (the stroke's tangent-angle deflection at most "
                f"{_LINEAR_ANGLE:g} rad), fewer than the 4 (3 far above the noise) a fit needs; beyond that "
                "regime the envelope no longer grows at the linear rate (a start closer to straight, or less "
                "noise, leaves more such cycles)")
    return Cycles(
        starts=starts,
        periods=periods,
        amplitudes=amps,
        d_period=d_period,
        d_amplitude=d_amp,
        d_shape=d_shape,
        converged=conv,
        limit_cycle=bool(limit),
        limit_cycle_time=lc_time,
        onset_time=onset,
        transient_duration=transient,
        growth_rate=rate,
        growth_rate_stderr=rate_err,
        growth_fit_window=win,
        axis_angle=ax_angle,
        section_t=t,
        section_signal=u,
        tol=float(tol),
        tip=itip,
        tol_used=tol_used,
        growth_note=growth_note,
        merged=merged,
    )
