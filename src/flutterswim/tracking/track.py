"""Tracking a movie: per-frame centreline, head and tail kept by temporal continuity, and
failure flags with their reasons; the result is the analysis' :class:`Track`.

Per frame: pixels that are not finite and hot pixels removed
(:func:`~flutterswim.tracking.segment.clean_frame`) ->
:func:`segment` (matched filter, hysteresis) -> :func:`fit_centreline` (skeleton,
spline, ridge refinement, half-maximum tips) -> :func:`refine_tips` (line-end model fitted to
the raw pixels). A frame is flagged, never kept, when:

- lost contrast: nothing above the thresholds, or the ridge is below ``min_contrast`` noise
  standard deviations of the filtered frame (a line at SNR 1 gives about 3);
- gap: a second piece beyond one of the body's ends (within 0.75 of its length and 60
  degrees of the end's tangent: where a broken-off piece of it lies) holds more than
  ``gap_fraction`` of the light of the largest one, or the ridge breaks along the body;
- crossing: the body encloses a hole (it loops over itself) or its skeleton branches;
- out of view: the body touches the edge of the frame or ROI;
- length: the body length differs from the median of the good frames by more than
  ``length_tol`` (a partial or merged body), or at most half of the good frames agree on a
  length within it (no consensus: every frame is flagged);
- too short: the ridge's longest skeleton path is too short to fit a centreline (a speck, or
  a body seen end-on);
- tips not found: the ridge's intensity along the curve and its extension does not fall to
  half its plateau at both ends, or the half-maximum tips lie closer than the shortest body;
- tip not found: the line-end fit failed at an end;
- jump: the centreline moved more than ``jump_tol`` body lengths since the last good frame (and
  ``SWIM_PER_FRAME`` more for each frame lost in between),
  or head and tail cannot be told apart (both assignments about equally close, by the whole
  curves and by the two ends alone: after lost frames a strongly bending body can change too
  much for the curves, while its ends have moved far less than their distance apart), or,
  after more than half a stroke of lost frames, the frames that follow match the shapes before
  them (rigid motion removed) about as well in both orders: a body that turned by about 180 - a
  degrees while it was lost looks reversed and turned by a against the last good frame. Every
  later frame is flagged then; when the shapes tell (one order twice as close), the later frames
  are put in that order;
- tip outlier: an end leaves the path of its neighbouring frames (across the body, by more
  than ``tip_k`` robust standard deviations and ``tip_floor_px``), see
  :mod:`flutterswim.tracking.temporal`.

Across frames (after the checks): the ends placed for the median body length, their position
along the body smoothed in time (:mod:`flutterswim.tracking.temporal`), and, for a movie verified
periodic (a settled stroke), every frame replaced by the stroke's shape template at its phase in
its own rigid placement (:mod:`flutterswim.tracking.periodic`).

Coordinates: x = column, y = row (image axes, y pointing down), pixel centres at integers,
converted to mm by ``px_per_mm``; times = frame index / fps.
"""

from __future__ import annotations

import math
import re
import time
import warnings
from typing import Any

import numpy as np
from scipy import ndimage as ndi

from .._validate import ParameterError, angle, finite, non_negative, positive, positive_int, within
from ..analysis.track import Track
from .centreline import fit_centreline
from .io import Frames, open_frames
from .segment import _STATIC_SHARE, BACKGROUND_SIGMA, _moving_best, background_plane, clean_frame, segment
from .tips import end_span, refine_tips

__all__ = ["track", "track_frame", "track_image", "coarse_box", "static_objects", "orient", "failures", "START_ENDS"]

#: The advice when a movie records no frame rate (track_batch says it in its options' words).
NO_FRAME_RATE = "give fps (frames per second) or the frames' times"

START_ENDS = ("left", "right", "top", "bottom")


def _component_light(filtered: np.ndarray, median: float, noise: float, k_high: float,
                     mask: np.ndarray, x: np.ndarray, y: np.ndarray, static: np.ndarray | None = None) -> float:
    """Light of the brightest piece other than ``mask`` that could be the body's own over that
    of ``mask`` (0: none). A piece of the body broken off lies beyond one of the ends of the
    centreline (x, y) (P,) [px]: within 0.75 of that centreline's length of an end (the piece
    tracked may be the smaller part) and within 60 degrees of its outward tangent; a piece
    elsewhere (dust or debris beside the body, static or not) is not the body's, nor one lying on
    ``static`` objects (:func:`static_objects`)."""
    lab, n = ndi.label(filtered > median + k_high * noise, structure=np.ones((3, 3), bool))
    if n < 2:
        return 0.0
    sums = np.bincount(lab.ravel(), weights=(filtered - median).ravel(), minlength=n + 1)[1:]
    own = np.unique(lab[mask & (lab > 0)])
    main = float(sums[own - 1].sum()) if own.size else float(sums.max())
    reach = 0.75 * float(np.sum(np.hypot(np.diff(x), np.diff(y))))  # the piece tracked may be the smaller part
    rows, cols = np.nonzero(lab)
    ids = lab[rows, cols]
    near = np.zeros(n + 1, bool)
    for e, i in ((0, 1), (-1, -2)):
        tx, ty = x[e] - x[i], y[e] - y[i]
        nt = math.hypot(tx, ty)
        dx, dy = cols - x[e], rows - y[e]
        dist = np.hypot(dx, dy)
        ahead = (dx * tx + dy * ty) >= 0.5 * dist * nt  # within 60 degrees of the outward tangent
        near[np.unique(ids[(dist <= reach) & ahead])] = True
    if static is not None:
        size = np.bincount(lab.ravel(), minlength=n + 1)
        on = np.bincount(lab.ravel(), weights=static.ravel(), minlength=n + 1)
        near &= on < _STATIC_SHARE * np.maximum(size, 1)
    cand = np.array([k for k in range(1, n + 1) if near[k] and k not in set(own.tolist())], int)
    others = sums[cand - 1] if cand.size else np.empty(0)
    return float(others.max()) / main if others.size and main > 0 else 0.0


def _has_loop(mask: np.ndarray, min_hole: int = 12) -> bool:
    rows, cols = np.nonzero(mask)
    sub = mask[rows.min(): rows.max() + 1, cols.min(): cols.max() + 1]
    return int(ndi.binary_fill_holes(sub).sum() - sub.sum()) >= min_hole


# the matched filter smooths over at least this [px]: a line blurred by less (a sharp focus,
# PSF sigma 0.5-0.7 px) is nearly one pixel wide, and a filter that narrow leaves the frame's
# noise almost as it is (at SNR 3, 20-34 of 101 frames lost at 0.7 px, all at 0.5 px)
_MIN_FILTER_SIGMA = 1.2


