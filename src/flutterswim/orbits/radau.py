"""The linear algebra of the Radau IIA steps of :mod:`flutterswim.orbits.shooting`, and the
compiled stage iteration.

The step matrix P = I - h (A x I) diag(J_j) (3 stages, J_j the exact Jacobian of the shape
dynamics at stage j) is 3(2N+1) square. The activity law makes the kappa block of every
J_j equal to -I (kappa_t = -kappa - chi sin(theta - phi)), so the kappa unknowns of the
three stages can be eliminated exactly. Writing J_j = [[T_j, B_j], [C_j, -I]] (theta rows,
kappa rows), W = (I + h A)^-1 and a right-hand side (r_theta, r_kappa) per stage:
    kappa_i = sum_k W_ik r_kappa,k + h sum_l (W A)_il C_l theta_l,
    R theta = r_theta,i + h sum_j A_ij B_j sum_k W_jk r_kappa,k,
    R_il = delta_il I - h A_il T_l - h^2 sum_j A_ij (W A)_jl B_j C_l,
a 3N-square system instead of 3(2N+1): its inverse costs 8 times less, a solve 4 times less.
:func:`factor` forms and inverts R (scipy/LAPACK); :func:`reduced_solve` solves with it
(with R^-1: one matrix product, so the same kernel serves one stage residual and the
variational equation's many columns); :func:`exact_solve` solves a variational equation
whose step matrix is not kept by one LU instead; :func:`stages` is the simplified Newton
iteration of one step; :func:`chord_pass` runs it over all steps of a pass whose step matrices are all
given (a warm start). The forming of step matrices and the variational equation stay in
:func:`flutterswim.orbits.shooting.flow`. Kernels are written once and compiled with numba
when it is installed (:mod:`flutterswim._jit`).
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla

from .. import _jit, rosw

KERNELS = ("reduced_matrix", "reduce_rhs", "expand", "reduced_solve", "stages", "chord_pass")

#: status codes of :func:`stages`
CONVERGED, SLOW, NOT_FINITE, NO_CONVERGENCE = 0, 1, 2, 3


def kernels():
    """This module with its kernels compiled (numba), callees (rosw) first."""
    import sys

    rosw.kernels()
    mod = sys.modules[__name__]
    _jit.compile_module(mod, KERNELS)
    return mod


def constants(h: float, a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(h A, W = (I + h A)^-1, h W A) of a step size h and a Runge-Kutta matrix A."""
    w = np.linalg.inv(np.eye(3) + h * a)
    return h * a, w, h * (w @ a)


def reduced(jac: np.ndarray, n: int, consts, kern=None) -> tuple:
    """The reduced step matrix R (3N, 3N, column-major) of the stage Jacobians ``jac``
    (3, 2N+1, 2N+1), with their blocks B (3, N, N+1) and C (3, N+1, N). ``kern``: this
    module's kernels (compiled or not)."""
    kern = kernels() if kern is None else kern
    nk = jac.shape[1] - n
    r = np.empty((3 * n, 3 * n), order="F")
    b = np.empty((3, n, nk))
    c = np.empty((3, nk, n))
    if not kern.reduced_matrix(jac, n, consts[0], consts[2], r, b, c):
        raise ValueError("the kappa block of the Jacobian is not -I: the reduced Radau step does not apply")
    return r, b, c


def factor(jac: np.ndarray, n: int, consts, kern=None) -> tuple:
    """R of :func:`reduced`, inverted: (R^-1, B, C). A solve is then one matrix product
    (BLAS), for one stage residual as for many columns: the chord passes solve about 20
    times with each matrix, where a product is several times faster than two triangular
    solves. ``kern``: this module's kernels (compiled or not)."""
    r, b, c = reduced(jac, n, consts, kern)
    try:
        with warnings.catch_warnings():
            # singular to working precision (reciprocal condition number below eps): an
            # "inverse" of rounding errors, treated as the singular case (and not printed)
            warnings.simplefilter("error", sla.LinAlgWarning)
            rinv = sla.inv(r, overwrite_a=True, check_finite=False)
    except (np.linalg.LinAlgError, sla.LinAlgWarning):  # singular: a step too long for the stiff dynamics
        rinv = np.full(r.shape, np.nan)
    return np.ascontiguousarray(rinv), b, c


