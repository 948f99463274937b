"""Compiled scalar kernels for the reduced characteristic function and root following.

numba (cache=True) when available; otherwise the same functions run as plain Python and
callers use the vectorised numpy path instead (see ``HAVE_NUMBA``).
"""

from __future__ import annotations

import math

import numpy as np

try:  # pragma: no cover - exercised implicitly
    import numba

    HAVE_NUMBA = True
    _jit = numba.njit(cache=True, fastmath=False)
    _pjit = numba.njit(cache=True, parallel=True)
    prange = numba.prange
except ImportError:  # pragma: no cover
    HAVE_NUMBA = False

    def _jit(f):
        return f

    _pjit = _jit
    prange = range

SEP_TOL = 1e-4
NCIRCLE = 8


@_jit
def _aberth(c, q, lam, maxit):
    """Polish (in place) the roots of z^4 + c z^3 + q by Aberth iteration; True if converged."""
    scale = max(abs(c), abs(q) ** 0.25, 1.0)
    done = False
    for _ in range(maxit):
        maxw = 0.0
        for i in range(4):
            z = lam[i]
            z2 = z * z
            p = z2 * z2 + c * z2 * z + q
            if p == 0:
                continue
            dp = 4.0 * z2 * z + 3.0 * c * z2
            s = 0j
            for j in range(4):
                if j != i:
                    d = z - lam[j]
                    if d == 0:
                        d = 1e-300 + 0j
                    s += 1.0 / d
            den = dp - p * s
            if den == 0:
                den = 1e-300 + 0j
            w = p / den
            lam[i] = z - w
            aw = abs(w)
            if aw > maxw:
                maxw = aw
        if not math.isfinite(maxw):
            return False
        if done:
            return True
        if maxw <= 1e-9 * scale:
            done = True  # one more sweep: cubic convergence gives full precision
    return False


@_jit
def _cold_roots(c, q, lam):
    scale = max(abs(c), abs(q) ** 0.25, 1.0)
    for k in range(4):
        ang = 0.4 + 2.0 * math.pi * k / 4.0
        lam[k] = 1.3 * scale * complex(math.cos(ang), math.sin(ang))
    return _aberth(c, q, lam, 150)


@_jit
def _roots(omega, chi, eta, lam, warm):
    c = chi / (omega + 1.0)
    q = eta * omega
    ok = False
    if warm:
        ok = _aberth(c, q, lam, 40)
    if not ok:
        ok = _cold_roots(c, q, lam)
    return ok


@_jit
def _closed(omega, chi, eta, lam):
    """g, dg/domega, dg/dchi (all times e^{-2m}), m, relative root separation (roots in lam)."""
    c = chi / (omega + 1.0)
    dc = -chi / ((omega + 1.0) * (omega + 1.0))
    m = lam[0].real
    big = abs(lam[0])
    for i in range(1, 4):
        if lam[i].real > m:
            m = lam[i].real
        if abs(lam[i]) > big:
            big = abs(lam[i])
    ex = np.empty(4, dtype=np.complex128)
    for i in range(4):
        ex[i] = np.exp(lam[i] - m)
    B = 0j
    dB = np.zeros(4, dtype=np.complex128)
    for k in range(3):
        if k == 0:
            a, b, cc, d, s = 0, 1, 2, 3, 1.0
        elif k == 1:
            a, b, cc, d, s = 0, 2, 1, 3, -1.0
        else:
            a, b, cc, d, s = 0, 3, 1, 2, 1.0
        p1 = ex[a] - ex[b]
        p2 = ex[cc] - ex[d]
        w = lam[a] * lam[b] + lam[cc] * lam[d]
        B += s * p1 * p2 * w
        dB[a] += s * (ex[a] * p2 * w + p1 * p2 * lam[b])
        dB[b] += s * (-ex[b] * p2 * w + p1 * p2 * lam[a])
        dB[cc] += s * (p1 * ex[cc] * w + p1 * p2 * lam[d])
        dB[d] += s * (-p1 * ex[d] * w + p1 * p2 * lam[cc])
    V = -1.0 + 0j
    sep = np.inf
    for i in range(4):
        for j in range(i + 1, 4):
            d = lam[j] - lam[i]
            V *= d
            if abs(d) < sep:
                sep = abs(d)
    sep /= max(big, 1.0)
    if sep < SEP_TOL:
        return 0j, 0j, 0j, m, sep
    g = B / V
    dg = 0j
    dgc = 0j
    for i in range(4):
        s = 0j
        for j in range(4):
            if j != i:
                s += 1.0 / (lam[i] - lam[j])
        li = lam[i]
        l2 = li * li
        den = 4.0 * l2 * li + 3.0 * c * l2
        dgi = dB[i] / V - g * s
        dg += dgi * (-(dc * l2 * li + eta) / den)
        dgc += dgi * (-(l2 * li / (omega + 1.0)) / den)
    return g, dg, dgc, m, sep