# (and 0: an unsigned frame negated for dark_line, clipped at black)
_FULL_SCALES = frozenset([0.0, 1.0] + [float(2**n - 1) for n in range(8, 17)])


def saturation_level(img: np.ndarray, min_plateau: int = 10) -> float | None:
    """The value at which the frame is clipped (a sensor or a conversion saturated), or None:
    the largest value (the dtype's largest for an integer frame) where at least
    ``min_plateau`` pixels holding it touch another such pixel (a clipped line is a plateau;
    a few brightest pixels of a frame scaled to full range, or ties of integer counts, are
    not). Those pixels tell only that the light was at least that."""
    a = np.asarray(img)
    if a.dtype.kind in "iu":
        top = float(np.iinfo(a.dtype).max)
    elif a.dtype.kind == "f":
        with np.errstate(invalid="ignore"):
            top = float(np.nanmax(a)) if a.size and not np.all(np.isnan(a)) else math.nan
        # a float frame clips at a full scale (1, or 2^n - 1 of an n-bit sensor or format); a
        # plateau at another largest value is the line's own (a noise-free frame, say)
        if top not in _FULL_SCALES:
            return None
    else:
        return None
    m = a == top
    if np.count_nonzero(m) < min_plateau or m.all():  # (a uniform frame, black or blank, shows no clipping)
        return None
    touch = m & (np.roll(m, 1, 0) | np.roll(m, -1, 0) | np.roll(m, 1, 1) | np.roll(m, -1, 1))
    return top if np.count_nonzero(touch) >= min_plateau else None


def track_frame(img: np.ndarray, *, n_points: int = 49, sigma: float = 1.2, k_low: float = 2.0,
                k_high: float = 5.0, min_contrast: float = 4.0, gap_fraction: float = 0.2,
                max_branch: float = 0.15, refine: bool = True, static: np.ndarray | None = None) -> dict[str, Any]:
    """Centreline of one frame (H, W): dict with x, y (n_points,) [px] (NaN on failure),
    length [px], contrast (ridge over filtered-noise sd), ok, reason. ``static``: (H, W) bool,
    static objects (:func:`static_objects`): the body is the brightest component not on them
    (when one is not), and a piece on them is not a piece of the body."""
    nan = np.full(n_points, np.nan)
    sat = saturation_level(img)
    out: dict[str, Any] = {"x": nan, "y": nan, "length": math.nan, "contrast": math.nan, "ok": False,
                           "reason": "", "saturated": sat is not None}
    img = clean_frame(img)
    plane = background_plane(img)
    seg = segment(img, sigma=max(sigma, _MIN_FILTER_SIGMA), k_low=k_low, k_high=k_high, plane=plane, static=static)
    if not seg.ok:
        out["reason"] = f"lost contrast: {seg.reason}"
        return out
    m = seg.mask
    H, W = m.shape
    if m[0].any() or m[-1].any() or m[:, 0].any() or m[:, -1].any():
        out["reason"] = "out of view: the body touches the edge of the frame"
        return out
    with np.errstate(over="ignore"):  # a flat log-profile fit overflows exp; that point is dropped
        c = fit_centreline(seg.filtered, m, n_points=n_points, half_width=max(3.0, 2.5 * sigma))
    contrast = c.plateau / seg.noise if seg.noise > 0 and math.isfinite(c.plateau) else math.nan
    out["contrast"] = contrast
    if math.isfinite(contrast) and contrast < min_contrast:
        out["reason"] = f"lost contrast: ridge {contrast:.2g} noise sd, below {min_contrast:g}"
        return out
    if not c.ok:
        why = {"gap in the ridge": "gap: the ridge breaks along the body",
               "lost ridge": "lost contrast: the ridge is lost"}.get(c.reason, c.reason)
        out["reason"] = why
        return out
    light = _component_light(seg.filtered, seg.median, seg.noise, k_high, m, c.x, c.y, static)
    if light > gap_fraction:
        out["reason"] = f"gap: a second piece holds {100 * light:.0f}% of the body's light"
        return out
    if _has_loop(m):
        out["reason"] = "crossing: the body loops over itself"
        return out
    if c.branch_fraction > max_branch:
        out["reason"] = f"crossing: {100 * c.branch_fraction:.0f}% of the skeleton branches off"
        return out
    x, y = c.x, c.y
    if refine:
        x, y, da, db = refine_tips(img, x, y, sigma=sigma, saturation=sat, plane=plane, span=end_span(math.inf if seg.noise == 0 else contrast, sigma))
        if not (math.isfinite(da) and math.isfinite(db)):
            out["reason"] = "tip not found: the line-end fit failed"
            return out
    x, y = _ridge_to_centreline(x, y, sigma, max(sigma, _MIN_FILTER_SIGMA))
    out.update(x=x, y=y, length=float(np.sum(np.hypot(np.diff(x), np.diff(y)))), ok=True)
    return out


def _ridge_to_centreline(x: np.ndarray, y: np.ndarray, sigma: float, sigma_filter: float) -> tuple[np.ndarray, np.ndarray]:
    """The body's samples (x, y) (P,) [px] moved from the ridge of the matched-filtered line to
    the line itself. The ridge of a curved line blurred to a Gaussian of width w lies inside it
    by w^2 kappa / 2 (kappa the curvature; first order in w kappa); the filter's broad
    background (width W) pushes it out by the same rule times w / W (its slope across the
    line): the shift is w^2 kappa (1 - w / W) / 2, with w^2 = sigma^2 + sigma_filter^2 and
    W^2 = sigma^2 + BACKGROUND_SIGMA^2. Without noise it cut the centreline's error from 0.042
    to 0.016 px (PSF 1.2 px) and from 0.32 to 0.061 px (PSF 4 px). The ends (fitted on the raw
    pixels) stay; the shift fades in over 2 w from them."""
    w = math.sqrt(sigma * sigma + sigma_filter * sigma_filter)
    width2 = w * w * (1.0 - w / math.sqrt(sigma * sigma + BACKGROUND_SIGMA**2))
    P = x.size
    if P < 5:
        return x, y
    ax, ay = x[1:-1] - x[:-2], y[1:-1] - y[:-2]
    bx, by = x[2:] - x[1:-1], y[2:] - y[1:-1]
    cross = ax * by - ay * bx
    la, lb, lc = np.hypot(ax, ay), np.hypot(bx, by), np.hypot(x[2:] - x[:-2], y[2:] - y[:-2])
    kappa = 2.0 * cross / np.maximum(la * lb * lc, 1e-12)  # signed (Menger), left turns positive
    kappa = np.convolve(np.pad(kappa, 1, mode="edge"), np.ones(3) / 3.0, mode="valid")  # less noise
    tx, ty = x[2:] - x[:-2], y[2:] - y[:-2]
    nt = np.maximum(np.hypot(tx, ty), 1e-12)
    s = np.concatenate(([0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))))
    fade = np.clip(np.minimum(s, s[-1] - s)[1:-1] / (2.0 * w), 0.0, 1.0)
    shift = -0.5 * width2 * kappa * fade  # along the left normal (-t_y, t_x)
    xo, yo = x.copy(), y.copy()
    xo[1:-1] += shift * (-ty / nt)
    yo[1:-1] += shift * (tx / nt)
    return xo, yo


