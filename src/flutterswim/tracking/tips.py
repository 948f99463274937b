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
    about the hinge at q0 - outward * pivot; NaN if the fit fails. ``outward`` = +1 for the s_end end, -1 for the s = 0 end.
    Pixels at ``saturation`` (clipped) count as light of at least that: the model is clipped
    there too (leaving them out, a line clipped tenfold had its ends 5-12 px off in 4 of 20
    frames, its few unclipped pixels fitted by a line of any height)."""
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
    if np.count_nonzero(sel) < 30:
        return math.nan, math.nan, 0.0
    v = v[sel].astype(float)
    ceiling = None if saturation is None else np.full(v.shape, float(saturation))
    if plane is not None:  # the frame's background plane (refine_tips)
        v -= plane[r0:r1, c0:c1].ravel()[sel]
        if ceiling is not None:
            ceiling -= plane[r0:r1, c0:c1].ravel()[sel]
    q, d, u = q[sel], d[sel], u[sel]
    hinge = np.maximum(u + pivot, 0.0)

    return _levenberg_marquardt(q, d, hinge, v, q0, sigma0, outward, ceiling=ceiling)


def _levenberg_marquardt(q: np.ndarray, d: np.ndarray, h: np.ndarray, v: np.ndarray, q0: float,
                         sigma0: float, o: int, iters: int = 30, ceiling: np.ndarray | None = None
                         ) -> tuple[float, float, float]:
    """Least squares of v ~ b + A exp(-(d - c h)^2 / 2 sg^2) Phi(o (qe - q) / sg) over
    (qe, sg, c, A, b) by Levenberg-Marquardt with the analytic Jacobian; returns (qe, sg, c)
    or NaNs if the fit ends on the edge of the trust box (|qe - q0| < 6, sigma0/2 < sg < 2 sigma0).
    ``ceiling``: each pixel's clipping level; the model is clipped there (a clipped pixel only
    says the light reached it: its residual and slope vanish while the model is above it)."""
    from scipy.special import ndtr

    def parts(p):
        qe, sg, c, A, b = p
        e = d - c * h
        E = np.exp(-0.5 * (e / sg) ** 2)
        z = o * (qe - q) / sg
        Ph = ndtr(z)
        ph = np.exp(-0.5 * z * z) / math.sqrt(2 * math.pi)
        m = b + A * E * Ph
        free = None if ceiling is None else m < ceiling
        r = (m if free is None else np.where(free, m, ceiling)) - v
        return e, E, z, Ph, ph, free, r

    # start: A, b linear at (q0, sigma0, 0)
    g = np.exp(-0.5 * (d / sigma0) ** 2) * ndtr(o * (q0 - q) / sigma0)
    (A0, b0), *_ = np.linalg.lstsq(np.stack([g, np.ones_like(g)], -1), v, rcond=None)
    p = np.array([q0, sigma0, 0.0, A0, b0])
    e, E, z, Ph, ph, free, r = parts(p)
    cost = float(r @ r)
    lam = 1e-3
    for _ in range(iters):
        qe, sg, c, A, b = p
        J = np.stack([A * E * ph * o / sg,
                      A * E * (Ph * e * e / sg**3 - ph * z / sg),
                      A * E * Ph * e * h / sg**2,
                      E * Ph, np.ones_like(v)], -1)
        if free is not None:
            J = J * free[:, None]
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
                p, (e, E, z, Ph, ph, free, r) = pn, parts_n
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
    if np.isfinite(qe) and abs(qe - q0) > 2.0:
        q2, _, c2 = _fit_end(img, spl, s_end, qe, outward, sigma0, inner, outer, pivot, saturation, plane)
        if np.isfinite(q2):
            return q2, c2, qe - outward * pivot
    return qe, c, q0 - outward * pivot


def _angle_end(u: np.ndarray, z: np.ndarray, fit: np.ndarray, degree: int, span: float, start: tuple,
               iters: int = 12) -> np.ndarray | None:
    """The curve whose tangent angle is a polynomial of ``degree`` in arc length, fitted by
    least squares to the points z (complex x + i y) at the nodes u (ascending, equally spaced)
    where ``fit``; returns it at every node (None if the fit fails). ``start``: the x and y
    polynomials (numpy.polyfit coefficients in u) over the same points, for the first guess.

    Positions are the integral of exp(i theta) by Simpson's rule on the nodes and their
    midpoints (exact to ~1e-8 px here), the Jacobian the integral of i u^k exp(i theta), by
    Gauss-Newton from the tangent angles of the x, y polynomials."""
    cx, cy = start
    u0 = float(u[fit][0])
    w = np.empty(2 * u.size - 1)
    w[0::2] = u
    w[1::2] = 0.5 * (u[1:] + u[:-1])
    w = (w - u0) / span
    h = float(u[1] - u[0])
    V = np.vander(w, degree + 1, increasing=True).T  # (degree + 1, 2 n - 1)
    uf = u[fit]
    th = np.unwrap(np.arctan2(np.polyval(np.polyder(cy), uf), np.polyval(np.polyder(cx), uf)))
    a = np.polyfit((uf - u0) / span, th, degree)[::-1]
    r0 = int(np.argmax(fit))  # the fitted node nearest the tip: the curve's anchor z0
    z0 = complex(np.polyval(cx, u0), np.polyval(cy, u0))
    zf = z[fit]

    def integrals(a: np.ndarray) -> np.ndarray:
        """(degree + 2, n): the positions' integral and its derivatives in a, from the anchor."""
        E = np.exp(1j * (a @ V))
        f = np.vstack([E, 1j * V * E])
        c = np.zeros((f.shape[0], u.size), complex)
        c[:, 1:] = np.cumsum(h / 6.0 * (f[:, 0:-1:2] + 4.0 * f[:, 1::2] + f[:, 2::2]), axis=1)
        return c - c[:, r0:r0 + 1]

    for _ in range(iters):
        c = integrals(a)
        r = z0 + c[0, fit] - zf
        J = np.column_stack([np.ones(uf.size), 1j * np.ones(uf.size), c[1:, fit].T])
        JtJ = (J.conj().T @ J).real
        try:
            step = -np.linalg.solve(JtJ, (J.conj().T @ r).real)
        except np.linalg.LinAlgError:
            return None
        if not np.all(np.isfinite(step)):
            return None
        z0 += complex(step[0], step[1])
        a = a + step[2:]
        if np.max(np.abs(step)) < 1e-7:
            break
    else:
        return None
    return z0 + integrals(a)[0]


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


