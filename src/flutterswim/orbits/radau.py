"""Compiled kernels of the Radau IIA steps of :mod:`flutterswim.orbits.shooting`.

``stages`` is the simplified Newton iteration of one step's stage equations
Z_i = h sum_j A_ij f(u + Z_j), with a step matrix P = I - h (A x I) diag(J_j) factored by
LAPACK (scipy's ``lu_factor``: column-major, 0-based sequential row interchanges), solved
here by ``lu_solve``. The rhs is the simulator's own kernel (:func:`flutterswim.rosw.rhs`).
The step loop, the forming of step matrices and the variational part stay in
:func:`flutterswim.orbits.shooting.flow`: the iteration returns to it when it needs a
fresh matrix. Written once, compiled with numba when it is installed
(:mod:`flutterswim._jit`).
"""

from __future__ import annotations

import numpy as np

from .. import _jit, rosw

KERNELS = ("lu_solve", "stages")

#: status codes of :func:`stages`
CONVERGED, SLOW, NOT_FINITE, NO_CONVERGENCE = 0, 1, 2, 3


def kernels():
    """This module with its kernels compiled (numba), callees (rosw) first."""
    import sys

    rosw.kernels()
    mod = sys.modules[__name__]
    _jit.compile_module(mod, KERNELS)
    return mod


def lu_solve(lu, piv, b):
    """Solve in place P L U x = b, with (lu, piv) from LAPACK getrf (scipy ``lu_factor``)."""
    n = b.shape[0]
    for i in range(n):
        p = piv[i]
        if p != i:
            tmp = b[i]
            b[i] = b[p]
            b[p] = tmp
    for j in range(n):  # unit lower triangle, by columns (lu is column-major)
        bj = b[j]
        if bj != 0.0:
            for i in range(j + 1, n):
                b[i] -= lu[i, j] * bj
    for j in range(n - 1, -1, -1):
        b[j] /= lu[j, j]
        bj = b[j]
        if bj != 0.0:
            for i in range(j):
                b[i] -= lu[i, j] * bj
    return b


def stages(u, z, ha, lu, piv, avg, diff, weights, eta_par, eta_perp, chi, phi, tol, state, fz):
    """Simplified Newton iteration for the stage increments z (3, m), in place, with the
    factored step matrix (lu, piv) and ``ha`` = h A. ``state`` = [iterations done, last
    correction size, iteration limit] carries over when the caller re-forms the matrix
    (status SLOW). ``fz`` (3, m + 2): the full rhs at the last iterate's stage points (within
    ``tol`` of z). Stops when the correction is below ``tol`` (absolute) or at the rounding
    floor (below 1e3 tol and no longer halving). Returns a status code."""
    m = u.shape[0]
    y = np.zeros(m + 2)
    res = np.empty(3 * m)
    it = int(state[0])
    last = state[1]
    limit = int(state[2])
    while it <= limit:
        for i in range(3):
            for k in range(m):
                y[2 + k] = u[k] + z[i, k]
            rosw.rhs(y, avg, diff, weights, eta_par, eta_perp, chi, phi, fz[i])
        for i in range(3):
            for k in range(m):
                acc = z[i, k]
                for j in range(3):
                    acc -= ha[i, j] * fz[j, 2 + k]
                res[i * m + k] = -acc
        lu_solve(lu, piv, res)
        size = 0.0
        finite = True
        for i in range(3):
            for k in range(m):
                d = res[i * m + k]
                z[i, k] += d
                if not np.isfinite(z[i, k]):
                    finite = False
                if abs(d) > size:
                    size = abs(d)
        state[0] = it + 1
        state[1] = size
        if not finite:
            return NOT_FINITE
        if size < tol:
            return CONVERGED
        if size < 1e3 * tol and size >= 0.5 * last:
            return CONVERGED  # at the rounding floor: the corrections no longer shrink
        if size > 0.1 * last and it >= 1:
            return SLOW  # a fresh matrix at the current iterate
        last = size
        it += 1
    return NO_CONVERGENCE