def estimate_blur(img: np.ndarray, x: np.ndarray, y: np.ndarray, sigma_filter: float = 1.2) -> float:
    """Gaussian sigma [px] of the line's cross profile (PSF and defocus together): the profiles
    across the middle 80 % of the centreline (x, y), every px, of the frame smoothed by
    ``sigma_filter``, each less its own baseline (its outer samples), are averaged and fitted
    by b + b_d d + A exp(-(d - m)^2 / 2 w^2) (the slope: without it, a background rising across
    the body by 2.5 % of the line's height per px read 1.33 px where a flat one read 1.27); then
    sigma^2 = w^2 - sigma_filter^2."""
    from scipy.optimize import curve_fit

    from .tips import resample

    L = float(np.sum(np.hypot(np.diff(x), np.diff(y))))
    n = max(int(0.8 * L), 8)
    xs, ys = resample(x, y, 0.1 * L, 0.9 * L, n)
    tx, ty = np.gradient(xs), np.gradient(ys)
    nn = np.hypot(tx, ty)
    nn[nn == 0] = 1.0
    nx, ny = -ty / nn, tx / nn
    hw = max(8.0, 6.0 * sigma_filter)
    d = np.arange(-hw, hw + 1e-9, 0.25)
    f = ndi.gaussian_filter(np.asarray(img, np.float64), sigma_filter, mode="nearest")
    P = ndi.map_coordinates(f, [(ys[:, None] + d * ny[:, None]).ravel(), (xs[:, None] + d * nx[:, None]).ravel()],
                            order=1, mode="nearest").reshape(n, d.size)
    outer = np.abs(d) >= hw - 2.0
    prof = np.mean(P - np.median(P[:, outer], axis=1, keepdims=True), axis=0)

    def g(u, A, m, w, b, bd):
        return b + bd * u + A * np.exp(-0.5 * ((u - m) / w) ** 2)

    try:
        (A, m, w, b, _), _ = curve_fit(g, d, prof, p0=[float(prof.max()), 0.0, 1.7, 0.0, 0.0], maxfev=2000)
    except (RuntimeError, ValueError):
        return math.nan
    w = abs(float(w))
    if not (A > 0 and w > sigma_filter):
        return math.nan
    return math.sqrt(max(w * w - sigma_filter**2, 0.25))


def _coarse_objects(img: np.ndarray, k: int = 4) -> tuple[np.ndarray, np.ndarray] | None:
    """(objects (Hc, Wc) bool, excess light (Hc, Wc)) on the frame reduced k x k (block means
    raise a thin line's SNR about k-fold): blocks 4 robust SD above a 9-block local mean; None
    for a frame under 16 k px a side or without noise."""
    H, W = img.shape
    Hc, Wc = H // k, W // k
    if Hc < 16 or Wc < 16:
        return None
    small = np.asarray(img[: Hc * k, : Wc * k], np.float32).reshape(Hc, k, Wc, k).mean(axis=(1, 3))
    f = ndi.gaussian_filter(small, 0.7) - ndi.uniform_filter(small, 9)
    med = float(np.median(f))
    sd = 1.4826 * float(np.median(np.abs(f - med)))
    if not sd > 0:
        return None
    return f > med + 4 * sd, f - med


def static_objects(frames: Any, k: int = 4, n_samples: int = 8, negate: bool = False) -> np.ndarray | None:
    """(H, W) bool: the bright objects that stay put, found in every one of ``n_samples``
    frames spread over the movie on the k x k reduced grid (:func:`_coarse_objects`; a block's
    neighbours included): debris, a fibre, a bead, never a swimmer that strokes or advances
    (one at rest is, and is then tracked as before). None for fewer frames or frames too
    small. ``negate``: the frames of a dark line."""
    T = len(frames)
    if T < n_samples:
        return None
    on, img = None, None
    idx = np.unique(np.linspace(0, T - 1, n_samples).round().astype(int))
    for raw in (frames.take(idx) if isinstance(frames, Frames) else [frames[i] for i in idx]):
        img = clean_frame(raw)
        obj = _coarse_objects(-np.asarray(img, np.float32) if negate else img, k)
        if obj is None:
            return None
        on = obj[0] if on is None else on & obj[0]
    if on is None or not on.any():
        return None
    on = ndi.binary_dilation(on, np.ones((3, 3), bool))
    H, W = np.shape(img)
    out = np.zeros((H, W), bool)
    out[: on.shape[0] * k, : on.shape[1] * k] = np.repeat(np.repeat(on, k, 0), k, 1)
    return out


def coarse_box(img: np.ndarray, k: int = 4, static: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray] | None:
    """Corners ([x0, x1], [y0, y1]) [px] of the brightest line-like object (not on ``static``,
    :func:`static_objects`, when another is), found on the frame reduced k x k, or None."""
    obj = _coarse_objects(img, k)
    if obj is None:
        return None
    lab, n = ndi.label(obj[0], structure=np.ones((3, 3), bool))
    if n == 0:
        return None
    sums = np.bincount(lab.ravel(), weights=obj[1].ravel(), minlength=n + 1)
    st = None if static is None else static[: lab.shape[0] * k: k, : lab.shape[1] * k: k]
    rows, cols = np.nonzero(lab == _moving_best(lab, n, sums, st))
    return (np.array([cols.min(), cols.max() + 1]) * k, np.array([rows.min(), rows.max() + 1]) * k)


