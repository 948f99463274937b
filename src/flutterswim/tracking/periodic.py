"""A settled stroke is periodic in the body's own frame: one shape template for all cycles.

The tracked centrelines of a settled stroke repeat, cycle after cycle, up to a rigid motion
(the swimmer advances, and may turn steadily). :func:`periodic_shape` uses that:

1. each good frame's 49 samples are put into a body frame (rigid motion removed) and every
   sample's two body-frame coordinates are fitted by one Fourier series in the stroke's
   phase over all cycles (``harmonics``; the period in frames refined by least squares
   around :func:`~flutterswim.tracking.temporal.frames_per_stroke`): the *template*, about
   sqrt(n_frames / (2 H + 1)) less noisy than one frame;
2. each frame's rigid motion is fitted to its own measured curve: the normal distances of
   the body's samples (all but ``end_samples`` at each end) to the template placed in the
   frame, plus ``end_weight`` times the misfit of the two measured ends (weight about
   (0.17 / 0.45)^2, the ratio of a body sample's noise across the curve to a tip's, at SNR 3).
   The normal distances leave the template free to slide along the curve, so the ends'
   position along the body comes from the template (averaged over the cycles) and the
   measured ends only, not from the samples' correspondence;
3. steps 1-2 are repeated (``iterations``); each frame becomes the template of its phase in
   its own rigid placement. Per-frame rigid motion is never smoothed in time;
4. mirror symmetry: a swimmer whose field lies along its mean axis strokes symmetrically, the
   stroke reflected across the axis being the stroke half a period later. In the body frame
   the along-body coordinate then holds only the constant and even harmonics and the
   across-body coordinate only odd ones, half the coefficients. The symmetric template is
   used unless the data reject it (nested F test of the full template against it: ``max_f``
   and ``floor_px``): a stroke made asymmetric (a field tilted from the
   swimmer's axis, a bent body) keeps the full template;

This is only valid for a periodic movie. :func:`periodic_shape` therefore refuses (returns
the input, with the reason) unless the good frames span at least ``min_cycles`` strokes (2.5: a movie
rendered with "3 cycles" of frames spans 2.97; on the paper's stroke at SNR 3, 57 frames, the template
gave the period, advance and both ends' lateral p2p 0.07, 0.23, 0.70, 0.26 % RMS from the truth over 8
movies, the frames alone 0.38, 0.51, 1.06, 0.34 %; 49 frames, 0.14, 0.23, 0.64, 0.22 % against 0.66,
0.49, 0.46, 0.51 %), and the
template passes a drift test: the same template with its coefficients changing linearly in time
must not fit significantly better (F statistic of the nested fit <= ``max_drift_f``, or its
systematic part below ``floor_px`` RMS). The samples along a tracked body are correlated, so
the statistic spreads wider than its nominal F distribution: on 16 movies of the settled stroke
at SNR 3 it was 0.27-3.18 (one over the 3 this test had used, whose movie then lost its
template and had 0.53 px tip error instead of 0.17 px), while the onsets and drifts that must
be refused gave 7.1 or more (34 frames) and 15 or more (51 frames and over); hence 5. The drift model has at most half as many coefficients per
coordinate as there are frames: the drift of all H harmonics from 2 (2 (2 H + 1)) frames (52 for
6 harmonics), of the constant and harmonics 1..H_d only on fewer (as at a lower frame rate:
the paper's stroke at 25 fps gives 51 frames in 5.4 strokes), and no template below
2 (2 H + 4) frames. The harmonics are not limited by the frame rate's Nyquist limit: a stroke
period that is not a whole number of frames samples every phase over the cycles. A stroke still
growing (onset), an unsteady turn or a changing stroke fails the drift test and is left to the
per-frame estimates. Because the F statistic is relative to the residual, a stroke changed
abruptly (the field turned within the movie) can pass it while the template misses every frame
by pixels: the template is also refused when it misses the frames by more than
``max_residual_px`` (median over frames of a frame's RMS distance to it; 0.13-0.28 px on the
settled stroke at SNR 5-3, 1.6 px after a 2 degree turn of the field), or one frame by more than
``max_frame_ratio`` times that (3-5 times on the settled stroke). A body at rest (below the
threshold, or trapped in a bent equilibrium) has no stroke: its frames' noise picks a period of
a few frames, and a template at it is refused unless it fits significantly better than one
static shape (F >= ``min_stroke_f``). None of these compares the template's misfit with the
frames' own noise, and a swimmer turning slowly (the field rotating 2-10 degrees per second) passes
them all while the template misses it by more than the frames' noise (0.12-0.44 px across the
body without noise, against 0.004 px on the settled stroke): the template is also refused when
its misfit across the body that changes smoothly from frame to frame exceeds the frames' own
noise (``max_smooth_ratio`` times it, and ``smooth_floor_px``). The frames' noise across the body
is independent from one frame to the next, so it comes from the residuals' differences between
consecutive frames; what the differences cancel is the smooth misfit (:func:`_aperiodic_misfit`;
the settled stroke tracked at SNR 3-10: none, 0 px on 24 movies; a turn of 2-5 degrees per
second: 1.6-4.3 times the noise at SNR 6 and without noise, where the frames' own estimates were
1.6-9 times closer to the true centreline than the template).

On the paper's settled stroke rendered at SNR 3 (50 fps, 14 um/px, 5.3 cycles) the tip error
falls from 0.46-0.57 px RMS to about 0.2 px (0.19 px over 16 movies) and the centreline error
halves; without noise the result moves by < 0.01 px (benchmarks/RESULTS.md).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["periodic_shape", "periodic_shape_flagging", "fourier_basis"]

_J = np.array([[0.0, -1.0], [1.0, 0.0]])


def fourier_basis(phase: np.ndarray, harmonics: int) -> np.ndarray:
    """(n, 2 H + 1) columns 1, cos(2 pi h phase), sin(2 pi h phase), h = 1..H."""
    a = np.outer(np.asarray(phase, float), 2.0 * np.pi * np.arange(1, harmonics + 1))
    return np.hstack([np.ones((a.shape[0], 1)), np.cos(a), np.sin(a)])


def _symmetric_columns(harmonics: int) -> tuple[np.ndarray, np.ndarray]:
    """Columns of :func:`fourier_basis` kept by a stroke symmetric under reflection across its
    axis with a half-period shift: the constant and even harmonics along the body, odd
    harmonics across it."""
    h = np.concatenate([[0], np.arange(1, harmonics + 1), np.arange(1, harmonics + 1)])
    return h % 2 == 0, h % 2 == 1


def _fit(U: np.ndarray, B: np.ndarray, symmetric: bool) -> np.ndarray:
    """The least-squares template B coef of the body-frame coordinates U (n, 2P) (columns x, y
    of each sample); ``symmetric``: along-body (x) columns by the even, across (y) by the odd
    harmonics only."""
    if not symmetric:
        coef, *_ = np.linalg.lstsq(B, U, rcond=None)
        return B @ coef
    even, odd = _symmetric_columns((B.shape[1] - 1) // 2)
    out = np.empty_like(U)
    for cols, sel in ((slice(0, None, 2), even), (slice(1, None, 2), odd)):
        coef, *_ = np.linalg.lstsq(B[:, sel], U[:, cols], rcond=None)
        out[:, cols] = B[:, sel] @ coef
    return out


def _initial_frames(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per frame: centroid (n, 2) and rotation (n, 2, 2) whose first axis runs from the mean of
    the first half of the samples to that of the second half."""
    c = pts.mean(axis=1)
    h = pts.shape[1] // 2
    d = pts[:, h:].mean(axis=1) - pts[:, :h].mean(axis=1)
    a = np.arctan2(d[:, 1], d[:, 0])
    ca, sa = np.cos(a), np.sin(a)
    R = np.stack([np.stack([ca, -sa], -1), np.stack([sa, ca], -1)], -2)
    return c, R