# the end curve's span against the frame's ridge contrast (matched-filter ridge over the
# filtered noise's SD; about 2.4 x the renderer's peak SNR at 3, 2.2 x at 5, 1.9 x at 10): its
# bias and its noise trade. The end is a curve whose tangent angle is a cubic in arc length
# (:func:`_angle_end`), which follows an end bent by tens of degrees over the span; the x, y
# quartic it replaced (stop 37) did not, and needed 20 px on clean frames (noise-free, the stroke
# at 48 segments: leading end -0.29 % over 40 px), where its scatter grew (SNR 5: 3 of 8 movies
# of the paper's 24-segment stroke outside 0.5 %). Over 50 px the cubic-angle curve leaves
# -0.18..-0.25 % on well-resolved strokes without noise (the free end's shape changes within
# ~l / 5), over 30 px within 0.06 %. On 101-frame movies of 4 strokes at 14 um/px, 8 seeds,
# leading end outside 0.5 %: SNR 3 12 of 32 (the quartic over 40 px: 12), SNR 5 4 of 32 (the
# quartic's contrast rule: 10), SNR 10 none (benchmarks/RESULTS.md, stop 37). Hence 50 px up
# to contrast 12.5 (SNR 5 and below), 30 px from 18 (SNR 10 and above), linear between. The
# contrast is taken at the PSF of 1.2 px these were measured with: the ridge's noise across the
# line grows as sigma / contrast (the contrast of a line of peak SNR p is about p sqrt(sigma)),
# so a blurred frame counts as contrast x 1.2 / sigma (defocus to 1.92 px at SNR 5: contrast
# 9.4, as noisy as 5.9 in focus)
_SPAN_NOISY, _SPAN_CLEAN = 50.0, 30.0
_CONTRAST_NOISY, _CONTRAST_CLEAN = 12.5, 18.0
_SIGMA_REF = 1.2
# below this span [px] (a body shorter than ~120 px: coarser than ~30 um/px at the paper's
# length) the ends are rebuilt by the x, y quartic: over 21 px (35 um/px) the cubic-angle curve
# kept frames whose ends the quartic's fit could not find, with the lateral excursions 3-9 %
# short, and at 50-60 um/px returned tracks with ends 2-4 px off where the quartic's frames fail
# and the movie is refused (a review's movies); from 25 px (30 um/px) it was as good or better
_ANGLE_MIN_SPAN = 24.0


