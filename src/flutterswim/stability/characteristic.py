"""Characteristic function of the linearised filament (paper appendix, eq. char_eq_f).

With r = R(s) e^{omega t}, kappa = -chi/(1+omega) R' and R = sum_i c_i exp(lambda_i s),
where lambda_i are the roots of the quartic (c = chi/(omega+1), q = eta_perp omega)

    p(lambda) = lambda^4 + c lambda^3 + q.

Free-end conditions give the 4x4 boundary matrix (:func:`boundary_matrix`) and the paper's

    f = (omega+1)^-4 prod(lambda_i) prod(lambda_i (omega+1) + chi) * bracket(lambda),

which equals (eta_perp omega)^2 * bracket, flips sign under a swap of two roots, equals
minus the determinant of the boundary matrix as printed (row order moment, shear), and
vanishes like omega^3 at omega = 0 (prefactor, and the triple root lambda = 0).
The reduced function used for root finding is order independent and has no spurious zeros,

    g(omega) = -bracket(lambda) / prod_{i<j} (lambda_j - lambda_i)
             = E[l1,l2,l3] E[l2,l3,l4] - E[l1,l2,l3,l4] E[l2,l3],

(E[...] divided differences of exp) so that f = -(eta_perp omega)^2 prod_{i<j}(lambda_j - lambda_i) g. g is also the
determinant of the 2x2 block Phi[0:2, 2:4] of Phi = expm(A), A the companion matrix of
the moment equation M'''' + c M''' + q M = 0 with M = M' = 0 at both ends
(:func:`reduced_char_expm`, an independent reference).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = [
    "quartic_roots",
    "char_f",
    "reduced_char",
    "reduced_char_expm",
    "boundary_matrix",
]

_PAIRS = ((0, 1, 2, 3, 1.0), (0, 2, 1, 3, -1.0), (0, 3, 1, 2, 1.0))
#: Relative root separation below which the closed form is replaced by a circle mean.
SEP_TOL = 1e-4


def _coeffs(omega, chi, eta_perp):
    omega = np.asarray(omega, dtype=complex)
    chi = np.asarray(chi, dtype=float)
    eta = np.asarray(eta_perp, dtype=float)
    omega, chi, eta = np.broadcast_arrays(omega, chi, eta)
    c = chi / (omega + 1.0)
    q = eta * omega
    return omega, chi, eta, c, q


def quartic_roots(omega, chi, eta_perp) -> np.ndarray:
    """Roots lambda (..., 4) of lambda^4 + chi/(omega+1) lambda^3 + eta_perp omega, sorted.

    Eigenvalues of the balanced companion matrix (backward stable, also for repeated
    roots, whose individual positions are then only sqrt(eps)-accurate; every function of
    the roots used here is symmetric and insensitive to that). Order: by real part, then
    imaginary part, after rounding to 1e-9 relative, so nearby parameters give the same order.
    """
    omega, chi, eta, c, q = _coeffs(omega, chi, eta_perp)
    shape = omega.shape
    c = c.reshape(-1)
    q = q.reshape(-1)
    # scale lambda = sigma mu so that the companion matrix has O(1) entries
    sigma = np.maximum(np.maximum(np.abs(c), np.abs(q) ** 0.25), 1.0)
    sigma = np.where(np.isfinite(sigma), sigma, 1.0)
    C = np.zeros((c.size, 4, 4), dtype=complex)
    C[:, 1, 0] = C[:, 2, 1] = C[:, 3, 2] = 1.0
    C[:, 0, 3] = -q / sigma**4
    C[:, 3, 3] = -c / sigma
    lam = np.linalg.eigvals(C) * sigma[:, None]
    lam = _sort_roots(lam)
    return lam.reshape(shape + (4,))


def _sort_roots(lam: np.ndarray) -> np.ndarray:
    scale = np.maximum(np.abs(lam).max(axis=-1, keepdims=True), 1e-300)
    key_re = np.round(lam.real / scale, 9)
    key_im = np.round(lam.imag / scale, 9)
    idx = np.lexsort((key_im, key_re), axis=-1)
    return np.take_along_axis(lam, idx, axis=-1)


def _bracket(lam, ex):
    """Paper's bracket B and dB/dlambda_i (...,4), with ex = exp(lambda) (possibly scaled)."""
    B = np.zeros(lam.shape[:-1], dtype=complex)
    dB = np.zeros(lam.shape, dtype=complex)
    for a, b, c, d, s in _PAIRS:
        la, lb, lc, ld = lam[..., a], lam[..., b], lam[..., c], lam[..., d]
        ea, eb, ec, ed = ex[..., a], ex[..., b], ex[..., c], ex[..., d]
        p1, p2, w = ea - eb, ec - ed, la * lb + lc * ld
        B += s * p1 * p2 * w
        dB[..., a] += s * (ea * p2 * w + p1 * p2 * lb)
        dB[..., b] += s * (-eb * p2 * w + p1 * p2 * la)
        dB[..., c] += s * (p1 * ec * w + p1 * p2 * ld)
        dB[..., d] += s * (-p1 * ed * w + p1 * p2 * lc)
    return B, dB


def _vandermonde(lam):
    """-prod_{i<j} (lambda_j - lambda_i): the sign makes g equal det Phi[0:2, 2:4]."""
    V = -np.ones(lam.shape[:-1], dtype=complex)
    for i in range(4):
        for j in range(i + 1, 4):
            V = V * (lam[..., j] - lam[..., i])
    return V