@_jit
def _gval(omega, chi, eta, lam, warm):
    """(g, dg/domega, dg/dchi) scaled by e^{-2m}, and m; circle mean near coinciding roots."""
    if omega + 1.0 == 0:
        return complex(np.nan, np.nan), complex(np.nan, np.nan), complex(np.nan, np.nan), 0.0
    ok = _roots(omega, chi, eta, lam, warm)
    if ok:
        g, dg, dgc, m, sep = _closed(omega, chi, eta, lam)
        if sep >= SEP_TOL and math.isfinite(abs(g)) and math.isfinite(abs(dg)):
            return g, dg, dgc, m
    delta = min(1e-3 * max(abs(omega), 1.0), 0.05 * abs(omega + 1.0))
    tmp = np.empty(4, dtype=np.complex128)
    gk = np.empty(NCIRCLE, dtype=np.complex128)
    gck = np.empty(NCIRCLE, dtype=np.complex128)
    mk = np.empty(NCIRCLE)
    zk = np.empty(NCIRCLE, dtype=np.complex128)
    mref = -np.inf
    for k in range(NCIRCLE):
        ang = 2.0 * math.pi * (k + 0.5) / NCIRCLE
        z = complex(math.cos(ang), math.sin(ang))
        zk[k] = z
        _cold_roots(chi / (omega + delta * z + 1.0), eta * (omega + delta * z), tmp)
        g1, _, gc1, m1, _ = _closed(omega + delta * z, chi, eta, tmp)
        gk[k] = g1
        gck[k] = gc1
        mk[k] = m1
        if m1 > mref:
            mref = m1
    g = 0j
    dg = 0j
    dgc = 0j
    for k in range(NCIRCLE):
        fac = math.exp(2.0 * (mk[k] - mref))
        v = gk[k] * fac
        g += v
        dg += v / zk[k]
        dgc += gck[k] * fac
    return g / NCIRCLE, dg / (NCIRCLE * delta), dgc / NCIRCLE, mref


@_jit
def _newton(omega, chi, eta, lam, warm, tol, maxit):
    """Newton on g from omega; returns (omega, iterations) with iterations = -1 if not converged."""
    for it in range(maxit):
        g, dg, _, m = _gval(omega, chi, eta, lam, warm)
        warm = True
        if dg == 0 or not math.isfinite(abs(g)) or not math.isfinite(abs(dg)):
            return omega, -1
        step = -g / dg
        # keep away from the essential singularity at omega = -1
        lim = 0.5 * abs(omega + 1.0)
        if abs(step) > lim:
            step *= lim / abs(step)
        omega = omega + step
        if abs(step) <= tol * max(abs(omega), 1.0):
            return omega, it + 1
    return omega, -1


@_jit
def _follow(etas, chis, w0, tol, maxit, out, iters):
    """Follow one root along the path (etas[k], chis[k]) from w0 (a root at point 0)."""
    n = etas.shape[0]
    lam = np.empty(4, dtype=np.complex128)
    warm = False
    w1 = w0
    w2 = w0
    for k in range(n):
        if k >= 2:
            dp1 = abs(etas[k] - etas[k - 1]) + abs(chis[k] - chis[k - 1])
            dp0 = abs(etas[k - 1] - etas[k - 2]) + abs(chis[k - 1] - chis[k - 2])
            guess = w1 + (w1 - w2) * (dp1 / dp0) if dp0 > 0 else w1
        else:
            guess = w1
        w, it = _newton(guess, chis[k], etas[k], lam, warm, tol, maxit)
        warm = True
        if it < 0 and k > 0:
            # substeps between the previous point and this one
            w = w1
            it = 0
            nsub = 16
            for sidx in range(1, nsub + 1):
                t = sidx / nsub
                e = etas[k - 1] + t * (etas[k] - etas[k - 1])
                ch = chis[k - 1] + t * (chis[k] - chis[k - 1])
                w, it2 = _newton(w, ch, e, lam, True, tol, maxit)
                if it2 < 0:
                    it = -1
                    break
                it += it2
        if it < 0:
            out[k] = complex(np.nan, np.nan)
            iters[k] = -1
            continue
        if w.imag < 0:
            w = complex(w.real, -w.imag)
            for i in range(4):
                lam[i] = lam[i].conjugate()
        out[k] = w
        iters[k] = it
        w2 = w1 if k > 0 else w
        w1 = w