def track_image(img: np.ndarray, ref: tuple[np.ndarray, np.ndarray] | None, window_px: float,
                static: np.ndarray | None = None, **opts: Any) -> dict[str, Any]:
    """:func:`track_frame` inside a search window around ``ref`` (the last good centreline,
    or without one the box of :func:`coarse_box`) plus ``window_px``; on the whole frame if
    anything fails in the window, so no verdict depends on it. ``static``: the movie's static
    objects (:func:`static_objects`), passed over for a moving one."""
    if window_px > 0:
        box = (ref[0], ref[1]) if ref is not None else coarse_box(clean_frame(img), static=static)
        if box is not None:
            Hf, Wf = img.shape
            c0 = int(max(np.floor(np.min(box[0])) - window_px, 0))
            c1 = int(min(np.ceil(np.max(box[0])) + window_px + 1, Wf))
            r0 = int(max(np.floor(np.min(box[1])) - window_px, 0))
            r1 = int(min(np.ceil(np.max(box[1])) + window_px + 1, Hf))
            if (r1 - r0) * (c1 - c0) < 0.8 * Hf * Wf:
                r = track_frame(img[r0:r1, c0:c1], static=None if static is None else static[r0:r1, c0:c1], **opts)
                if r["ok"]:
                    r["x"], r["y"] = r["x"] + c0, r["y"] + r0
                    return r
    return track_frame(img, static=static, **opts)


def _start_score(x: np.ndarray, y: np.ndarray, start_end: str) -> float:
    """> 0 when the s = 0 end of (x, y) lies on the requested side."""
    dx, dy = x[-1] - x[0], y[-1] - y[0]
    return {"left": dx, "right": -dx, "top": dy, "bottom": -dy}[start_end]


def orient(x: np.ndarray, y: np.ndarray, ref_x: np.ndarray, ref_y: np.ndarray) -> tuple[bool, float, float]:
    """Whether to reverse (x, y) to match the reference centreline: (flip, mean point distance
    of the chosen order, that of the other order)."""
    d_keep = float(np.mean(np.hypot(x - ref_x, y - ref_y)))
    d_flip = float(np.mean(np.hypot(x[::-1] - ref_x, y[::-1] - ref_y)))
    return (d_flip < d_keep), min(d_keep, d_flip), max(d_keep, d_flip)


def _aligned_rms(x: np.ndarray, y: np.ndarray, ref_x: np.ndarray, ref_y: np.ndarray) -> float:
    """RMS distance [px] between the samples of (x, y) and those of the reference centreline
    after the rigid motion that best maps one onto the other (least squares, Kabsch)."""
    p = np.stack([ref_x - ref_x.mean(), ref_y - ref_y.mean()])
    q = np.stack([x - x.mean(), y - y.mean()])
    c = p @ q.T
    a = math.atan2(c[0, 1] - c[1, 0], c[0, 0] + c[1, 1])
    ca, sa = math.cos(a), math.sin(a)
    r = np.array([[ca, -sa], [sa, ca]]) @ p - q
    return float(np.sqrt(np.mean(np.sum(r * r, axis=0))))


def _unlinked(links: list, X: np.ndarray, Y: np.ndarray, good: np.ndarray, per_stroke: float
              ) -> tuple[list[int], tuple[int, str] | None]:
    """Head and tail across runs of lost frames longer than half a stroke. Over such a run the
    body's shape is unrelated to the last good frame's (a strongly bending stroke's reads 20-50
    degrees of rigid turn against it at half a stroke), and a body turned by 180 - a degrees with
    head and tail swapped looks as close as one turned by a (the field turned 60 degrees per
    second: 140 degrees across 18 lost frames, and every later frame swapped). So the good frames
    after the run (up to a stroke of them, to the next run) are compared, rigid motion removed,
    with every good frame before it, in both orders (a frame at its phase of an earlier stroke
    matches its shape): their best matches in one order must be at least twice as close (RMS
    over them) as in the other. A shorter run is checked so too where the last good frame did
    not tell the order. links: (frame, frames since the last good one, whether that frame did not
    tell the order); X, Y, good: the
    frames as tracked before the later checks (X, Y reversed in place from a frame found
    reversed). Returns the frames from which every later frame is reversed, and the first frame
    from which head and tail cannot be told apart with the reason (or None)."""
    flips: list[int] = []
    if not (math.isfinite(per_stroke) and per_stroke > 0):
        untold = [(i, gap) for i, gap, u in links if u]
        if untold:  # (no stroke to compare shapes over)
            i, gap = untold[0]
            return flips, (i, f"jump: head and tail cannot be told apart after {gap - 1:g} lost frames before "
                              f"frame {i} (no stroke period found to compare the shapes over)")
        return flips, None
    starts = [i for i, *_ in links]
    for n, (i, gap, untold) in enumerate(links):
        if gap <= 0.5 * per_stroke and not untold:
            continue
        before = np.nonzero(good[:i])[0]
        end = min(starts[n + 1] if n + 1 < len(starts) else good.size, i + int(math.ceil(per_stroke)))
        after = np.nonzero(good[i:end])[0] + i
        if before.size == 0 or after.size == 0:
            continue
        e = np.array([[[_aligned_rms(X[k, ::o], Y[k, ::o], X[j], Y[j]) for j in before] for o in (1, -1)]
                      for k in after]).min(axis=2)  # (after, order): the best match's RMS [px]
        e_keep, e_flip = np.sqrt(np.mean(e**2, axis=0))
        if e_flip >= 2.0 * e_keep:
            continue
        if e_keep >= 2.0 * e_flip:  # the frames since the run were followed reversed
            X[i:], Y[i:] = X[i:, ::-1].copy(), Y[i:, ::-1].copy()
            flips.append(i)
            continue
        return flips, (i, f"jump: head and tail cannot be told apart after {gap - 1:g} lost frames before frame {i} "
                          f"({gap / per_stroke:.2f} strokes): rigid motion removed, the {after.size} frame(s) after "
                          f"them match the frames before {e_keep:.1f} px RMS in their order and {e_flip:.1f} px "
                          "reversed")
    return flips, None


# more than this share of a movie's pixels keeping their exact value between frames is a codec's
# skipped blocks, not a camera: H.264 at CRF 25 on a line 3 noise SD high with noise of 6 grey
# levels kept 70-78 % (the noise gone, the ends moved 4-6 %, 7-14 of 101 frames flagged); the same
# at CRF 10, or stretched to the full 8 bits at CRF 25, 1-5 % (the descriptors within 0.5 %)
_MAX_UNCHANGED = 0.5


class _StillPixels:
    """The share of an integer-valued movie's pixels (every second row and column) that keep
    their exact value between consecutive frames, among those inside both frames' value range
    (a clipped black level or saturation repeats in any camera); frames with fractional values
    (rendered in floats, noiseless or not) are not counted."""

    def __init__(self) -> None:
        self.prev: np.ndarray | None = None
        self.shares: list[float] = []

    def add(self, img: Any) -> None:
        a = np.asarray(img)[::2, ::2]
        with np.errstate(invalid="ignore"):  # a NaN or inf pixel: not integer-valued
            fractional = a.dtype.kind == "f" and not np.all(np.mod(a[::2, ::2], 1) == 0)
        if a.ndim != 2 or fractional:
            self.prev = None
            return
        p, self.prev = self.prev, a
        if p is None or p.shape != a.shape:
            return
        lo, hi = max(int(a.min()), int(p.min())), min(int(a.max()), int(p.max()))
        inner = (a > lo) & (a < hi) & (p > lo) & (p < hi)
        n = int(np.count_nonzero(inner))
        if n >= 100:
            self.shares.append(float(np.count_nonzero(inner & (a == p))) / n)

    def fraction(self) -> float:
        return float(np.median(self.shares)) if self.shares else math.nan