def exact_solve(jac: np.ndarray, n: int, consts, x: np.ndarray, kern=None) -> bool:
    """Solve P x = r in place for x (3(2N+1), k), P from the stage Jacobians ``jac``, by one
    LU of R (LAPACK) and no inverse: for a variational equation whose step matrix is not
    kept. False if R is singular."""
    kern = kernels() if kern is None else kern
    r, b, c = reduced(jac, n, consts, kern)
    th = np.empty((r.shape[0], x.shape[1]))
    qk = np.empty((3, b.shape[2], x.shape[1]))
    kern.reduce_rhs(b, consts[0], consts[1], x, th, qk)
    from scipy.linalg.lapack import dgetrf, dgetrs

    lu, piv, info = dgetrf(r, overwrite_a=1)
    if info != 0:
        return False
    th, info = dgetrs(lu, piv, th, overwrite_b=1)
    if info != 0 or not np.all(np.isfinite(th)):
        return False
    kern.expand(np.ascontiguousarray(th), c, consts[2], qk, x)
    return True


def reduced_matrix(jac, n, ha, hwa, r, b, c):
    """R (3N, 3N) of the module docstring into ``r``, with the blocks B_j and C_j of the stage
    Jacobians into ``b`` (3, N, N+1) and ``c`` (3, N+1, N). False if a kappa block is not -I."""
    nk = jac.shape[1] - n
    for j in range(3):
        for p in range(nk):
            for q in range(nk):
                if jac[j, n + p, n + q] != (-1.0 if p == q else 0.0):
                    return False
        for p in range(n):
            for q in range(nk):
                b[j, p, q] = jac[j, p, n + q]
        for p in range(nk):
            for q in range(n):
                c[j, p, q] = jac[j, n + p, q]
    for i in range(3):
        for l in range(3):
            bsum = np.zeros((n, nk))  # sum_j h A_ij (h W A)_jl B_j
            for j in range(3):
                coef = ha[i, j] * hwa[j, l]
                for p in range(n):
                    for q in range(nk):
                        bsum[p, q] += coef * b[j, p, q]
            block = np.dot(bsum, c[l])
            hil = ha[i, l]
            for p in range(n):
                for q in range(n):
                    r[i * n + p, l * n + q] = -block[p, q] - hil * jac[l, p, q] + (1.0 if i == l and p == q else 0.0)
    return True


def reduce_rhs(b, ha, w, r, th, qk):
    """The reduced right-hand side (module docstring): th (3N, k) with R theta = th, and
    qk (3, N+1, k) = sum_k W_jk r_kappa,k, of r (3(2N+1), k)."""
    n = b.shape[1]
    nk = b.shape[2]
    m = n + nk
    k = r.shape[1]
    qk[:] = 0.0
    for j in range(3):
        for q in range(3):
            wjq = w[j, q]
            for p in range(nk):
                for col in range(k):
                    qk[j, p, col] += wjq * r[q * m + n + p, col]
    for i in range(3):
        for p in range(n):
            for col in range(k):
                th[i * n + p, col] = r[i * m + p, col]
    for j in range(3):
        bq = np.dot(b[j], qk[j])  # (N, k)
        for i in range(3):
            hij = ha[i, j]
            for p in range(n):
                for col in range(k):
                    th[i * n + p, col] += hij * bq[p, col]