@_pjit
def _follow_columns(etas, chis, seeds, tol, maxit, out, iters):
    """For each etas[i] follow from seeds[i] (root at chis[0]) along chis; out (ne, nc)."""
    ne = etas.shape[0]
    nc = chis.shape[0]
    for i in prange(ne):
        e = np.full(nc, etas[i])
        _follow(e, chis, seeds[i], tol, maxit, out[i], iters[i])


@_jit
def _newton_serial(w0, chis, etas, tol, maxit, out, iters):
    """As _newton_batch without threads (a parallel launch costs milliseconds)."""
    lam = np.empty(4, dtype=np.complex128)
    for i in range(w0.shape[0]):
        w, it = _newton(w0[i], chis[i], etas[i], lam, False, tol, maxit)
        out[i] = w
        iters[i] = it


@_pjit
def _newton_batch(w0, chis, etas, tol, maxit, out, iters):
    for i in prange(w0.shape[0]):
        lam = np.empty(4, dtype=np.complex128)
        w, it = _newton(w0[i], chis[i], etas[i], lam, False, tol, maxit)
        out[i] = w
        iters[i] = it


@_pjit
def _gval_batch(w, chis, etas, g, dg, dgc, m):
    for i in prange(w.shape[0]):
        lam = np.empty(4, dtype=np.complex128)
        g[i], dg[i], dgc[i], m[i] = _gval(w[i], chis[i], etas[i], lam, False)


@_jit
def _hopf_newton(chi, beta, eta, lam, warm, tol, maxit):
    """Solve g(i beta; chi, eta) = 0 for real (chi, beta); returns (chi, beta, iterations or -1)."""
    for it in range(maxit):
        g, dg, dgc, m = _gval(complex(0.0, beta), chi, eta, lam, warm)
        warm = True
        # columns: d/dchi -> dgc, d/dbeta -> i dg
        a11 = dgc.real
        a21 = dgc.imag
        db = 1j * dg
        a12 = db.real
        a22 = db.imag
        det = a11 * a22 - a12 * a21
        if det == 0 or not math.isfinite(det):
            return chi, beta, -1
        dchi = -(a22 * g.real - a12 * g.imag) / det
        dbeta = -(-a21 * g.real + a11 * g.imag) / det
        chi += dchi
        beta += dbeta
        if abs(dchi) <= tol * max(abs(chi), 1.0) and abs(dbeta) <= tol * max(abs(beta), 1.0):
            return chi, abs(beta), it + 1
    return chi, abs(beta), -1


@_jit
def _neutral_follow(etas, chi0, beta0, tol, maxit, chi_max, out_chi, out_beta, iters):
    """Continue the Hopf point (chi, beta) along etas from a solution at etas[0]."""
    lam = np.empty(4, dtype=np.complex128)
    warm = False
    c1 = chi0
    b1 = beta0
    c2 = chi0
    b2 = beta0
    for k in range(etas.shape[0]):
        if k >= 2 and math.isfinite(c2):
            r = (etas[k] - etas[k - 1]) / (etas[k - 1] - etas[k - 2])
            cg = c1 + (c1 - c2) * r
            bg = b1 + (b1 - b2) * r
        else:
            cg = c1
            bg = b1
        c, b, it = _hopf_newton(cg, bg, etas[k], lam, warm, tol, maxit)
        warm = True
        if it < 0 or not (abs(c) <= chi_max):
            for j in range(k, etas.shape[0]):
                out_chi[j] = np.nan
                out_beta[j] = np.nan
                iters[j] = -1
            return
        out_chi[k] = c
        out_beta[k] = b
        iters[k] = it
        c2 = c1
        b2 = b1
        c1 = c
        b1 = b