def _smooth_frames(v: Any) -> Any:
    if v != 0 and not (isinstance(v, (int, np.integer)) and v >= 7):
        raise ParameterError(f"smooth_frames={v!r} is not allowed; give 0 (off) or a whole number "
                             "of frames >= 7 (the window of a quartic in time)")
    return v


def _dark_line(v: Any) -> Any:
    if not isinstance(v, (bool, np.bool_)):
        raise ParameterError(f"dark_line={v!r} is not allowed; give True (a line darker than its background) "
                             "or False (brighter)")
    return v


def _start_end(v: Any) -> Any:
    if v not in START_ENDS:
        raise ParameterError(f"start_end={v!r} is not allowed; choose one of {', '.join(START_ENDS)}")
    return v


#: pixels per millimetre a camera may have: a pixel from 1 m to 1 nm
PX_PER_MM_RANGE = (1e-3, 1e6)
#: most samples along the tracked body (a 512 px body has 512 pixels along it)
MAX_POINTS = 10_000
#: widest matched filter [px]: the ridge is a line of a pixel or two (sigma 1e6 ran for minutes)
MAX_SIGMA_PX = 20.0


# the checks of track()'s options (NaN would switch the checks off: min_contrast, the tolerances)
_OPTION_CHECKS = {
    "n_points": lambda v: positive_int("n_points", v, 5, MAX_POINTS, "samples along the body; 10^8 ran out of "
                                                                     "memory"),
    "tip_k": lambda v: positive("tip_k", v),
    "tip_floor_px": lambda v: positive("tip_floor_px", v),
    "sigma": lambda v: None if v is None else within("sigma", positive("sigma", v), 0.0, MAX_SIGMA_PX,
                                                       "px: a wider filter than a line a pixel or two wide; the "
                                                       "default 1.2 px suits a focused ribbon"),
    # (radians: more than a turn is likely degrees; user -> track -> check_options -> here)
    "field_angle": lambda v: angle("field_angle", v, stacklevel=3), "t0": lambda v: finite("t0", v),
    "min_contrast": lambda v: non_negative("min_contrast", v), "length_tol": lambda v: positive("length_tol", v),
    "jump_tol": lambda v: positive("jump_tol", v), "gap_fraction": lambda v: non_negative("gap_fraction", v),
    "window_px": lambda v: non_negative("window_px", v), "smooth_frames": _smooth_frames,
    "dark_line": _dark_line, "start_end": _start_end,
}
# options of track() passed through unchecked (booleans of its own)
_PLAIN_OPTIONS = ("roi", "refine", "fixed_length", "tip_check", "periodic", "progress", "fps", "times")


def _frame_times(times: Any, n_frames: int) -> np.ndarray:
    """The frames' times [s] checked: finite, strictly increasing, one per frame."""
    try:
        t = np.asarray(times, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"times={times!r} must be numbers, one time [s] per frame") from None
    if t.ndim != 1 or t.size != n_frames:
        raise ParameterError(f"times holds {t.size if t.ndim == 1 else t.shape} values; give one time [s] per frame "
                             f"({n_frames} frames)")
    if not np.all(np.isfinite(t)):
        k = int(np.nonzero(~np.isfinite(t))[0][0])
        raise ParameterError(f"times[{k}]={float(t[k])!r} must be finite (seconds)")
    if t.size > 1 and not np.all(np.diff(t) > 0):
        k = int(np.nonzero(~(np.diff(t) > 0))[0][0])
        raise ParameterError(f"times must increase strictly; times[{k + 1}]={float(t[k + 1])!r} follows "
                             f"times[{k}]={float(t[k])!r}")
    return t


def check_options(**options: Any) -> dict[str, Any]:
    """:func:`track`'s options checked (each named in its error), e.g. the ``track_kwargs`` of
    a batch before its first trial; an unknown name is refused."""
    out = {}
    for k, v in options.items():
        if k in _OPTION_CHECKS:
            out[k] = _OPTION_CHECKS[k](v)
        elif k in _PLAIN_OPTIONS:
            out[k] = v
        else:
            raise ParameterError(f"{k}={v!r}: track() has no option {k!r}; its options are "
                                 f"{', '.join(sorted((*_OPTION_CHECKS, *_PLAIN_OPTIONS)))}")
    return out


#: how far a movie's recorded frame rate may be from the rate of the times given (--times)
#: before they are refused as in another unit (a camera's nominal rate against its clock: < 1 %)
_TIMES_FPS_TOLERANCE = 0.1
#: the most a swimmer travels per frame [body lengths] in the jump check across lost frames
SWIM_PER_FRAME = 0.05
#: after more lost frames than this, a frame whose ends the last good frame cannot order is kept
#: and ordered by the shape check across the gap (_unlinked); after fewer it is flagged
UNTOLD_AFTER = 10