def expand(th, c, hwa, qk, r):
    """The solution into r (3(2N+1), k) from theta ``th`` (3N, k): kappa_i = qk_i +
    h sum_l (W A)_il C_l theta_l."""
    nk = c.shape[1]
    n = c.shape[2]
    m = n + nk
    k = r.shape[1]
    for l in range(3):
        theta = np.ascontiguousarray(th[l * n : (l + 1) * n])
        for p in range(n):
            for col in range(k):
                r[l * m + p, col] = theta[p, col]
        ct = np.dot(c[l], theta)  # (N+1, k)
        for i in range(3):
            hil = hwa[i, l]
            for p in range(nk):
                for col in range(k):
                    qk[i, p, col] += hil * ct[p, col]
    for i in range(3):
        for p in range(nk):
            for col in range(k):
                r[i * m + n + p, col] = qk[i, p, col]


def reduced_solve(rinv, b, c, ha, w, hwa, r):
    """Solve P x = r in place for r (3(2N+1), k) (stage-major rows: theta then kappa of
    each stage), with the factors of :func:`factor`. Returns 0, or 1 if R was singular."""
    th = np.empty((rinv.shape[0], r.shape[1]))
    qk = np.empty((3, b.shape[2], r.shape[1]))
    reduce_rhs(b, ha, w, r, th, qk)
    th = np.dot(rinv, th)
    if not np.isfinite(th[0, 0]):
        return 1
    expand(th, c, hwa, qk, r)
    return 0


def stages(u, z, ha, w, hwa, rinv, b, c, avg, diff, weights, eta_par, eta_perp, chi, phi, tol, state, fz):
    """Simplified Newton iteration for the stage increments z (3, m), in place, with a
    factored step matrix (:func:`factor`). ``state`` = [iterations done, last correction
    size, iteration limit] carries over when the caller re-forms the matrix (status SLOW).
    ``fz`` (3, m + 2): the full rhs at the last iterate's stage points (within ``tol`` of
    z). Stops when the correction is below ``tol`` (absolute) or at the rounding floor
    (below 1e3 tol and no longer halving). Returns a status code."""
    m = u.shape[0]
    y = np.zeros(m + 2)
    res = np.empty((3 * m, 1))
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
                res[i * m + k, 0] = -acc
        if reduced_solve(rinv, b, c, ha, w, hwa, res) != 0:
            return NOT_FINITE
        size = 0.0
        finite = True
        for i in range(3):
            for k in range(m):
                d = res[i * m + k, 0]
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


def chord_pass(u0, zs, rinvs, bs, cs, ha, w, hwa, avg, diff, weights, eta_par, eta_perp, chi, phi, h, rk_b,
               tol, max_iter, ys, fs):
    """All steps of a pass with given step matrices (stacked per step): the stage increments
    zs (steps, 3, m) in place (warm start in, converged out), states ys and full rhs fs
    (steps + 1, m + 2) from ys[0] on (ys[0] and fs[0] given). Stage tolerance ``tol`` times
    1 + max|u| of each step. Returns (step, status): (-1, CONVERGED), or the first step whose
    iteration did not converge with its given matrix (the caller takes over)."""
    m = u0.shape[0]
    u = u0.copy()
    state = np.empty(3)
    fz = np.empty((3, m + 2))
    rx = ys[0, 0]
    ry = ys[0, 1]
    for step in range(zs.shape[0]):
        scale = 1.0 + np.max(np.abs(u))
        state[0] = 0.0
        state[1] = np.inf
        state[2] = max_iter
        z = zs[step]
        status = stages(u, z, ha, w, hwa, rinvs[step], bs[step], cs[step], avg, diff, weights, eta_par,
                        eta_perp, chi, phi, tol * scale, state, fz)
        if status != CONVERGED:
            return step, status
        for i in range(3):
            rx += h * rk_b[i] * fz[i, 0]
            ry += h * rk_b[i] * fz[i, 1]
        for k in range(m):
            u[k] += z[2, k]
        ys[step + 1, 0] = rx
        ys[step + 1, 1] = ry
        ys[step + 1, 2:] = u
        fs[step + 1, :] = fz[2]
    return -1, CONVERGED
