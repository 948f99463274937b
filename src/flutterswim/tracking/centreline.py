"""Sub-pixel centreline of a thin bright line in one frame.

Steps (pixel coordinates: x = column, y = row, pixel centres at integers):

1. skeleton of the segmented mask (skimage.morphology.skeletonize) and its longest path
   (8-connected graph, two Dijkstra sweeps: the path between the two mutually farthest ends);
2. least-squares cubic spline x(s), y(s) with knots every ``knot_px`` px of arc length;
3. ridge refinement: along the normal at points every px (the curve extended by its tangent
   beyond both skeleton ends), the matched-filtered profile p(d) is sampled at d in
   [-w, w]; the peak is located by a least-squares parabola fit of log p near its maximum
   (exact for a Gaussian profile); points whose peak is below half the plateau are dropped;
   the spline is refitted (twice);
4. tips: along the curve and its tangent extension the ridge intensity is sampled every
   0.05 px; each end is where it falls to half the plateau (the true end of a line blurred by
   a symmetric PSF sits at half maximum), by linear interpolation;
5. the curve between the two tips resampled at ``n_points`` equal arc-length steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage as ndi
from scipy.interpolate import make_lsq_spline

__all__ = ["Centreline", "longest_skeleton_path", "fit_centreline"]

_OFFS = [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)]


@dataclass(frozen=True, eq=False)
class Centreline:
    """x, y: (n_points,) sub-pixel centreline, tip to tip; length [px]; plateau: ridge
    intensity (filtered units); branch_fraction: share of skeleton pixels off the longest
    path; ok/reason: failure flag."""

    x: np.ndarray
    y: np.ndarray
    length: float
    plateau: float
    branch_fraction: float
    ok: bool
    reason: str


def longest_skeleton_path(skel: np.ndarray) -> np.ndarray:
    """(H, W) bool skeleton -> (K, 2) (row, col) pixels of the longest geodesic path
    (8-neighbour steps of length 1 or sqrt 2; exact for a tree, the diameter estimate by a
    double sweep otherwise)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    rr, cc = np.nonzero(skel)
    n = rr.size
    if n < 2:
        return np.stack([rr, cc], axis=1)
    H, W = skel.shape
    index = -np.ones((H + 2, W + 2), dtype=np.int64)
    index[rr + 1, cc + 1] = np.arange(n)
    src, dst, wt = [], [], []
    for dr, dc in _OFFS:
        j = index[rr + 1 + dr, cc + 1 + dc]
        ok = j >= 0
        src.append(np.nonzero(ok)[0])
        dst.append(j[ok])
        wt.append(np.full(int(ok.sum()), math.sqrt(2.0) if dr and dc else 1.0))
    g = coo_matrix((np.concatenate(wt), (np.concatenate(src), np.concatenate(dst))), shape=(n, n)).tocsr()
    d0 = dijkstra(g, indices=0)
    d0[~np.isfinite(d0)] = -1
    a = int(np.argmax(d0))
    da, pred = dijkstra(g, indices=a, return_predecessors=True)
    da[~np.isfinite(da)] = -1
    b = int(np.argmax(da))
    path = [b]
    while path[-1] != a:
        path.append(int(pred[path[-1]]))
    path = np.array(path[::-1])
    return np.stack([rr[path], cc[path]], axis=1)


def _arclength(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])


def _lsq(s: np.ndarray, x: np.ndarray, y: np.ndarray, knot_px: float):
    """Least-squares cubic splines x(s), y(s), interior knots every ~knot_px."""
    L = s[-1] - s[0]
    m = max(0, int(L / knot_px) - 1)
    inner = np.linspace(s[0], s[-1], m + 2)[1:-1]
    t = np.concatenate([[s[0]] * 4, inner, [s[-1]] * 4])
    try:
        return make_lsq_spline(s, x, t, k=3), make_lsq_spline(s, y, t, k=3)
    except (ValueError, np.linalg.LinAlgError):
        t = np.concatenate([[s[0]] * 4, [s[-1]] * 4])
        return make_lsq_spline(s, x, t, k=3), make_lsq_spline(s, y, t, k=3)