def track(source: Any, *, px_per_mm: float, fps: float | None = None, roi: Any = None,
          n_points: int = 49, start_end: str = "left", field_angle: float = 0.0, sigma: float | None = None,
          min_contrast: float = 4.0, length_tol: float = 0.03, jump_tol: float = 0.25,
          gap_fraction: float = 0.2, refine: bool = True, window_px: float = 40.0,
          fixed_length: bool = True, tip_check: bool = True, tip_k: float = 6.0, tip_floor_px: float = 2.0,
          smooth_frames: int = 7, periodic: bool = True, dark_line: bool = False, t0: float = 0.0,
          times: Any = None, progress: bool = False) -> Track:
    """Track the filament in a movie and return its :class:`Track` (good frames only, mm, s).

    source: TIFF stack, folder of PNG/TIFF frames, MP4/AVI movie (path), an array (T, H, W)
    or a rendered :class:`Movie`. px_per_mm: image scale; fps: frame rate (default: the
    movie's own); roi: (x0, y0, x1, y1) pixels or "x0,y0,x1,y1"; n_points: arc-length samples;
    start_end: where the s = 0 end lies in the first good frame ("left", "right", "top",
    "bottom"), later frames follow by continuity; field_angle: field direction [rad] in image
    axes (0: +x); sigma: Gaussian sigma of the line's blur [px] (None: measured on the first
    good frame, PSF and defocus together); window_px: margin of the search window around the last good body (0: whole
    frames); fixed_length: place each frame's ends so the body has the median length
    (inextensible; the measured lengths stay in the record); tip_check: flag a frame whose
    end leaves the path of its neighbouring frames by more than tip_k robust standard
    deviations and tip_floor_px (:func:`flutterswim.tracking.temporal.tip_outliers`);
    smooth_frames: window [frames] of the along-body position of the ends, smoothed in time
    through the middle of the body (:func:`~flutterswim.tracking.temporal.smooth_offsets`;
    0: off; the ends' paths are never smoothed); periodic: when the movie is verified periodic
    (a settled stroke: >= 2.5 strokes, no drift of the shape in the body frame), every frame
    becomes the stroke's shape template at its phase (fitted over all cycles), placed by the
    frame's own rigid motion (:func:`flutterswim.tracking.periodic.periodic_shape`; the raw
    per-frame lengths stay in the record; ``meta["temporal"]["periodic"]`` says whether and
    why (not)); dark_line: the filament is darker than its background (bright field, a
    shadow): every frame is tracked negated; times: each frame's time [s] (a camera's timestamps,
    for a movie with dropped or unevenly spaced frames; default t0 + i / fps). A frame identical to
    the one before (a duplicated frame: its content is not of its time) is flagged "repeated",
    unless most are (a noiseless movie of a body at rest). Per-frame results (all frames, failed ones NaN, with their reasons) are in
    ``track.meta["frames"]``; see the module docstring for the checks.
    """
    # (1e-300 gave a body of 2.6e302 mm)
    px_per_mm = within("px_per_mm", px_per_mm, *PX_PER_MM_RANGE, "pixels per millimetre of a camera; the paper's "
                       "movies: about 71")
    # checked before any frame is read
    o = check_options(n_points=n_points, tip_k=tip_k, tip_floor_px=tip_floor_px, sigma=sigma,
                      field_angle=field_angle, t0=t0, min_contrast=min_contrast, length_tol=length_tol,
                      jump_tol=jump_tol, gap_fraction=gap_fraction, window_px=window_px,
                      smooth_frames=smooth_frames, dark_line=dark_line, start_end=start_end)
    n_points, tip_k, tip_floor_px, field_angle, t0 = (o[k] for k in ("n_points", "tip_k", "tip_floor_px",
                                                                        "field_angle", "t0"))
    min_contrast, length_tol, jump_tol, gap_fraction, window_px = (
        o[k] for k in ("min_contrast", "length_tol", "jump_tol", "gap_fraction", "window_px"))
    sig = 1.2 if sigma is None else o["sigma"]
    frames = open_frames(source, roi)
    T = len(frames)
    if times is not None:
        times = _frame_times(times, T)
        rate = 1.0 / float(np.median(np.diff(times))) if T > 1 else math.nan
        if fps is not None and T > 1 and abs(positive("fps", fps) / rate - 1.0) > 0.01:
            # (the fits in time count in frame intervals of fps: --fps 10 with 50 fps times was
            # dropped without a word)
            raise ParameterError(f"fps={fps!r} disagrees with the frames' times (median interval "
                                 f"{1.0 / rate:.6g} s, {rate:.6g} fps); give one of them, or fps matching the times")
        if fps is None and T > 1 and frames.fps is not None and abs(frames.fps / rate - 1.0) > _TIMES_FPS_TOLERANCE:
            # (times in ms read as s gave a period 1000 times too long without a word)
            raise ParameterError(f"times: their median interval {1.0 / rate:.6g} s ({rate:.6g} fps) disagrees with the "
                                 f"frame rate input={frames.source!r} records ({frames.fps:.6g} fps): are the times in "
                                 "another unit (ms for s)? Name the unit in the header (time_ms, Time (ms)), or give "
                                 "fps to confirm the times' rate")
        if fps is None:  # (one frame has no interval: its rate is moot, 1 per second is written)
            fps = rate if T > 1 else 1.0
    elif fps is None:
        fps = frames.fps
        if fps is None:
            raise ParameterError(f"fps was not given and input={frames.source!r} does not record a frame rate; "
                                 + NO_FRAME_RATE)
    elif frames.fps is not None and abs(positive("fps", fps) / frames.fps - 1.0) > 0.01:
        # (given, it is used: a high-speed camera's movie records its playback rate; but a
        # mistyped rate scaled the period without a word)
        warnings.warn(f"fps={fps:g} is used, while input={frames.source!r} records {frames.fps:g} fps (the period "
                      "and the speeds scale with it): leave fps out to use the recorded rate", stacklevel=2)
    fps = positive("fps", fps)
    # the frames' times in frame intervals, for the checks and fits in time (None: the indices)
    pos = None if times is None else (times - times[0]) * fps
    X = np.full((T, n_points), np.nan)
    Y = np.full((T, n_points), np.nan)
    length = np.full(T, np.nan)
    contrast = np.full(T, np.nan)
    ok = np.zeros(T, bool)
    reason = [""] * T
    match = np.full(T, np.nan)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=T, unit="frame", desc="track", leave=False)
    tic = time.perf_counter()
    ref: tuple[np.ndarray, np.ndarray] | None = None
    ref_i = -1
    # (frame, frames since the last good one, whether the last good frame told its order): checked after the loop
    links: list[tuple[int, float, bool]] = []
    blur_known = sigma is not None
    n_clipped = 0
    static = static_objects(frames, negate=dark_line)
    still = _StillPixels()
    repeated = np.zeros(T, bool)
    prev = None
    try:
        for i, img in enumerate(frames):
            still.add(img)
            repeated[i] = prev is not None and np.array_equal(img, prev)
            prev = img
            if dark_line:  # in floats: an unsigned frame's negative wraps (0 stays 0)
                img = -np.asarray(img, np.float32) if np.asarray(img).dtype.kind in "iu" else np.negative(img)
            r = track_image(img, ref, window_px, static, n_points=n_points, sigma=sig, min_contrast=min_contrast,
                            gap_fraction=gap_fraction, refine=refine)
            if sigma is None and not blur_known and r["ok"]:
                # the blur of this movie, from its first good frame; that frame again if it is
                # more than 15 % off the default
                est = estimate_blur(clean_frame(img), r["x"], r["y"], sig)
                blur_known = True
                if math.isfinite(est) and abs(est - sig) > 0.15 * sig:
                    sig = float(np.clip(est, 0.6, 6.0))
                    r = track_image(img, None, window_px, static, n_points=n_points, sigma=sig,
                                    min_contrast=min_contrast, gap_fraction=gap_fraction, refine=refine)
            contrast[i] = r["contrast"]
            n_clipped += bool(r.get("saturated", False))
            if r["ok"]:
                x, y = r["x"], r["y"]
                if ref is None:
                    if _start_score(x, y, start_end) < 0:
                        x, y = x[::-1], y[::-1]
                else:
                    flip, d_best, d_other = orient(x, y, *ref)
                    if flip:
                        x, y = x[::-1], y[::-1]
                    Lr = r["length"]
                    if d_other < 2.0 * d_best:
                        # the whole curves do not tell (a body that changed much since a last
                        # good frame some frames back): the ends alone may
                        e = [0, -1]
                        flip_e, e_best, e_other = orient(x[e], y[e], ref[0][e], ref[1][e])
                        if e_other >= 2.0 * e_best:
                            if flip_e:
                                x, y = x[::-1], y[::-1]
                            d_best = float(np.mean(np.hypot(x - ref[0], y - ref[1])))
                            d_other = math.inf
                    match[i] = d_best
                    # the stroke's change is bounded (jump_tol) and, across lost frames, the
                    # swimmer's travel grows by at most SWIM_PER_FRAME body lengths a frame (9
                    # times the paper's swimmer at 50 fps): a fixed tolerance lost every frame
                    # after 45 lost frames (the body 78 px on), one of jump_tol per frame took a
                    # second ribbon a body length away after 3; head and tail across a long run
                    # are checked after the loop (_unlinked)
                    since = (i - ref_i) if pos is None else max(float(pos[i] - pos[ref_i]), 1.0)
                    tol = jump_tol + SWIM_PER_FRAME * (since - 1.0)
                    if d_best > tol * Lr:
                        r["ok"], r["reason"] = False, (f"jump: the body moved {d_best:.1f} px since the last good "
                                                       f"frame, {since:g} frame(s) before (> {tol:.3g} body lengths)")
                    elif d_other < 2.0 * d_best and since <= UNTOLD_AFTER:
                        r["ok"], r["reason"] = False, "jump: head and tail cannot be told apart from the last good frame"
                if r["ok"] and ref is not None and since > 1.5:
                    # across lost frames: checked once the stroke's period is known (an order the
                    # last good frame did not tell, kept after more than UNTOLD_AFTER lost frames,
                    # whatever the run's length: after 70 the swimmer had swum 1.5 body lengths on,
                    # and every later frame had been refused as not told apart)
                    links.append((i, since, d_other < 2.0 * d_best))
                if r["ok"]:
                    X[i], Y[i], length[i] = x, y, r["length"]
                    ref, ref_i = (x, y), i
            ok[i] = r["ok"]
            reason[i] = r["reason"]
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    wall = time.perf_counter() - tic
    X_loop, Y_loop, ok_loop = X.copy(), Y.copy(), ok.copy()
    if 0 < np.count_nonzero(repeated) <= (T - 1) // 2:
        # a camera's noise never repeats a frame: a codec or a grabber duplicated it (in place of
        # one it dropped), so its content is of an earlier time. All frames repeating is a
        # noiseless movie of a body at rest.
        for i in np.nonzero(repeated)[0]:
            ok[i] = False
            reason[i] = f"repeated: identical to frame {i - 1} (a duplicated frame: its content is not of its time)"
    if np.count_nonzero(ok) >= 1:
        med = float(np.median(length[ok]))
        dev = np.abs(length - med) / med
        bad = ok & (dev > length_tol)
        n_ok, n_agree = int(np.count_nonzero(ok)), int(np.count_nonzero(ok & ~bad))
        if 2 * n_agree <= n_ok:
            # no consensus (at most half of the frames agree): partial or merged bodies, and the
            # median is not the body's length (a movie near the noise floor); none of them is kept
            for i in np.nonzero(ok)[0]:
                reason[i] = (f"length: no consistent body length (only {n_agree} of {n_ok} frames within "
                             f"{100 * length_tol:g}% of their median {med:.1f} px)")
            bad = ok.copy()
        else:
            for i in np.nonzero(bad)[0]:
                reason[i] = (f"length: {length[i]:.1f} px differs from the median {med:.1f} px by "
                             f"{100 * dev[i]:.1f}% (> {100 * length_tol:g}%: a partial or merged body)")
        ok &= ~bad
    X[~ok] = np.nan
    Y[~ok] = np.nan
    from .temporal import frames_per_stroke, smoothing_allowed

    per_stroke = frames_per_stroke(X, Y, ok, pos)
    flips, unsure = _unlinked(links, X_loop, Y_loop, ok_loop, per_stroke)
    for i in flips:
        X[i:], Y[i:] = X[i:, ::-1].copy(), Y[i:, ::-1].copy()
    if unsure is not None:
        for k in np.nonzero(ok[unsure[0]:])[0] + unsure[0]:
            ok[k], reason[k] = False, unsure[1]
        X[~ok] = np.nan
        Y[~ok] = np.nan
    if flips or unsure is not None:
        per_stroke = frames_per_stroke(X, Y, ok, pos)
    temporal: dict[str, Any] = {"frames_per_stroke": per_stroke, "tip_check": "off", "smoothing": "off",
                                "periodic": "off"}
    if tip_check and not per_stroke >= 12:
        temporal["tip_check"] = f"not done: {per_stroke:.1f} frames per stroke (needs >= 12)"
    elif tip_check:
        from .temporal import tip_outliers

        temporal["tip_check"] = f"done (k = {tip_k:g}, floor {tip_floor_px:g} px)"
        for i, e, res, z in tip_outliers(X, Y, ok, k=tip_k, floor_px=tip_floor_px, positions=pos):
            if ok[i]:
                ok[i] = False
                reason[i] = (f"tip outlier: the {'s = l' if e else 's = 0'} end is {abs(res):.1f} px "
                             f"({z:.1f} robust SD, > {tip_k:g} and > {tip_floor_px:g} px) off the path of "
                             "its neighbouring frames")
        X[~ok] = np.nan
        Y[~ok] = np.nan
    if fixed_length and np.count_nonzero(ok) >= 3:
        # the body is inextensible: slide each frame's ends along the curve so its length is
        # the median; the two ends' errors along the body are independent, so their mean
        # error is sqrt(2) smaller (the measured lengths stay in length_px)
        from .tips import resample

        med = float(np.median(length[ok]))
        for i in np.nonzero(ok)[0]:
            h = 0.5 * (length[i] - med)
            X[i], Y[i] = resample(X[i], Y[i], h, length[i] - h, n_points)
    if smooth_frames:
        from .temporal import smooth_offsets

        w = int(smooth_frames) | 1
        if smoothing_allowed(w, 4, per_stroke):
            X, Y, _ = smooth_offsets(X, Y, ok, window=w, degree=4, positions=pos)
            temporal["smoothing"] = f"end offsets along the body, window {w} frames, quartic"
        else:
            temporal["smoothing"] = (f"not done: {per_stroke:.1f} frames per stroke, too few for a quartic over "
                                     f"{w} frames")
    if periodic and np.count_nonzero(ok) >= 2:
        from .periodic import periodic_shape_flagging

        try:
            X, Y, pinfo = periodic_shape_flagging(X, Y, ok, reason, per_stroke, positions=pos)
        except (np.linalg.LinAlgError, ValueError) as exc:  # a degenerate movie: the frames stay as they are
            pinfo = {"done": False, "reason": f"not done: the template fit failed ({exc})"}
        if "outlier_frame" in pinfo or re.search(r"\(frame \d+ is [\d.]+ px from the template", pinfo["reason"]):
            # (a run of frames far from the stroke: dust or debris the body passes over merges with it)
            pinfo["reason"] += ("; look at the frames around it: dust or debris on the body's path, or another "
                                "object passing, can merge with the body in a few frames")
        if times is None and pinfo["reason"].startswith("not done: the stroke is not periodic"):
            pinfo["reason"] += ("; if the camera dropped frames, give the frames' times (times, --times): a dropped "
                                "frame shifts every later one by a frame interval")
        temporal["periodic"] = pinfo["reason"]
        temporal["periodic_info"] = {k: v for k, v in pinfo.items() if k != "reason"}
    n_ok = int(np.count_nonzero(ok))
    counts: dict[str, int] = {}
    for rsn in reason:
        key = rsn.split(":")[0]
        counts[key] = counts.get(key, 0) + 1
    # (a bright hump of illumination read as 127 crossings and 19 gaps: no word named it)
    branched = ("most frames show a body branching or broken: a crossing filament, or a background that is not a "
                "plane (uneven illumination, a bright patch) taken for part of the body: flatten the frames' "
                "background first, or give roi (--roi) around the swimmer"
                if counts.get("crossing", 0) + counts.get("gap", 0) > T // 2 else "")
    if n_ok >= 2 and branched:
        warnings.warn(f"input={frames.source!r}: {n_ok} of {T} frames were tracked; {branched}", stacklevel=2)
    if n_ok < 2:
        why = ", ".join(f"{k} ({v})" for k, v in counts.items() if k)
        hint = ""
        if counts.get("lost contrast", 0) > T // 2:
            c = contrast[np.isfinite(contrast)]
            level = (f"; the ridge stands {float(np.median(c)):.2g} noise SD above the background (median over "
                     f"{c.size} frames; {min_contrast:g} needed): too noisy a movie, or") if c.size else \
                "; no frame showed a ridge above the noise: too noisy a movie (or no filament in view), or"
            hint = (f"{level} if the filament is brighter than its background, leave out dark_line (--dark-line)"
                    if dark_line else f"{level} if the filament is darker than its background, give dark_line=True "
                    "(--dark-line)")
        elif branched:
            hint = f"; {branched}"
        raise ParameterError(f"input={frames.source!r}: {n_ok} of {T} frames were tracked; at least 2 are required "
                             f"(failures: {why or 'none'}){hint}")
    Lgood = length[ok]
    L_px = float(np.median(Lgood))
    t_all = t0 + np.arange(T) / fps if times is None else times
    scale = 1.0 / px_per_mm
    frames_info = {
        "t": t_all, "x_px": X, "y_px": Y, "length_px": length, "contrast": contrast, "ok": ok,
        "reason": reason, "match_px": match,
    }
    if n_clipped:
        warnings.warn(f"input={frames.source!r}: {n_clipped} of {T} frames have pixels clipped at their largest "
                      "value (saturated); the line ends are fitted with them as at least that value, but a clipped line's blur is "
                      "measured too wide: lower the exposure, or give the blur (sigma, --sigma)", stacklevel=2)
    unchanged = still.fraction()
    if unchanged > _MAX_UNCHANGED:
        warnings.warn(f"input={frames.source!r}: {100 * unchanged:.0f}% of the pixels keep their exact value from "
                      "one frame to the next (median over frame pairs; a camera's noise changes them): a lossy "
                      "codec skipped them, or the movie has no noise; heavy compression removes detail with the "
                      "noise and moves the ends by several % (encode at CRF <= 18, or lossless)", stacklevel=2)
    meta = {
        "source": frames.source, "px_per_mm": px_per_mm, "fps": fps, "roi": frames.roi,
        "times_given": times is not None,  # the frames' own times (timestamps), not index / fps
        # a folder's frame files in the order tracked (by the numbers in their names)
        **({"frame_files": list(frames.names)} if frames.names else {}),
        "unchanged_fraction": unchanged,
        "frame_shape": frames.shape, "dark_line": bool(dark_line), "n_frames": T, "psf_sigma_px": sig, "n_failed": T - n_ok,
        "n_clipped": n_clipped,
        "length_px": L_px, "length_std_px": float(np.std(Lgood, ddof=1)) if n_ok > 1 else 0.0,
        "length_spread": float((Lgood.max() - Lgood.min()) / L_px), "wall_time_s": wall,
        "frames": frames_info, "temporal": temporal,
    }
    template = temporal.get("periodic_info", {})
    if template.get("done") and "end_residual_px" in template:
        # standard error of the template's harmonic coefficients at each end [mm]: noise that
        # every cycle shares (describe tests the harmonics it borrows against it)
        meta["template_coef_se"] = [float(r * math.sqrt(2.0 / template["template_frames"]) * scale)
                                    for r in template["end_residual_px"]]
        # the same with the template's degrees of freedom and the ends' correlation from frame to
        # frame, in the lab frame (registration noise included): for the descriptors' standard
        # errors (the harmonic tests keep the plain scale above, which they were set against)
        if "end_coef_stderr_px" in template:
            meta["template_coef_stderr"] = [float(v * scale) for v in template["end_coef_stderr_px"]]
    return Track(t=t_all[ok], x=X[ok] * scale, y=Y[ok] * scale, s=np.linspace(0.0, L_px * scale, n_points),
                 field_angle=field_angle, length=L_px * scale, units="mm", meta=meta)


def failures(tr: Track) -> list[tuple[int, float, str]]:
    """(frame index, time [s], reason) of every failed frame of a tracked movie."""
    info = tr.meta.get("frames")
    if info is None:
        return []
    return [(i, float(info["t"][i]), info["reason"][i]) for i in np.nonzero(~info["ok"])[0]]
