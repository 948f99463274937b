"""Chebyshev collocation of the linearised problem, written with the bending moment.

Unknowns on N+1 Chebyshev points of s in [0, 1]: r (lateral displacement), kappa
(spontaneous curvature) and M = r'' - kappa (bending moment). Generalised eigenproblem
A x = omega B x from

    eta_perp omega r = -M'',   omega kappa = -kappa - chi r',   0 = r'' - kappa - M,

with M = 0 and M' = 0 at s = 0 and s = 1 (zero moment and shear). B is singular; the
infinite eigenvalues are discarded. The neutral modes omega = 0 (rigid translation and
the equilibrium family r ~ exp(-chi s)) are reported separately from the others.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.linalg

from .._validate import finite, positive, positive_int

__all__ = ["Spectrum", "chebyshev", "spectrum", "spectral_matrices"]


@lru_cache(maxsize=16)
def chebyshev(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Chebyshev-Gauss-Lobatto points s (n+1,) on [0, 1] (s[0]=0), and d/ds, d2/ds2 ((n+1, n+1))."""
    k = np.arange(n + 1)
    x = np.cos(np.pi * k / n)  # 1 .. -1
    c = np.where((k == 0) | (k == n), 2.0, 1.0) * (-1.0) ** k
    X = np.tile(x, (n + 1, 1)).T
    dX = X - X.T
    D = np.outer(c, 1.0 / c) / (dX + np.eye(n + 1))
    D -= np.diag(D.sum(axis=1))
    # map x in [-1, 1] to s = (1 - x)/2 so that s[0] = 0; ds/dx = -1/2
    s = (1.0 - x) / 2.0
    D1 = -2.0 * D
    D2 = D1 @ D1
    for a in (s, D1, D2):
        a.setflags(write=False)
    return s, D1, D2


def spectral_matrices(chi: float, eta_perp: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Return (A, B), each (3(n+1), 3(n+1)), unknown vector x = (r, kappa, M)."""
    s, D1, D2 = chebyshev(n)
    m = n + 1
    I = np.eye(m)
    A = np.zeros((3 * m, 3 * m))
    B = np.zeros((3 * m, 3 * m))
    r, k, M = slice(0, m), slice(m, 2 * m), slice(2 * m, 3 * m)
    ends = [0, n]
    # block 1: eta omega r = -M'' (interior), M' = 0 at the ends
    A[r, M] = -D2
    B[r, r] = eta_perp * I
    A[ends, :] = 0.0
    B[ends, :] = 0.0
    A[ends, 2 * m :] = D1[ends]
    # block 2: omega kappa = -kappa - chi r'
    A[k, k] = -I
    A[k, r] = -chi * D1
    B[k, k] = I
    # block 3: 0 = r'' - kappa - M (interior), M = 0 at the ends
    A[M, r] = D2
    A[M, k] = -I
    A[M, M] = -I
    rows = [2 * m, 2 * m + n]
    A[rows, :] = 0.0
    A[rows, [2 * m, 2 * m + n]] = 1.0
    return A, B


@dataclass(frozen=True)
class Spectrum:
    """Eigenvalues from collocation, sorted by decreasing real part.

    omega: finite eigenvalues other than the neutral ones (k,), complex;
    neutral: eigenvalues recognised as omega = 0 (translation / equilibrium family);
    n: polynomial degree; chi, eta_perp: dimensionless groups.
    """

    omega: np.ndarray
    neutral: np.ndarray
    n: int
    chi: float
    eta_perp: float

    @property
    def leading(self) -> complex:
        """Non-neutral eigenvalue with largest real part (Im >= 0 of a conjugate pair)."""
        w = self.omega
        top = w[0]
        return complex(top.real, abs(top.imag))


def spectrum(
    chi: float,
    eta_perp: float,
    *,
    n: int = 48,
    neutral_tol: float = 1e-7,
    max_abs: float | None = None,
    vectors: bool = False,
    use_symmetry: bool = True,
):
    """Whole spectrum of the collocation problem (no initial guess).

    Returns a :class:`Spectrum`; with ``vectors=True`` returns ``(Spectrum, V, s)`` where
    V[:, j] = (r, kappa, M) at points s for eigenvalue ``Spectrum.omega[j]``.
    ``max_abs`` drops eigenvalues with |omega| above it (default 1e12, i.e. only infinite ones).
    ``use_symmetry``: for chi < 0 solve at -chi and reflect s -> 1 - s (same spectrum; the
    QZ iteration is markedly slower for some chi < 0 matrices).
    """
    chi = finite("chi", chi)
    eta_perp = positive("eta_perp", eta_perp)
    n = positive_int("n", n, minimum=8)
    if use_symmetry and chi < 0:
        out = spectrum(-chi, eta_perp, n=n, neutral_tol=neutral_tol, max_abs=max_abs, vectors=vectors)
        if not vectors:
            return Spectrum(out.omega, out.neutral, n, chi, eta_perp)
        sp, V, s = out
        m = n + 1
        idx = np.concatenate([np.arange(m)[::-1] + b * m for b in range(3)])
        return Spectrum(sp.omega, sp.neutral, n, chi, eta_perp), V[idx], s
    A, B = spectral_matrices(chi, eta_perp, n)
    if vectors:
        w, V = scipy.linalg.eig(A, B, overwrite_a=True, overwrite_b=True, check_finite=False)
    else:
        w = scipy.linalg.eig(A, B, right=False, overwrite_a=True, overwrite_b=True, check_finite=False)
        V = None
    cap = 1e12 if max_abs is None else float(max_abs)
    ok = np.isfinite(w) & (np.abs(w) < cap)
    scale = max(1.0, abs(chi))
    neutral = ok & (np.abs(w) < neutral_tol * scale)
    keep = ok & ~neutral
    order = np.argsort(-w[keep].real, kind="stable")
    res = Spectrum(w[keep][order], w[neutral], n, chi, eta_perp)
    if vectors:
        s, _, _ = chebyshev(n)
        return res, V[:, keep][:, order], s
    return res
