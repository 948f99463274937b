"""Per-frame segmentation of a thin bright line: matched filter, robust thresholds, the
largest connected component.

Matched filter: F = G_sigma * I - B (a Gaussian of the line's width minus a broad background
B: the frame's least-squares plane plus a broad Gaussian of the rest, computed on a 4x-reduced
image, so that a background rising across the frame stays level to its edges).
Noise: sd = 1.4826 MAD(F) about median(F) (the line covers a small fraction of the frame, so
median and MAD are those of the background). Hysteresis thresholds: median + k_low sd and
median + k_high sd.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage as ndi

__all__ = ["Segmentation", "background_plane", "matched_filter", "robust_noise", "segment", "clean_hot_pixels", "clean_frame"]


@dataclass(frozen=True, eq=False)
class Segmentation:
    """filtered: (H, W) matched-filtered frame; mask: (H, W) bool, the largest component
    (None if nothing passed the thresholds); median, noise: background level and sd of
    ``filtered``; n_components: components that passed; ok/reason: failure flag."""

    filtered: np.ndarray
    mask: np.ndarray | None
    median: float
    noise: float
    n_components: int
    ok: bool
    reason: str


BACKGROUND_SIGMA = 16.0  # px: the matched filter's broad background estimate


def _plane(small: np.ndarray) -> np.ndarray:
    """Coefficients (c, c_row, c_col) of the least-squares plane through a (reduced) frame,
    about its centre, without its bright objects: fitted again without the blocks more than 3
    robust SD above the first plane (the line and debris, a large share of a small frame's
    light, would tilt it)."""
    Hc, Wc = small.shape
    r = (np.arange(Hc) - 0.5 * (Hc - 1))[:, None]
    c = (np.arange(Wc) - 0.5 * (Wc - 1))[None, :]
    v = np.asarray(small, np.float64)
    # all blocks: the grid's columns are orthogonal
    coef = np.array([v.mean(), np.sum(r * v) / (Wc * np.sum(r * r)), np.sum(c * v) / (Hc * np.sum(c * c))])
    res = v - (coef[0] + coef[1] * r + coef[2] * c)
    med = float(np.median(res))
    sd = 1.4826 * float(np.median(np.abs(res - med)))
    keep = res <= med + 3.0 * sd
    if not sd > 0 or keep.all() or keep.sum() < 3:
        return coef
    rr, cc = np.broadcast_to(r, v.shape)[keep], np.broadcast_to(c, v.shape)[keep]
    X = np.stack([np.ones_like(rr), rr, cc])
    return np.linalg.solve(X @ X.T, X @ v[keep])


def _plane_at(coef: np.ndarray, shape: tuple[int, int], reduced: tuple[int, int], k: int) -> np.ndarray:
    """The plane ``coef`` of a frame reduced k x k to ``reduced`` at the full frame's pixels
    (reduced pixel i spans full pixels k i .. k i + k - 1)."""
    (H, W), (Hc, Wc) = shape, reduced
    r = ((np.arange(H) + 0.5) / k - 0.5 - 0.5 * (Hc - 1))[:, None]
    c = ((np.arange(W) + 0.5) / k - 0.5 - 0.5 * (Wc - 1))[None, :]
    return coef[0] + coef[1] * r + coef[2] * c


def _reduced(a: np.ndarray, k: int) -> np.ndarray:
    """Means of the frame's k x k blocks (the last partial rows and columns left out)."""
    Hc, Wc = a.shape[0] // k, a.shape[1] // k
    return a[: Hc * k, : Wc * k].reshape(Hc, k, Wc, k).mean(axis=(1, 3))


def background_plane(img: np.ndarray, k: int = 4) -> np.ndarray:
    """(H, W) float32: the least-squares plane through the frame's k x k block means (zeros for
    a frame under 4 k px a side). The line holds a small share of the frame's light and tilts
    it little; a background that rises across the frame (uneven illumination) it follows."""
    a = np.asarray(img, dtype=np.float32)
    if a.shape[0] // k < 4 or a.shape[1] // k < 4:
        return np.zeros(a.shape, np.float32)
    small = _reduced(a, k)
    return _plane_at(_plane(small), a.shape, small.shape, k).astype(np.float32)


