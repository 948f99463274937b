"""Tip refinement by a least-squares fit of the line-end model to the raw pixels.

Near an end the image of a PSF-blurred line is, in curvilinear coordinates (q along the
centreline and its tangent extension, d across it)::

    mu(q, d) = b + A exp(-d^2 / (2 sigma^2)) Phi((q_end - q) / sigma)

(Phi the normal CDF; exact for a straight end, accurate while the radius of curvature is
much larger than sigma). The four parameters (q_end, sigma, A, b) are fitted to the raw
pixels with |d| <= 3 sigma and q_end - ``inner`` <= q <= q_end + ``outer`` by variable
projection (A and b linear), less the frame's background plane
(:func:`~flutterswim.tracking.segment.background_plane`): under a background rising along
the body by 2.5 % of the line's height per px, a constant b moved the ends 0.3-0.6 px towards
the brighter side. This uses all the light near the end, not one sampled line:
for Gaussian noise its spread is close to the Cramér-Rao bound sqrt(2) / SNR px.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import make_interp_spline

from .segment import background_plane

__all__ = ["refine_tips", "resample", "end_span"]


def _arclength(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])


def _curve(x: np.ndarray, y: np.ndarray):
    s = _arclength(x, y)
    k = 3 if s.size >= 4 else 1
    return s, make_interp_spline(s, np.stack([x, y], -1), k=k)


def _points(spl, s_end: float, q: np.ndarray) -> np.ndarray:
    """(M, 2) points at parameters q; linear continuation by the end tangents outside [0, s_end]."""
    qc = np.clip(q, 0.0, s_end)
    p = spl(qc)
    tan = spl.derivative()(qc)
    tan /= np.maximum(np.hypot(tan[:, 0], tan[:, 1]), 1e-12)[:, None]
    return p + (q - qc)[:, None] * tan


def _fit_end(img: np.ndarray, spl, s_end: float, q0: float, outward: int, sigma0: float,
             inner: float, outer: float, pivot: float, saturation: float | None = None,
             plane: np.ndarray | None = None) -> tuple[float, float, float]:
    """Fitted end parameter q_end (same parametrisation as ``spl``), sigma and the bend c
    about the hinge at q0 - outward * pivot; NaN if the fit fails. ``outward`` = +1 for the s_end end, -1 for the s = 0 end."""
    H, W = img.shape
    # dense polyline of the curve near the end (the inner part and the tangent extension)
    lo, hi = (q0 - inner - 4, q0 + outer + 4) if outward > 0 else (q0 - outer - 4, q0 + inner + 4)
    qq = np.arange(lo, hi + 1e-9, 0.25)
    P = _points(spl, s_end, qq)
    r = int(math.ceil(3 * sigma0 + 1))
    c0, c1 = int(max(math.floor(P[:, 0].min()) - r, 0)), int(min(math.ceil(P[:, 0].max()) + r + 1, W))
    r0, r1 = int(max(math.floor(P[:, 1].min()) - r, 0)), int(min(math.ceil(P[:, 1].max()) + r + 1, H))
    if c1 - c0 < 3 or r1 - r0 < 3:
        return math.nan, math.nan, 0.0
    yy, xx = np.mgrid[r0:r1, c0:c1]
    px, py = xx.ravel().astype(float), yy.ravel().astype(float)
    # nearest polyline point for each pixel: q, and signed distance d
    d2 = (px[:, None] - P[None, :, 0]) ** 2 + (py[:, None] - P[None, :, 1]) ** 2
    j = np.argmin(d2, axis=1)
    q = qq[j]
    T = _points(spl, s_end, qq + 0.01) - P
    T /= np.hypot(T[:, 0], T[:, 1])[:, None]
    # signed distance: positive to the left of the direction of increasing q
    d = (py - P[j, 1]) * T[j, 0] - (px - P[j, 0]) * T[j, 1]
    u = outward * (q - q0)
    sel = (np.abs(d) <= 3.0 * sigma0) & (u >= -inner) & (u <= outer) & (j > 0) & (j < qq.size - 1)
    v = img[r0:r1, c0:c1].ravel()
    if saturation is not None:  # clipped pixels: the light was at least that, not that
        sel &= v < saturation
    if np.count_nonzero(sel) < 30:
        return math.nan, math.nan, 0.0
    v = v[sel].astype(float)
    if plane is not None:  # the frame's background plane (refine_tips)
        v -= plane[r0:r1, c0:c1].ravel()[sel]
    q, d, u = q[sel], d[sel], u[sel]
    hinge = np.maximum(u + pivot, 0.0)

    return _levenberg_marquardt(q, d, hinge, v, q0, sigma0, outward)


def _levenberg_marquardt(q: np.ndarray, d: np.ndarray, h: np.ndarray, v: np.ndarray, q0: float,
                         sigma0: float, o: int, iters: int = 30) -> tuple[float, float, float]:
    """Least squares of v ~ b + A exp(-(d - c h)^2 / 2 sg^2) Phi(o (qe - q) / sg) over
    (qe, sg, c, A, b) by Levenberg-Marquardt with the analytic Jacobian; returns (qe, sg, c)
    or NaNs if the fit ends on the edge of the trust box (|qe - q0| < 6, sigma0/2 < sg < 2 sigma0)."""
    from scipy.special import ndtr

    def parts(p):
        qe, sg, c, A, b = p
        e = d - c * h
        E = np.exp(-0.5 * (e / sg) ** 2)
        z = o * (qe - q) / sg
        Ph = ndtr(z)
        ph = np.exp(-0.5 * z * z) / math.sqrt(2 * math.pi)
        r = b + A * E * Ph - v
        return e, E, z, Ph, ph, r

    # start: A, b linear at (q0, sigma0, 0)
    g = np.exp(-0.5 * (d / sigma0) ** 2) * ndtr(o * (q0 - q) / sigma0)
    (A0, b0), *_ = np.linalg.lstsq(np.stack([g, np.ones_like(g)], -1), v, rcond=None)
    p = np.array([q0, sigma0, 0.0, A0, b0])
    e, E, z, Ph, ph, r = parts(p)
    cost = float(r @ r)
    lam = 1e-3
    for _ in range(iters):
        qe, sg, c, A, b = p
        J = np.stack([A * E * ph * o / sg,
                      A * E * (Ph * e * e / sg**3 - ph * z / sg),
                      A * E * Ph * e * h / sg**2,
                      E * Ph, np.ones_like(v)], -1)
        JtJ, Jtr = J.T @ J, J.T @ r
        improved = False
        for _ in range(8):
            M = JtJ + lam * np.diag(np.diag(JtJ) + 1e-12)
            try:
                step = -np.linalg.solve(M, Jtr)
            except np.linalg.LinAlgError:
                lam *= 10
                continue
            pn = p + step
            if not (abs(pn[0] - q0) < 6.0 and 0.5 * sigma0 < pn[1] < 2.0 * sigma0 and abs(pn[2]) < 0.3):
                lam *= 10
                continue
            parts_n = parts(pn)
            cn = float(parts_n[-1] @ parts_n[-1])
            if cn < cost:
                p, (e, E, z, Ph, ph, r) = pn, parts_n
                done = abs(cost - cn) <= 1e-10 * cost or np.max(np.abs(step[:3])) < 1e-5
                cost, lam, improved = cn, max(lam / 10, 1e-9), True
                break
            lam *= 10
        if not improved or done:
            break
    qe, sg, c, A, b = (float(t) for t in p)
    if not (A > 0 and abs(qe - q0) < 5.99):
        return math.nan, math.nan, 0.0
    return qe, sg, c


def _fit_end_twice(img: np.ndarray, spl, s_end: float, q0: float, outward: int, sigma0: float,
                   inner: float, outer: float, pivot: float, saturation: float | None = None,
                   plane: np.ndarray | None = None) -> tuple[float, float, float]:
    """:func:`_fit_end`, and once more with the pixels re-centred on its result when that
    moved the end by more than 2 px (a skeleton tip may be several px short). Returns
    (q_end, c, hinge parameter)."""
    qe, _, c = _fit_end(img, spl, s_end, q0, outward, sigma0, inner, outer, pivot, saturation, plane)
    if saturation is not None and not np.isfinite(qe):
        # clipped so heavily that the unclipped pixels do not hold the end: fit them all
        return _fit_end_twice(img, spl, s_end, q0, outward, sigma0, inner, outer, pivot, None, plane)
    if np.isfinite(qe) and abs(qe - q0) > 2.0:
        q2, _, c2 = _fit_end(img, spl, s_end, qe, outward, sigma0, inner, outer, pivot, saturation, plane)
        if np.isfinite(q2):
            return q2, c2, qe - outward * pivot
    return qe, c, q0 - outward * pivot


def resample(x: np.ndarray, y: np.ndarray, q_a: float, q_b: float, n_points: int,
             bend: tuple[float, float] = (0.0, 0.0), hinge: tuple[float, float] = (0.0, 0.0)
             ) -> tuple[np.ndarray, np.ndarray]:
    """The curve through (x, y) (interpolating spline in arc length, continued by its end
    tangents) between parameters q_a < q_b, resampled at ``n_points`` equal arc-length steps.
    ``bend`` (c_a, c_b): each end rotated about its ``hinge`` parameter (h_a, h_b), the normal
    displacement growing as c (distance past the hinge) (the fitted hinge of the end model)."""
    s, spl = _curve(x, y)
    L = float(s[-1])
    qq = np.linspace(q_a, q_b, 8 * n_points)
    P = _points(spl, L, qq)
    T = _points(spl, L, qq + 0.01) - P
    T /= np.hypot(T[:, 0], T[:, 1])[:, None]
    disp = bend[0] * np.maximum(hinge[0] - qq, 0.0) + bend[1] * np.maximum(qq - hinge[1], 0.0)
    P = P + disp[:, None] * np.stack([-T[:, 1], T[:, 0]], -1)
    sa = _arclength(P[:, 0], P[:, 1])
    su = np.linspace(0.0, sa[-1], n_points)
    return np.interp(su, sa, P[:, 0]), np.interp(su, sa, P[:, 1])


# the end polynomial's span against the frame's ridge contrast (matched-filter ridge over the
# filtered noise's SD; about 2.4 x the renderer's peak SNR at 3, 2.2 x at 5): its bias and its
# noise trade. Fitted over 40 px the quartic misses a well-resolved end's curvature (noise-free,
# the stroke at 48 segments: leading end -0.29 % on the paper's, -0.49 % at 2 x threshold,
# -0.64 % at 20 um/px); over 20 px by -0.28..+0.05 %, but its scatter, and a noise-induced
# outward shift, grow: at SNR 3 (contrast ~7) the leading end's RMS over 6 strokes was 0.31-1.12 %
# at 40 px and 0.42-2.84 % at 20 px, at SNR 5 (contrast ~11) 0.42-0.70 % at 40 px (12 of 20 movies
# outside 0.5 %) and 0.22-0.83 % at 20 px (3 of 19): 40 px up to contrast 8, 20 px from 10.5,
# linear between (benchmarks/RESULTS.md, stop 31). The contrast is taken at the PSF of 1.2 px
# these were measured with: the ridge's noise across the line grows as sigma / contrast (the
# contrast of a line of peak SNR p is about p sqrt(sigma)), so a blurred frame counts as
# contrast x 1.2 / sigma (defocus to 1.92 px at SNR 5: contrast 9.4, as noisy as 5.9 in focus;
# over 20-25 px its tips were 0.33-0.38 px RMS and two frames flagged, over 40 px 0.23-0.26 px)
_SPAN_NOISY, _SPAN_CLEAN = 40.0, 20.0
_CONTRAST_NOISY, _CONTRAST_CLEAN = 8.0, 10.5
_SIGMA_REF = 1.2


def end_span(contrast: float, sigma: float = _SIGMA_REF) -> float:
    """The span [px] of the end polynomial for a frame of this ridge contrast and PSF sigma
    [px] (NaN contrast: the noisy span)."""
    c = contrast * _SIGMA_REF / sigma
    if not math.isfinite(c) or c <= _CONTRAST_NOISY:
        return _SPAN_NOISY
    f = min((c - _CONTRAST_NOISY) / (_CONTRAST_CLEAN - _CONTRAST_NOISY), 1.0)
    return _SPAN_NOISY + f * (_SPAN_CLEAN - _SPAN_NOISY)


def refine_tips(img: np.ndarray, x: np.ndarray, y: np.ndarray, *, sigma: float = 1.2,
                inner: float = 14.0, outer: float = 6.0, pivot: float | None = None, trim: float = 5.0,
                span: float = 40.0, hook: float = 6.0, hook_deg: float = 25.0, degree: int = 4,
                saturation: float | None = None, plane: np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Move both ends of the centreline (x, y) (P,) [px] to the line ends fitted on the raw
    frame ``img`` (H, W) (end position along the curve and a small rotation of the last
    ``pivot`` px, default 6 ``sigma`` (at most ``inner``), fitted over the last ``inner`` px;
    a pivot 7 px from the end (sigma 1.2 px) had less tip error across the body than one at
    14 px on rendered strokes, 0.46-0.54 px RMS at SNR 3 against 0.57-0.63, and less bias
    without noise). The last ``trim`` px at each end (twice that for an end hooked by more
    than ``hook_deg`` over its last ``hook`` px) are first rebuilt by the polynomial of
    ``degree`` in arc length fitted over the next ``span`` px (at most the body's length / 5): a skeleton spline is least
    certain, and often hooked, at a noisy tip. At least cubic: a free end carries no bending
    moment, B (theta_s - kappa) = 0, so its curvature is the spontaneous curvature there, not
    zero (on the paper's stroke kappa l is about 9 RMS at one end, 5 at the other, 7.5 in the
    middle), and it changes along the end; a quadratic overshoots the lateral excursions by
    ~0.5 %; quartic over 40 px had the least bias on rendered strokes of 24 segments at SNR 3 (a
    well-resolved end, or a clean frame, wants 20 px: :func:`end_span`, which
    :func:`~flutterswim.tracking.track.track_frame` passes by the frame's contrast). Returns (x, y) resampled at P equal steps
    between the refined ends, and the two end corrections along the curve [px] (NaN where a
    fit failed; that end is then kept). ``saturation``: the value at which the frame is clipped;
    pixels at it are left out of the end fits. ``plane``: the frame's background plane
    (:func:`~flutterswim.tracking.segment.background_plane`), when already known."""
    n = x.size
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    L0 = float(np.sum(np.hypot(np.diff(x), np.diff(y))))
    # on a body shorter in pixels (coarser pixels) the span is at most L0 / 5, which leaves the
    # paper's 264 px body at 14 um/px its 40 px: the polynomial must follow the end, not a third
    # of the body (benchmarks/RESULTS.md: 20-40 um/px)
    span = min(float(span), L0 / 5.0)
    if L0 < 2 * (2 * trim + span) + 4:
        return x, y, math.nan, math.nan
    s0, spl0 = _curve(x, y)
    P = spl0(np.array([0.0, hook, 2 * hook, L0 - 2 * hook, L0 - hook, L0]))

    def turn(a, b, c) -> float:
        u, v = b - a, c - b
        return abs(math.atan2(u[0] * v[1] - u[1] * v[0], u @ v))

    # the last few px of a skeleton spline are its least certain part: rebuild each end by
    # a polynomial in arc length fitted over [trim, trim + span] from the end, extrapolated
    ta = 2 * trim if turn(P[0], P[1], P[2]) > math.radians(hook_deg) else trim
    tb = 2 * trim if turn(P[3], P[4], P[5]) > math.radians(hook_deg) else trim
    q = np.arange(0.0, L0 + 1e-9, 1.0)
    D = spl0(q)
    for t_, end in ((ta, 0), (tb, 1)):
        u = q if end == 0 else L0 - q
        fit = (u >= t_) & (u <= t_ + span)
        cx = np.polyfit(u[fit], D[fit, 0], degree)
        cy = np.polyfit(u[fit], D[fit, 1], degree)
        rep = u < t_
        D[rep, 0], D[rep, 1] = np.polyval(cx, u[rep]), np.polyval(cy, u[rep])
    x2, y2 = D[:, 0], D[:, 1]
    s, spl = _curve(x2, y2)
    L = float(s[-1])
    pivot = min(6.0 * sigma if pivot is None else float(pivot), inner)
    plane = background_plane(img) if plane is None else plane
    qa, ca, ha = _fit_end_twice(img, spl, L, 0.0, -1, sigma, inner, outer, pivot, saturation, plane)
    qb, cb, hb = _fit_end_twice(img, spl, L, L, +1, sigma, inner, outer, pivot, saturation, plane)
    xa = qa if np.isfinite(qa) else 0.0
    xb = qb if np.isfinite(qb) else L
    xo, yo = resample(x2, y2, xa, xb, n, (ca, cb), (ha, hb))
    return xo, yo, float(-qa), float(qb - L)