def _eval(sx, sy, s0: float, s1: float, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points and unit tangents at parameters q, the spline continued linearly (by its end
    tangents) outside [s0, s1]."""
    qc = np.clip(q, s0, s1)
    x, y = sx(qc), sy(qc)
    tx, ty = sx.derivative()(qc), sy.derivative()(qc)
    nrm = np.hypot(tx, ty)
    nrm[nrm == 0] = 1.0
    tx, ty = tx / nrm, ty / nrm
    over = q - qc
    return x + over * tx, y + over * ty, tx, ty


class _Bicubic:
    """Bicubic spline interpolation of an image, the spline prefiltered once (as
    ``ndi.map_coordinates(f, ..., order=3, mode="nearest")`` does on every call: the image
    padded by 12 edge values, then filtered)."""

    _PAD = 12

    def __init__(self, f: np.ndarray) -> None:
        self.coef = ndi.spline_filter(np.pad(f, self._PAD, mode="edge"), 3, output=np.float64, mode="nearest")

    def __call__(self, y: np.ndarray, x: np.ndarray) -> np.ndarray:
        return ndi.map_coordinates(self.coef, [y + self._PAD, x + self._PAD], order=3, mode="nearest",
                                   prefilter=False)


def _ridge_offsets(f: _Bicubic, x: np.ndarray, y: np.ndarray, nx: np.ndarray, ny: np.ndarray,
                   half_width: float, step: float = 0.25, fit_px: float = 1.5
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Peak offset along the normal (px), peak value and Gaussian width (px), each (M,).

    The profile p(d) of the image (``f``, its bicubic interpolator) along each normal is sampled at d in
    [-half_width, half_width] step ``step``; around its maximum d_m, log p is fitted by a
    least-squares parabola a + b u + c u^2 (u = d - d_m) over |u| <= fit_px where
    p > 0.6 max p (exact for a Gaussian profile: peak at d_m - b/2c, width sqrt(-1/2c)).
    Rows without a valid fit get NaN offsets."""
    d = np.arange(-half_width, half_width + 1e-9, step)
    px = x[:, None] + d[None, :] * nx[:, None]
    py = y[:, None] + d[None, :] * ny[:, None]
    p = f(py.ravel(), px.ravel()).reshape(px.shape)
    M = p.shape[0]
    i = np.argmax(p, axis=1)
    pk = p[np.arange(M), i]
    u = d[None, :] - d[i][:, None]
    w = (np.abs(u) <= fit_px + 1e-9) & (p > 0.6 * pk[:, None]) & (p > 0)
    lp = np.log(np.where(w, p, 1.0))
    wf = w.astype(float)
    S = [np.sum(wf * u**k, axis=1) for k in range(5)]
    T = [np.sum(wf * lp * u**k, axis=1) for k in range(3)]
    A = np.stack([np.stack([S[0], S[1], S[2]], -1), np.stack([S[1], S[2], S[3]], -1),
                  np.stack([S[2], S[3], S[4]], -1)], -2)
    rhs = np.stack(T, -1)
    good = (S[0] >= 3) & (pk > 0)
    A[~good] = np.eye(3)
    rhs[~good] = 0.0
    coef = np.linalg.solve(A, rhs[..., None])[..., 0]
    c0, c1, c2 = coef[:, 0], coef[:, 1], coef[:, 2]
    good &= c2 < 0
    c2s = np.where(good, c2, -1.0)
    shift = -c1 / (2 * c2s)
    good &= np.abs(shift) <= 1.0
    off = np.where(good, d[i] + shift, np.nan)
    val = np.where(good, np.exp(c0 - c1 * c1 / (4 * c2s)), pk)
    wid = np.where(good, np.sqrt(-1.0 / (2 * c2s)), np.nan)
    return off, val, wid


def _half_crossing(q: np.ndarray, v: np.ndarray, level: float, outward: int) -> float:
    """Parameter where v (sampled at increasing q) falls below ``level`` for good when walking
    from the middle outwards (outward = +1: towards larger q; -1: smaller)."""
    above = v >= level
    if outward > 0:
        idx = np.nonzero(above)[0]
        if idx.size == 0:
            return math.nan
        j = idx[-1]
        if j + 1 >= q.size:
            return float(q[-1])
        v0, v1 = v[j], v[j + 1]
        return float(q[j] + (v0 - level) / (v0 - v1) * (q[j + 1] - q[j]))
    idx = np.nonzero(above)[0]
    if idx.size == 0:
        return math.nan
    j = idx[0]
    if j == 0:
        return float(q[0])
    v0, v1 = v[j], v[j - 1]
    return float(q[j] - (v0 - level) / (v0 - v1) * (q[j] - q[j - 1]))


def _edge_fit(q: np.ndarray, v: np.ndarray, q0: float, plateau: float, sigma: float,
              outward: int, inner: float = 8.0, outer: float = 5.0) -> float:
    """Refine the end q0 by least squares of the blurred-step model
    v(q) = P Phi(-outward (q - q_end) / sigma) (Phi the normal CDF; plateau P and blur sigma
    known from the body) over the samples in [q0 - inner, q0 + outer] (mirrored for the start
    end): one parameter, q_end. Returns q0 if the fit moves the end by more than 3 px."""
    from scipy.optimize import minimize_scalar
    from scipy.special import ndtr

    if outward > 0:
        sel = (q >= q0 - inner) & (q <= q0 + outer)
    else:
        sel = (q >= q0 - outer) & (q <= q0 + inner)
    qs, vs = q[sel], v[sel]
    if qs.size < 20:
        return q0

    def cost(qe: float) -> float:
        return float(np.sum((vs - plateau * ndtr(-outward * (qs - qe) / sigma)) ** 2))

    res = minimize_scalar(cost, bounds=(q0 - 3.0, q0 + 3.0), method="bounded",
                          options={"xatol": 1e-3})
    qe = float(res.x)
    return qe if abs(qe - q0) < 2.99 else q0


def fit_centreline(filtered: np.ndarray, mask: np.ndarray, *, n_points: int = 49,
                   knot_px: float = 10.0, extend_px: float = 8.0, min_length_px: float = 10.0,
                   half_width: float = 3.0, edge_fit: bool = True,
                   max_gap_px: float = 4.0) -> Centreline:
    """Sub-pixel centreline (n_points, tip to tip) of the line in ``mask`` on the
    matched-filtered frame ``filtered`` (background ~0). See the module docstring."""
    from skimage.morphology import skeletonize

    nan = np.full(n_points, np.nan)
    rows, cols = np.nonzero(mask)
    pad = int(extend_px + half_width + 4)
    r0, c0 = max(rows.min() - pad, 0), max(cols.min() - pad, 0)
    r1, c1 = min(rows.max() + pad + 1, mask.shape[0]), min(cols.max() + pad + 1, mask.shape[1])
    sub_m = mask[r0:r1, c0:c1]
    f = _Bicubic(np.ascontiguousarray(filtered[r0:r1, c0:c1], dtype=np.float64))
    skel = skeletonize(sub_m)
    path = longest_skeleton_path(skel)
    n_skel = int(skel.sum())
    branch = 1.0 - path.shape[0] / max(n_skel, 1)
    if path.shape[0] < 4:
        return Centreline(nan, nan, math.nan, math.nan, branch, False, "too short (skeleton)")
    y, x = path[:, 0].astype(float), path[:, 1].astype(float)
    s = _arclength(x, y)
    if s[-1] < min_length_px:
        return Centreline(nan, nan, float(s[-1]), math.nan, branch, False, "too short")
    sx, sy = _lsq(s, x, y, knot_px)
    lo, hi = 0.0, float(s[-1])
    plateau = math.nan
    for _ in range(2):
        q = np.arange(lo - extend_px, hi + extend_px + 1e-9, 1.0)
        px, py, tx, ty = _eval(sx, sy, lo, hi, q)
        off, val, wid = _ridge_offsets(f, px, py, -ty, tx, half_width)
        core = (q >= lo) & (q <= hi)
        mid = core & (q >= lo + 0.2 * (hi - lo)) & (q <= hi - 0.2 * (hi - lo))
        body = mid if np.any(mid) else core
        plateau = float(np.median(val[body]))
        sigma_t = float(np.nanmedian(wid[body])) if np.any(np.isfinite(wid[body])) else 1.7
        keep = np.isfinite(off) & (val > 0.5 * plateau)
        if keep.sum() < 6:
            return Centreline(nan, nan, math.nan, plateau, branch, False, "lost ridge")
        # keep the run of good points around the middle, bridging dips up to max_gap_px
        bridged = ndi.binary_closing(keep, structure=np.ones(2 * int(max_gap_px) + 1, bool))
        bridged |= keep
        lab, _ = ndi.label(bridged)
        imid = int(np.argmin(np.abs(q - 0.5 * (lo + hi))))
        if lab[imid] == 0:
            return Centreline(nan, nan, math.nan, plateau, branch, False, "gap in the ridge")
        keep &= lab == lab[imid]
        rx = px[keep] - off[keep] * ty[keep]
        ry = py[keep] + off[keep] * tx[keep]
        s = _arclength(rx, ry)
        sx, sy = _lsq(s, rx, ry, knot_px)
        lo, hi = 0.0, float(s[-1])
    # tips: ridge intensity along the curve and its tangent extension
    step = 0.05
    q = np.arange(lo - extend_px, hi + extend_px + 1e-9, step)
    px, py, tx, ty = _eval(sx, sy, lo, hi, q)
    v = f(py, px)
    level = 0.5 * plateau
    imid = q.size // 2
    qa = _half_crossing(q[: imid + 1], v[: imid + 1], level, -1)
    qb = _half_crossing(q[imid:], v[imid:], level, +1)
    if not (np.isfinite(qa) and np.isfinite(qb)) or qb - qa < min_length_px:
        return Centreline(nan, nan, math.nan, plateau, branch, False, "tips not found")
    if edge_fit:
        qa = _edge_fit(q, v, qa, plateau, sigma_t, -1)
        qb = _edge_fit(q, v, qb, plateau, sigma_t, +1)
    # resample the curve between the tips at equal arc length
    qq = np.linspace(qa, qb, 8 * n_points)
    X, Y, _, _ = _eval(sx, sy, lo, hi, qq)
    sa = _arclength(X, Y)
    L = float(sa[-1])
    su = np.linspace(0.0, L, n_points)
    xo = np.interp(su, sa, X) + c0
    yo = np.interp(su, sa, Y) + r0
    return Centreline(xo, yo, L, plateau, branch, True, "")