def matched_filter(img: np.ndarray, sigma: float = 1.2, background_sigma: float = BACKGROUND_SIGMA,
                   plane: np.ndarray | None = None) -> np.ndarray:
    """(H, W) -> (H, W) float32: G_sigma * img minus a broad background estimate.

    The broad estimate smooths the frame less its plane (:func:`background_plane`, or
    ``plane`` when given) and adds the plane back: a Gaussian leaves a plane as it is inside
    the frame but flattens it at the edges (the frame continued by its edge values), where a
    background slope of 0.1 noise sd per px (a camera's bright background with a 30 % gradient)
    left bands of 45 sd along the edges, taken for the body ("out of view")."""
    a = np.asarray(img, dtype=np.float32)
    f = ndi.gaussian_filter(a, sigma, mode="nearest")
    k = 4
    H, W = a.shape
    Hc, Wc = H // k, W // k
    if Hc >= 4 and Wc >= 4:
        if plane is None:
            plane = background_plane(a, k)
        small = ndi.gaussian_filter(_reduced(a - plane, k), background_sigma / k, mode="nearest")
        zr = np.clip((np.arange(H) + 0.5) / k - 0.5, 0, Hc - 1)
        zc = np.clip((np.arange(W) + 0.5) / k - 0.5, 0, Wc - 1)
        # separable linear interpolation back to full size
        r0 = np.floor(zr).astype(int)
        c0 = np.floor(zc).astype(int)
        r1, c1 = np.minimum(r0 + 1, Hc - 1), np.minimum(c0 + 1, Wc - 1)
        fr, fc = (zr - r0)[:, None], (zc - c0)[None, :]
        rows = small[r0] * (1 - fr) + small[r1] * fr
        bg = rows[:, c0] * (1 - fc) + rows[:, c1] * fc + plane
    else:
        bg = ndi.gaussian_filter(a, background_sigma, mode="nearest")
    return (f - bg).astype(np.float32)