def end_span(contrast: float, sigma: float = _SIGMA_REF) -> float:
    """The span [px] of the end curve for a frame of this ridge contrast and PSF sigma
    [px] (NaN contrast: the noisy span)."""
    c = contrast * _SIGMA_REF / sigma
    if not math.isfinite(c) or c <= _CONTRAST_NOISY:
        return _SPAN_NOISY
    f = min((c - _CONTRAST_NOISY) / (_CONTRAST_CLEAN - _CONTRAST_NOISY), 1.0)
    return _SPAN_NOISY + f * (_SPAN_CLEAN - _SPAN_NOISY)


def refine_tips(img: np.ndarray, x: np.ndarray, y: np.ndarray, *, sigma: float = 1.2,
                inner: float = 14.0, outer: float = 6.0, pivot: float | None = None, trim: float = 5.0,
                span: float = 50.0, hook: float = 6.0, hook_deg: float = 25.0, degree: int = 3,
                saturation: float | None = None, plane: np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Move both ends of the centreline (x, y) (P,) [px] to the line ends fitted on the raw
    frame ``img`` (H, W) (end position along the curve and a small rotation of the last
    ``pivot`` px, default 6 ``sigma`` (at most ``inner``), fitted over the last ``inner`` px;
    a pivot 7 px from the end (sigma 1.2 px) had less tip error across the body than one at
    14 px on rendered strokes, 0.46-0.54 px RMS at SNR 3 against 0.57-0.63, and less bias
    without noise). The last ``trim`` px at each end (twice that for an end hooked by more
    than ``hook_deg`` over its last ``hook`` px) are first rebuilt by the curve whose tangent
    angle is a polynomial of ``degree`` in arc length, fitted over the next ``span`` px (at most
    the body's length / 5; :func:`_angle_end`): a skeleton spline is least certain, and often
    hooked, at a noisy tip. A free end carries no bending moment, B (theta_s - kappa) = 0, so
    its curvature is the spontaneous curvature there, not zero (on the paper's stroke kappa l is
    about 9 RMS at one end, 5 at the other, 7.5 in the middle), and it changes along the end:
    the angle needs a cubic (a quadratic, curvature linear along the end, left -0.62 % over
    40 px without noise), and a polynomial in x and y does not follow an end turning by tens
    of degrees. A clean frame wants a shorter span than a noisy one: :func:`end_span`, which
    :func:`~flutterswim.tracking.track.track_frame` passes by the frame's contrast. Returns (x, y) resampled at P equal steps
    between the refined ends, and the two end corrections along the curve [px] (NaN where a
    fit failed; that end is then kept). ``saturation``: the value at which the frame is clipped;
    the end fits count pixels at it as light of at least that. ``plane``: the frame's background plane
    (:func:`~flutterswim.tracking.segment.background_plane`), when already known."""
    n = x.size
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    L0 = float(np.sum(np.hypot(np.diff(x), np.diff(y))))
    # on a body shorter in pixels (coarser pixels) the span is at most L0 / 5, which leaves the
    # paper's 264 px body at 14 um/px its 50 px: the curve must follow the end, not a third
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
    # the cubic-angle curve fitted over [trim, trim + span] from the end, extrapolated (started
    # from the x, y quartic over the same points)
    ta = 2 * trim if turn(P[0], P[1], P[2]) > math.radians(hook_deg) else trim
    tb = 2 * trim if turn(P[3], P[4], P[5]) > math.radians(hook_deg) else trim
    q = np.arange(0.0, L0 + 1e-9, 1.0)
    D = spl0(q)
    for t_, end in ((ta, 0), (tb, 1)):
        u = q if end == 0 else L0 - q
        fit = (u >= t_) & (u <= t_ + span)
        cx = np.polyfit(u[fit], D[fit, 0], 4)
        cy = np.polyfit(u[fit], D[fit, 1], 4)
        rep = u < t_
        near = np.nonzero(rep | fit)[0]
        order = near[np.argsort(u[near])]
        zc = (_angle_end(u[order], D[order, 0] + 1j * D[order, 1], fit[order], degree, span, (cx, cy))
              if span >= _ANGLE_MIN_SPAN else None)
        if zc is not None:
            k = rep[order]
            D[order[k], 0], D[order[k], 1] = zc[k].real, zc[k].imag
        else:  # a short span (coarse pixels) or no convergence: the x, y quartic
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