def _to_body(pts: np.ndarray, c: np.ndarray, R: np.ndarray) -> np.ndarray:
    """(n, 2P) body-frame coordinates: R^T (p - c) for every sample."""
    return np.einsum("npk,nkj->npj", pts - c[:, None, :], R).reshape(pts.shape[0], -1)


def _place(tmpl: np.ndarray, c: np.ndarray, R: np.ndarray) -> np.ndarray:
    """(n, P, 2) template placed by the rigid motions: c + R t."""
    return c[:, None, :] + np.einsum("nij,npj->npi", R, tmpl)


def _register(pts: np.ndarray, tmpl: np.ndarray, c: np.ndarray, R: np.ndarray, end_weight: float,
              end_samples: int, steps: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Newton for each frame's rigid motion (see the module docstring, step 2)."""
    n, P, _ = pts.shape
    mid = slice(end_samples, P - end_samples)
    w = math.sqrt(end_weight)
    for _ in range(steps):
        q = _place(tmpl, c, R)
        tg = np.gradient(q, axis=1)
        tg /= np.maximum(np.linalg.norm(tg, axis=2, keepdims=True), 1e-12)
        nrm = tg @ _J.T
        dq = (q - c[:, None, :]) @ _J.T  # d q / d theta
        nm, dqm = nrm[:, mid], dq[:, mid]
        # rows: normal distances of the body's samples (theta, cx, cy)
        A1 = np.stack([np.sum(nm * dqm, axis=2), nm[..., 0], nm[..., 1]], -1)
        b1 = np.sum(nm * (pts[:, mid] - q[:, mid]), axis=2)
        # rows: both ends, both coordinates, weighted
        ends = [0, P - 1]
        e = np.eye(2)
        A2 = np.concatenate([np.stack([dq[:, j, k], np.full(n, e[k, 0]), np.full(n, e[k, 1])], -1)[:, None]
                             for j in ends for k in (0, 1)], axis=1) * w
        b2 = np.stack([pts[:, j, k] - q[:, j, k] for j in ends for k in (0, 1)], -1) * w
        A = np.concatenate([A1, A2], axis=1)
        b = np.concatenate([b1, b2], axis=1)
        AtA = np.einsum("nmi,nmj->nij", A, A)
        Atb = np.einsum("nmi,nm->ni", A, b)
        d = np.linalg.solve(AtA, Atb[..., None])[..., 0]
        ct, st = np.cos(d[:, 0]), np.sin(d[:, 0])
        Rd = np.stack([np.stack([ct, -st], -1), np.stack([st, ct], -1)], -2)
        # rotation about c (the linearisation above), then the translation
        R = Rd @ R
        c = c + d[:, 1:]
    return c, R


def _rss(U: np.ndarray, B: np.ndarray) -> float:
    coef, *_ = np.linalg.lstsq(B, U, rcond=None)
    return float(np.sum((U - B @ coef) ** 2))


def _refine_period(U: np.ndarray, frame: np.ndarray, period0: float, harmonics: int) -> float:
    """The period [frames] minimising the residual of the periodic fit: a grid over +-4 %
    around ``period0``, then a bounded scalar search around the best grid point."""
    from scipy.optimize import minimize_scalar

    def rss(p: float) -> float:
        return _rss(U, fourier_basis(frame / p, harmonics))

    grid = period0 * np.linspace(0.96, 1.04, 33)
    k = int(np.argmin([rss(p) for p in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    return float(minimize_scalar(rss, bounds=(lo, hi), method="bounded", options={"xatol": 1e-6 * period0}).x)


def periodic_shape(X: np.ndarray, Y: np.ndarray, ok: np.ndarray, period_frames: float, *, harmonics: int = 6,
                   iterations: int = 3, end_weight: float = 0.15, end_samples: int = 3, min_cycles: float = 2.5,
                   max_f: float = 3.0, floor_px: float = 0.02, symmetric: bool = True,
                   max_drift_f: float = 5.0,
                   max_residual_px: float = 1.0, max_frame_ratio: float = 8.0, min_stroke_f: float = 10.0,
                   max_smooth_ratio: float = 1.0, smooth_floor_px: float = 0.03,
                   positions: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
    """The periodic template of a settled stroke placed in every good frame (module docstring).

    X, Y (T, P) [px], equal arc-length samples, NaN on frames not ``ok``; period_frames: the
    stroke's period estimate [frames]; symmetric: use the mirror symmetry of the stroke when
    the data do not reject it (module docstring, step 4; max_f: its F test); max_drift_f: the
    drift test's F (module docstring); max_residual_px, max_frame_ratio: the
    template is refused when it misses the frames by more than max_residual_px (median over
    frames of each frame's RMS distance to it), or one frame by more than max_frame_ratio times
    that median and max_residual_px (a stroke changed by a turn of the field: the drift test's
    F statistic, relative to the residual, can miss it); min_stroke_f: the template is refused
    unless it fits significantly better than one static shape (F of the nested fit; a body at
    rest); max_smooth_ratio, smooth_floor_px: the template is refused when its misfit across the
    body that changes smoothly from frame to frame exceeds max_smooth_ratio times the frames' own
    noise across it and smooth_floor_px (a slowly turning swimmer; :func:`_aperiodic_misfit`); positions: (T,) each frame's time in frame intervals (a camera's timestamps: a dropped
    frame leaves a step of 2), default its index. Returns (X, Y, info): info["done"]
    (bool), info["reason"] (why not, or a summary), and when tested "period_frames",
    "harmonics", "drift_harmonics", "drift_f", "drift_px" (the systematic part of the drift
    model's improvement, RMS over samples), "residual_px", "frame_residual_px" (median over
    frames), "frame_residual_max_px", "end_residual_px" (each end's residual per coordinate, [s = 0,
    s = l]), "template_frames", "stroke_f", "smooth_misfit_px", "frame_noise_px" (the misfit's
    smooth part and the frames' noise, across the body, RMS), "symmetric", "symmetry_f" and
    "symmetry_px"."""
    ok = np.asarray(ok, bool)
    idx = np.nonzero(ok)[0]
    pos = np.arange(ok.size, dtype=float) if positions is None else np.asarray(positions, float)
    info: dict = {"done": False, "reason": ""}
    H = int(harmonics)
    if not (math.isfinite(period_frames) and period_frames > 0):
        info["reason"] = "not done: no stroke period found"
        return X, Y, info
    span = (pos[idx[-1]] - pos[idx[0]]) / period_frames if idx.size else 0.0
    if span < min_cycles:
        info["reason"] = f"not done: the good frames span {span:.1f} strokes (needs >= {min_cycles:g})"
        return X, Y, info
    # the drift model: the template's 2 H + 1 coefficients plus linear drifts of its constant and
    # first H_d harmonics, at most half as many coefficients as frames (H_d = H from 52 frames
    # for 6 harmonics; fewer frames, as at a lower frame rate, test the drift of the low harmonics)
    H_d = min(H, (idx.size // 2 - (2 * H + 1) - 1) // 2)
    if H_d < 1:
        need = 2 * (2 * H + 4)
        info["reason"] = f"not done: {idx.size} good frames, too few for {H} harmonics (needs >= {need})"
        return X, Y, info
    pts = np.stack([X[idx], Y[idx]], -1)  # (n, P, 2)
    n, P, _ = pts.shape
    frame = pos[idx] - pos[idx[0]]
    c, R = _initial_frames(pts)
    U = _to_body(pts, c, R)
    period = _refine_period(U, frame, float(period_frames), H)
    B = fourier_basis(frame / period, H)

    def settle(pts: np.ndarray, c: np.ndarray, R: np.ndarray, sym: bool):
        for _ in range(iterations + 1):
            tmpl = _fit(_to_body(pts, c, R), B, sym).reshape(n, P, 2)
            c, R = _register(pts, tmpl, c, R, end_weight, end_samples)
        return c, R

    c, R = settle(pts, c, R, False)
    U = _to_body(pts, c, R)
    res = U - _fit(U, B, False)
    rss0 = float(np.sum(res**2))
    # each frame's RMS distance to the template at its phase [px]
    e_frame = np.sqrt(np.sum(res**2, axis=1) / P)
    e_med, k_max = float(np.median(e_frame)), int(np.argmax(e_frame))
    tau = (2.0 * frame / max(frame[-1], 1.0) - 1.0)[:, None]
    drift = np.r_[0, 1:H_d + 1, H + 1:H + H_d + 1]  # columns 1, cos and sin of harmonics 1..H_d
    B1 = np.hstack([B, B[:, drift] * tau])
    rss1 = _rss(U, B1)
    dof = n - B1.shape[1]
    f_stat = ((rss0 - rss1) / drift.size) / (rss1 / dof) if rss1 > 0 else math.inf
    drift_px = math.sqrt(max(rss0 - rss1, 0.0) / (n * P))
    # a stroke at all: the template must fit far better than one static shape (a body at rest
    # gives F of about 1; the settled stroke at SNR 3, about 10^4)
    rss_static = float(np.sum((U - U.mean(axis=0)) ** 2))
    f_stroke = (((rss_static - rss0) / (2 * P * (B.shape[1] - 1))) / (rss0 / (2 * P * (n - B.shape[1])))
                if rss0 > 0 else math.inf)
    # each end's residual per coordinate [px] over the n frames: the noise that the template's
    # harmonic coefficients there carry (standard error about it x sqrt(2 / n)), which every
    # cycle shares, so that a test across cycles cannot see it (analysis.descriptors)
    end_res = [float(np.sqrt(np.mean(res.reshape(n, P, 2)[:, i, :] ** 2))) for i in (0, P - 1)]
    smooth_px, noise_px = _aperiodic_misfit(res.reshape(n, P, 2), (U - res).reshape(n, P, 2), frame)
    info.update(period_frames=period, harmonics=H, drift_harmonics=H_d, drift_f=float(f_stat), drift_px=drift_px,
                end_residual_px=end_res, template_frames=int(n),
                residual_px=math.sqrt(rss0 / (n * P)), frame_residual_px=e_med,
                frame_residual_max_px=float(e_frame[k_max]), stroke_f=float(f_stroke),
                smooth_misfit_px=smooth_px, frame_noise_px=noise_px)
    if not (f_stat <= max_drift_f or drift_px <= floor_px):
        info["reason"] = (f"not done: the stroke is not periodic (a drifting template fits better: F = {f_stat:.3g} "
                          f"> {max_drift_f:g}, {drift_px:.3f} px > {floor_px:g} px)")
        return X, Y, info
    if e_med > max_residual_px:
        info["reason"] = (f"not done: the stroke is not periodic (the template misses the frames by {e_med:.2f} px, "
                          f"median over frames, > {max_residual_px:g} px)")
        return X, Y, info
    if e_frame[k_max] > max(max_frame_ratio * e_med, max_residual_px):
        info["reason"] = (f"not done: the stroke is not periodic (frame {int(idx[k_max])} is {e_frame[k_max]:.2f} px "
                          f"from the template, median {e_med:.2f} px)")
        info["outlier_frame"] = int(idx[k_max])
        return X, Y, info
    if f_stroke < min_stroke_f:
        info["reason"] = (f"not done: no stroke (the periodic template fits the body no better than one static "
                          f"shape: F = {f_stroke:.3g} < {min_stroke_f:g})")
        return X, Y, info
    if smooth_px > max(max_smooth_ratio * noise_px, smooth_floor_px):
        info["reason"] = (f"not done: the stroke is not periodic (the template misses the frames across the body by "
                          f"{smooth_px:.3f} px RMS that change smoothly from frame to frame, more than the frames' own "
                          f"noise, {noise_px:.3f} px: a drifting or turning stroke, better tracked frame by frame)")
        return X, Y, info
    # the mirror symmetry: the full template must not fit significantly better (nested F)
    rss_sym = float(np.sum((U - _fit(U, B, True)) ** 2))
    even, odd = _symmetric_columns(H)
    extra = P * (2 * B.shape[1] - int(even.sum()) - int(odd.sum()))
    f_sym = ((rss_sym - rss0) / extra) / (rss0 / (n * 2 * P - 2 * P * B.shape[1])) if rss0 > 0 else math.inf
    sym_px = math.sqrt(max(rss_sym - rss0, 0.0) / (n * P))
    sym = bool(symmetric and (f_sym <= max_f or sym_px <= floor_px))
    info.update(symmetric=sym, symmetry_f=float(f_sym), symmetry_px=sym_px)
    if sym:
        c, R = settle(pts, c, R, True)
    tmpl = _fit(_to_body(pts, c, R), B, sym).reshape(n, P, 2)
    c, R = _register(pts, tmpl, c, R, end_weight, end_samples)
    q = _place(tmpl, c, R)
    info["end_coef_stderr_px"] = [_coef_stderr(pts[:, i, :] - q[:, i, :], B.shape[1]) for i in (0, P - 1)]
    Xo, Yo = X.copy(), Y.copy()
    Xo[idx], Yo[idx] = q[..., 0], q[..., 1]
    info["done"] = True
    info["reason"] = (f"done: period {period:.3f} frames, {H} harmonics{', mirror-symmetric' if sym else ''}, "
                      f"drift F = {f_stat:.2f}, symmetry F = {f_sym:.2f}, residual {info['residual_px']:.3f} px")
    return Xo, Yo, info


def _aperiodic_misfit(res: np.ndarray, fit: np.ndarray, frame: np.ndarray) -> tuple[float, float]:
    """(smooth, noise) parts [px, RMS] of the template's residuals across the body: res and fit
    (n, P, 2) the residuals and the template in the body frame, frame (n,) the frames' positions.
    The residual's normal component (a slide along the body, as the ends' smoothed placement makes,
    is not a change of shape) is split by its differences between consecutive frames: the
    frames' own noise, independent from one frame to the next across the body, doubles in them
    (its mean square is half theirs), while a misfit that changes smoothly in time (a stroke that
    drifts or turns: the shape changes over strokes, not frames) cancels from them; the smooth part
    is the rest of the residual's mean square. (nan, nan) without consecutive frames."""
    tg = np.gradient(fit, axis=1)
    tg /= np.maximum(np.linalg.norm(tg, axis=2, keepdims=True), 1e-12)
    rn = np.sum(res * (tg @ _J.T), axis=2)
    k = np.nonzero(np.abs(np.diff(frame) - 1.0) < 0.5)[0]
    if k.size == 0:
        return math.nan, math.nan
    noise2 = 0.5 * float(np.mean((rn[k + 1] - rn[k]) ** 2))
    return math.sqrt(max(float(np.mean(rn**2)) - noise2, 0.0)), math.sqrt(noise2)


def _coef_stderr(d: np.ndarray, m: int, lags: int = 3) -> float:
    """Standard error [px] of one harmonic coefficient of a template fitted with m coefficients
    per coordinate to n frames, from the measured point's distances d (n, 2) to the placed
    template: its variance per coordinate with the m fitted coefficients' degrees of freedom,
    times the long-run factor 1 + 2 sum_k (1 - k / (lags + 1)) rho_k of its correlation from
    frame to frame (Bartlett weights; an end's along-body position is smoothed over frames, and
    its lag-1 correlation is about 0.2 at SNR 3), never below 1, over n / 2. The factor is the
    noise's at zero frequency, for every harmonic: at a lag-1 correlation of 0.4 it is right for
    the 1st harmonic (Monte Carlo, test) and 26 % high for the 5th of a stroke of 18.9 frames."""
    n = d.shape[0]
    if n <= m + lags:
        return math.nan
    d = d - d.mean(axis=0)
    g0 = float(np.sum(d * d))
    if g0 <= 0:
        return 0.0
    rho = [float(np.sum(d[k:] * d[:-k])) / g0 for k in range(1, lags + 1)]
    f = max(1.0, 1.0 + 2.0 * sum((1.0 - k / (lags + 1)) * r for k, r in enumerate(rho, 1)))
    var = g0 / (2 * (n - m))
    return math.sqrt(2.0 * var * f / n)


#: most frames in one run (within 2 frames of each other) that the template may flag as outliers
#: (a speck of dust on the end's path, as bright as the line, joined it in 2 frames: the template
#: was refused for the whole movie and the advance read 1.8 % long); a run of 3 or more is taken
#: for a transient of the stroke, which must not be hidden: the template is refused
MAX_OUTLIER_RUN = 2


def periodic_shape_flagging(X: np.ndarray, Y: np.ndarray, ok: np.ndarray, reason: list, period_frames: float,
                            max_fraction: float = 0.05, **kw) -> tuple[np.ndarray, np.ndarray, dict]:
    """:func:`periodic_shape`, where a few frames (lone, or in short runs) far from an otherwise accepted template
    (more than ``max_frame_ratio`` times the median frame's distance) are flagged instead of
    refusing the template for the whole movie: each such frame (at most ``max_fraction`` of
    the good frames, at least one; runs of at most :data:`MAX_OUTLIER_RUN` frames within 2 of each
    other) gets ok False and the reason "template outlier: ...", and
    the template is fitted again without it. ``ok`` and ``reason`` are updated in place;
    info["outliers"] lists the frames flagged. (A long body whose trailing end curls close to
    itself once a stroke gives such a frame in each: with one allowed per 100 frames the template
    was refused and the tips were 0.8-1.0 px off; 5 % takes one a stroke at 20 frames a stroke.)"""
    flagged: list[int] = []
    n_max = max(1, int(max_fraction * np.count_nonzero(ok)))
    X0, Y0 = X, Y
    while True:
        Xp, Yp, info = periodic_shape(X, Y, ok, period_frames, **kw)
        k = info.pop("outlier_frame", None)
        # short runs only (a speck of dust the end passes over spoils 2-3 frames; a longer run is a
        # transient of the stroke): the flagged frames within 2 of k and of each other, with k
        if info["done"] or k is None:
            break
        run = {k}
        while True:
            more = {f for f in flagged if f not in run and any(abs(f - g) <= 2 for g in run)}
            if not more:
                break
            run |= more
        if len(flagged) >= n_max or len(run) > MAX_OUTLIER_RUN:
            break
        ok[k] = False
        reason[k] = (f"template outlier: {info['frame_residual_max_px']:.2f} px RMS from the periodic stroke that "
                     f"fits the other frames (median {info['frame_residual_px']:.2f} px)")
        X, Y = X.copy(), Y.copy()
        X[k] = Y[k] = np.nan
        flagged.append(k)
    if flagged and not info["done"]:  # refused all the same: every frame keeps its own estimate
        for k in flagged:
            ok[k], reason[k] = True, ""
        return X0, Y0, {**info, "outliers": []}
    info["outliers"] = flagged
    if flagged:
        info["reason"] += f"; {len(flagged)} frame(s) flagged as template outliers"
    return Xp, Yp, info