def clean_hot_pixels(img: np.ndarray, k: float = 8.0) -> np.ndarray:
    """The frame with isolated bright pixels and pairs of them (a camera's hot pixels, cosmic
    rays) replaced by their neighbourhood: a pixel is hot when it exceeds all 8 neighbours by
    more than ``k`` noise standard deviations (from the differences of horizontally adjacent
    pixels) and by more than half its height over the frame's median, and replaced by the
    brightest neighbour; two touching pixels, each the other's brightest neighbour, are a hot
    pair when both exceed all the pair's other neighbours by as much (both then take the
    brightest of those); likewise 3 or 4 touching pixels within a 2 x 2 box (:func:`_hot_clusters`).
    A line blurred by the optics has neighbours as bright as itself along it and
    across it (at 1 px, 0.7 of its height for a blur of 1.2 px), so it is never touched.
    Returns ``img`` itself when nothing is hot."""
    a = np.asarray(img, dtype=np.float32)
    d = np.diff(a[:: max(1, a.size // 16384)], axis=1)  # about 16k differences
    sd = robust_noise(d)[1] / np.sqrt(2.0)
    if not sd > 0:
        return img
    med = float(np.median(a[::4, ::4]))
    # candidates: k sd over the median (the line and the spikes, a few pixels of the frame)
    r, c = np.nonzero(a > med + k * sd)
    if r.size == 0:
        return img
    p = np.pad(a, 1, mode="edge")
    offs = [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc]
    nbs = np.stack([p[r + 1 + dr, c + 1 + dc] for dr, dc in offs])  # (8, n)
    order = np.argsort(nbs, axis=0)
    nb1 = np.take_along_axis(nbs, order[-1:], 0)[0]
    nb2 = np.take_along_axis(nbs, order[-2:-1], 0)[0]
    v = a[r, c]

    def spike(ref: np.ndarray) -> np.ndarray:
        # over ref by k sd and by more than half its own height over the background: a
        # spike, not a noiseless ridge
        return (v - ref > k * sd) & (v - ref > 0.5 * (v - med))

    # pairs: two touching pixels, each the other's brightest neighbour, both over all the
    # pair's other neighbours as a lone hot pixel is over its own (a line's end pixel and the
    # next are not: the line goes on beyond the next)
    idx = -np.ones(a.shape, np.int64)
    idx[r, c] = np.arange(r.size)
    step = np.array(offs)[order[-1]]  # (n, 2): towards the brightest neighbour
    q = idx[np.clip(r + step[:, 0], 0, a.shape[0] - 1), np.clip(c + step[:, 1], 0, a.shape[1] - 1)]
    pair = (q >= 0) & (q != np.arange(r.size))
    qq = np.where(pair, q, 0)
    pair &= order[-1][qq] == 7 - order[-1]  # mutual: the offsets are listed symmetrically
    low = np.minimum(v, v[qq])
    other = np.maximum(nb2, nb2[qq])  # the brightest neighbour of the pair
    pair &= (low - other > k * sd) & (low - other > 0.5 * (low - med))
    hot = spike(nb1) & ~pair
    clusters = _hot_clusters(a, r, c, k * sd, med)
    if not (hot.any() or pair.any() or clusters):
        return img
    out = a.copy()
    out[r[hot], c[hot]] = nb1[hot]
    out[r[pair], c[pair]] = other[pair]
    for rows, cols, v in clusters:
        out[rows, cols] = v
    return out


def _hot_clusters(a: np.ndarray, r: np.ndarray, c: np.ndarray, step: float, med: float) -> list:
    """Clusters of 3 or 4 bright pixels within a 2 x 2 box (a sensor's hot cluster) among the
    candidates (r, c): each of them over every pixel around the box by more than ``step`` and by
    half its own height over ``med``. Returns (rows, cols, value) per cluster, the value the
    brightest pixel around it. A line is never one: it goes on beyond any 2 x 2 box."""
    H, W = a.shape
    m = np.zeros(a.shape, bool)
    m[r, c] = True
    lab, n = ndi.label(m, structure=np.ones((3, 3), bool))
    out = []
    for j, sl in enumerate(ndi.find_objects(lab), 1):
        if sl is None or sl[0].stop - sl[0].start > 2 or sl[1].stop - sl[1].start > 2:
            continue
        own = lab[sl] == j
        if np.count_nonzero(own) < 3:  # single pixels and pairs: clean_hot_pixels
            continue
        r0, r1 = max(sl[0].start - 1, 0), min(sl[0].stop + 1, H)
        c0, c1 = max(sl[1].start - 1, 0), min(sl[1].stop + 1, W)
        inner = np.zeros((r1 - r0, c1 - c0), bool)
        inner[sl[0].start - r0: sl[0].stop - r0, sl[1].start - c0: sl[1].stop - c0] = own
        box = a[r0:r1, c0:c1]
        low, ring = float(box[inner].min()), float(box[~inner].max())
        if low - ring > step and low - ring > 0.5 * (low - med):
            rows, cols = np.nonzero(inner)
            out.append((rows + r0, cols + c0, ring))
    return out


def clean_frame(img: np.ndarray) -> np.ndarray:
    """The frame made fit for segmentation: pixels that are not finite (NaN or inf, masked
    pixels of a float image) set to the median of the finite ones, then
    :func:`clean_hot_pixels`. A frame with no finite pixel is returned as zeros (no contrast)."""
    a = np.asarray(img)
    if a.dtype.kind == "f":
        good = np.isfinite(a)
        if not good.all():
            a = np.where(good, a, np.median(a[good]) if good.any() else 0.0).astype(np.float32)
    return clean_hot_pixels(a)


# a component lying at least this much on static objects is one (debris, a fibre, a bead)
_STATIC_SHARE = 0.8


def _moving_best(lab: np.ndarray, n: int, sums: np.ndarray, static: np.ndarray | None, min_pixels: int = 1) -> int:
    """Label (1..n) of the component with the most light ``sums`` (n + 1,), among those not lying
    on ``static`` objects (share >= _STATIC_SHARE) when any of at least ``min_pixels`` is not (a
    speck of noise is no body: a body at rest, itself static, lost 6 of 51 frames at SNR 5 to
    specks of a few pixels, then too small to be kept)."""
    best = int(np.argmax(sums[1:])) + 1
    if static is None or n < 2:
        return best
    on = np.bincount(lab.ravel(), weights=static.ravel(), minlength=n + 1)[1:]
    size = np.bincount(lab.ravel(), minlength=n + 1)[1:]
    moving = (on < _STATIC_SHARE * np.maximum(size, 1)) & (size >= min_pixels)
    if not moving.any() or moving[best - 1]:
        return best
    return int(np.nonzero(moving)[0][np.argmax(sums[1:][moving])]) + 1


def robust_noise(f: np.ndarray) -> tuple[float, float]:
    """(median, 1.4826 * median absolute deviation) of an array (subsampled if large)."""
    v = f.ravel()
    if v.size > 65536:
        v = v[:: v.size // 65536]
    med = float(np.median(v))
    return med, float(1.4826 * np.median(np.abs(v - med)))


def segment(img: np.ndarray, *, sigma: float = 1.2, k_low: float = 2.0, k_high: float = 5.0,
            min_pixels: int = 20, plane: np.ndarray | None = None, static: np.ndarray | None = None) -> Segmentation:
    """Matched filter, hysteresis threshold (skimage.filters.apply_hysteresis_threshold) at
    median + k sd, and the component with the largest summed filtered intensity (among those not
    lying on ``static`` objects, (H, W) bool, when any is not: debris that stays put); ``plane``:
    the frame's background plane, when already known (:func:`background_plane`)."""
    from skimage.filters import apply_hysteresis_threshold

    f = matched_filter(img, sigma, plane=plane)
    med, sd = robust_noise(f)
    if not sd > 0:
        return Segmentation(f, None, med, sd, 0, False, "flat frame (no noise, no contrast)")
    hyst = apply_hysteresis_threshold(f, med + k_low * sd, med + k_high * sd)
    lab, n = ndi.label(hyst, structure=np.ones((3, 3), bool))
    if n == 0:
        return Segmentation(f, None, med, sd, 0, False, "no component above the threshold")
    sums = np.bincount(lab.ravel(), weights=(f - med).ravel(), minlength=n + 1)
    mask = lab == _moving_best(lab, n, sums, static, min_pixels)
    if int(mask.sum()) < min_pixels:
        return Segmentation(f, None, med, sd, n, False, "no component above the threshold")
    return Segmentation(f, mask, med, sd, n, True, "")