def _dlam_domega(lam, omega, chi, eta):
    c = chi / (omega + 1.0)
    dc = -chi / (omega + 1.0) ** 2
    lam2 = lam * lam
    return -(dc[..., None] * lam2 * lam + eta[..., None]) / (4.0 * lam2 * lam + 3.0 * c[..., None] * lam2)


def char_f(omega, chi, eta_perp, *, derivative: bool = False):
    """Paper's f(omega; chi, eta_perp), vectorised over broadcast inputs.

    Roots are taken in the order of :func:`quartic_roots`. Returns f (complex, broadcast
    shape) or (f, df/domega) with the derivative along the continuous root branches
    (defined where the roots are distinct).
    """
    omega, chi, eta, c, q = _coeffs(omega, chi, eta_perp)
    lam = quartic_roots(omega, chi, eta)
    ex = np.exp(lam)
    B, dB = _bracket(lam, ex)
    pre = ((omega + 1.0) ** -4 * np.prod(lam, axis=-1) * np.prod(lam * (omega + 1.0)[..., None] + chi[..., None], axis=-1))
    f = pre * B
    if not derivative:
        return f
    # pre = (eta omega)^2 identically
    dlam = _dlam_domega(lam, omega, chi, eta)
    df = 2.0 * eta**2 * omega * B + pre * np.sum(dB * dlam, axis=-1)
    return f, df


def _reduced_closed(omega, chi, eta):
    """Closed form g and dg/domega scaled by exp(-2m), m = max Re lambda; also m and separation."""
    lam = quartic_roots(omega, chi, eta)
    m = lam.real.max(axis=-1)
    ex = np.exp(lam - m[..., None])
    B, dB = _bracket(lam, ex)
    V = _vandermonde(lam)
    with np.errstate(all="ignore"):
        g = B / V
        diff = lam[..., :, None] - lam[..., None, :]
        eye = np.eye(4, dtype=bool)
        inv = np.where(eye, 0.0, 1.0 / np.where(eye, 1.0, diff))
        dg_dlam = dB / V[..., None] - g[..., None] * inv.sum(axis=-1)
        dg = np.sum(dg_dlam * _dlam_domega(lam, omega, chi, eta), axis=-1)
        absd = np.abs(np.where(eye, np.inf, diff)).min(axis=(-1, -2))
    sep = absd / np.maximum(np.abs(lam).max(axis=-1), 1.0)
    return g, dg, m, sep


def reduced_char(omega, chi, eta_perp, *, derivative: bool = False, scaled: bool = False):
    """Reduced characteristic function g(omega; chi, eta_perp) = bracket / Vandermonde.

    Symmetric in the roots (no sign flips), analytic in omega away from omega = -1, no
    spurious zero at omega = 0; its zeros are the eigenvalues other than the neutral ones.
    Where two roots nearly coincide (relative separation < SEP_TOL) the value is the mean
    of g on a small circle around omega (exact for analytic g up to (radius/distance)^8).
    ``scaled=True`` returns (g e^{-2m}, dg e^{-2m}, m) with m = max Re lambda, avoiding overflow.
    """
    omega, chi, eta, c, q = _coeffs(omega, chi, eta_perp)
    g, dg, m, sep = _reduced_closed(omega, chi, eta)
    bad = ~(sep >= SEP_TOL) | ~np.isfinite(g) | ~np.isfinite(dg)
    if np.any(bad):
        w0, ch, et = omega[bad], chi[bad], eta[bad]
        delta = np.minimum(1e-3 * np.maximum(np.abs(w0), 1.0), 0.05 * np.abs(w0 + 1.0))
        K = 8
        z = np.exp(2j * np.pi * (np.arange(K) + 0.5) / K)
        wk = w0[:, None] + delta[:, None] * z
        gk, _, mk, _ = _reduced_closed(wk, ch[:, None], et[:, None])
        mref = mk.max(axis=1)
        gk = gk * np.exp(2.0 * (mk - mref[:, None]))
        g[bad] = gk.mean(axis=1)
        dg[bad] = (gk / z).mean(axis=1) / delta
        m[bad] = mref
    if scaled:
        return (g, dg, m) if derivative else (g, m)
    fac = np.exp(2.0 * m)
    return (g * fac, dg * fac) if derivative else g * fac


def reduced_char_expm(omega: complex, chi: float, eta_perp: float) -> complex:
    """Reference g = det Phi[0:2, 2:4], Phi = expm(companion of M'''' + c M''' + q M) (scalar)."""
    c = chi / (omega + 1.0)
    q = eta_perp * omega
    A = np.zeros((4, 4), dtype=complex)
    A[0, 1] = A[1, 2] = A[2, 3] = 1.0
    A[3, 0] = -q
    A[3, 3] = -c
    P = scipy.linalg.expm(A)
    return complex(P[0, 2] * P[1, 3] - P[0, 3] * P[1, 2])


def boundary_matrix(omega: complex, chi: float, eta_perp: float, lam: np.ndarray | None = None) -> np.ndarray:
    """Paper's 4x4 boundary matrix (eq. constr_matrix): rows moment(0), shear(0), moment(1), shear(1)."""
    if lam is None:
        lam = quartic_roots(omega, chi, eta_perp)
    lam = np.asarray(lam, dtype=complex)
    c = chi / (omega + 1.0)
    a = lam * c + lam**2
    e = np.exp(lam)
    return np.array([a, lam * a, a * e, lam * a * e])
