"""The mobility problem of the discrete filament: without inertia, the joint rates follow
from a linear balance of drag and bending at each instant (eqs. MOD:eq:nondim_MBLs).

Unknowns z = [U0x, U0y, omega_0..omega_{N-1}] (N+2,): the velocity of r(0) and the segment
rotation rates. Joint velocities V_j = U0 + sum_{k<j} h n_k omega_k; weighted drag
w_j F_j = -w_j R(a_j) V_j (:func:`flutterswim.drag.resistance`, trapezoidal weights w_j,
joint tangent angle a_j); joint positions X_j = sum_{k<j} h t_k. Rows of G z = b:
  sum_j w_j F_j = 0                                   (rows 0, 1: total force)
  sum_{k<j} (X_k - X_j) x w_k F_k = b_{1+j},  j=1..N  (moment balance at each cut; j=N: torque)
with b_{1+j} = -M_j (bending moment) inside and 0 at j = N.

Every kernel is written once and compiled with numba when it is installed
(:mod:`flutterswim._jit`); ``kernels()`` returns the module with its compiled kernels.
"""

from __future__ import annotations

import numpy as np

from . import _jit
from .drag import resistance

__all__ = ["kernels", "assemble", "joint_drag", "apply", "apply_theta_derivative", "solve", "substitute", "factor",
           "factored_solve", "inverse"]

#: The largest element growth of :func:`solve`'s substitution that it trusts: its backward
#: error is about 3e-17 times the growth (measured on 6000 random shapes).
GROWTH_MAX = 1e4

KERNELS = ("resistance", "joint_drag", "apply", "assemble", "apply_theta_derivative", "_solve3", "substitute",
           "banded_lu_factor", "factor", "factored_solve", "solve", "inverse")


def kernels():
    """This module, with its kernels compiled if numba is installed."""
    import sys

    mod = sys.modules[__name__]
    _jit.compile_module(mod, KERNELS)
    return mod


def joint_drag(theta, tn, weights, eta_par, eta_perp, h, z):
    """Weighted drag w_j F_j = (wfx, wfy) at the joints for rates z, and the joint positions
    (x_j, y_j) relative to r(0); each (N+1,)."""
    n = theta.size
    wfx = np.zeros(n + 1)
    wfy = np.zeros(n + 1)
    xj = np.zeros(n + 1)
    yj = np.zeros(n + 1)
    vx = z[0]
    vy = z[1]
    x = 0.0
    y = 0.0
    for j in range(n + 1):
        rxx, rxy, ryy = resistance(tn[j], weights[j], eta_par, eta_perp)
        wfx[j] = -(rxx * vx + rxy * vy)
        wfy[j] = -(rxy * vx + ryy * vy)
        xj[j] = x
        yj[j] = y
        if j < n:
            c = np.cos(theta[j])
            s = np.sin(theta[j])
            vx = vx - h * s * z[2 + j]
            vy = vy + h * c * z[2 + j]
            x = x + h * c
            y = y + h * s
    return wfx, wfy, xj, yj


def apply(theta, tn, weights, eta_par, eta_perp, h, z):
    """G(theta) z without forming G, O(N): the force and cut-moment rows, (N+2,)."""
    n = theta.size
    wfx, wfy, xj, yj = joint_drag(theta, tn, weights, eta_par, eta_perp, h, z)
    r = np.zeros(n + 2)
    sx = 0.0
    sy = 0.0
    p = 0.0
    for j in range(n + 1):
        if j > 0:
            r[1 + j] = p - xj[j] * sy + yj[j] * sx
        sx = sx + wfx[j]
        sy = sy + wfy[j]
        p = p + xj[j] * wfy[j] - yj[j] * wfx[j]
    r[0] = sx
    r[1] = sy
    return r


def assemble(theta, tn, weights, eta_par, eta_perp, h):
    """The mobility matrix G (N+2, N+2), O(N^2): column q is G e_q (same sums as :func:`apply`)."""
    n = theta.size
    m = n + 2
    c = np.cos(theta)
    s = np.sin(theta)
    g = np.zeros((m, m))
    sx = np.zeros(m)  # sum_{k<j} w F_x,k as a row over z
    sy = np.zeros(m)
    p = np.zeros(m)  # sum_{k<j} X_k x w F_k
    fx = np.zeros(m)
    fy = np.zeros(m)
    xk = 0.0
    yk = 0.0
    for k in range(n + 1):
        rxx, rxy, ryy = resistance(tn[k], weights[k], eta_par, eta_perp)
        if k > 0:
            for q in range(m):
                g[1 + k, q] = p[q] - xk * sy[q] + yk * sx[q]
        fx[0] = -rxx
        fx[1] = -rxy
        fy[0] = -rxy
        fy[1] = -ryy
        for q in range(k):
            vx = -h * s[q]
            vy = h * c[q]
            fx[2 + q] = -(rxx * vx + rxy * vy)
            fy[2 + q] = -(rxy * vx + ryy * vy)
        for q in range(k + 2):
            sx[q] += fx[q]
            sy[q] += fy[q]
            p[q] += xk * fy[q] - yk * fx[q]
        if k < n:
            xk += h * c[k]
            yk += h * s[k]
    for q in range(m):
        g[0, q] = sx[q]
        g[1, q] = sy[q]
    return g


def apply_theta_derivative(theta, tn, avg, weights, eta_par, eta_perp, h, z):
    """D = d(G(theta) z)/d theta at fixed z, (N+2, N): the term of the exact Jacobian that a
    W-method may leave out. ``avg`` (N+1, N) maps segment angles to joint angles
    (tn = avg @ theta). Forward-mode differentiation of the sums of :func:`apply`, all N
    directions at once, O(N^2): theta_m moves the joints beyond segment m (their velocity by
    -h (cos, sin) theta_m omega_m, position by h (-sin, cos) theta_m) and turns the
    resistance tensors of the joints that average it."""
    n = theta.size
    d = np.zeros((n + 2, n))
    # running values and their derivatives (over m) before joint j
    vx = z[0]
    vy = z[1]
    x = 0.0
    y = 0.0
    sx = 0.0
    sy = 0.0
    p = 0.0
    dvx = np.zeros(n)
    dvy = np.zeros(n)
    dx = np.zeros(n)
    dy = np.zeros(n)
    dsx = np.zeros(n)
    dsy = np.zeros(n)
    dp = np.zeros(n)
    for j in range(n + 1):
        rxx, rxy, ryy = resistance(tn[j], weights[j], eta_par, eta_perp)
        cn = np.cos(tn[j])
        sn = np.sin(tn[j])
        dxx = 2.0 * weights[j] * (eta_perp - eta_par) * cn * sn  # d/d(angle) of the tensor
        dxy = weights[j] * (eta_par - eta_perp) * (cn * cn - sn * sn)
        wfx = -(rxx * vx + rxy * vy)
        wfy = -(rxy * vx + ryy * vy)
        if j > 0:
            for m in range(n):
                d[1 + j, m] = dp[m] - dx[m] * sy - x * dsy[m] + dy[m] * sx + y * dsx[m]
        for m in range(n):
            a = avg[j, m]
            dwfx = -(a * (dxx * vx + dxy * vy) + rxx * dvx[m] + rxy * dvy[m])
            dwfy = -(a * (dxy * vx - dxx * vy) + rxy * dvx[m] + ryy * dvy[m])
            dp[m] += dx[m] * wfy + x * dwfy - dy[m] * wfx - y * dwfx
            dsx[m] += dwfx
            dsy[m] += dwfy
        sx += wfx
        sy += wfy
        p += x * wfy - y * wfx
        if j < n:
            c = np.cos(theta[j])
            s = np.sin(theta[j])
            om = z[2 + j]
            dvx[j] = -h * c * om
            dvy[j] = -h * s * om
            dx[j] = -h * s
            dy[j] = h * c
            vx = vx - h * s * om
            vy = vy + h * c * om
            x = x + h * c
            y = y + h * s
    for m in range(n):
        d[0, m] = dsx[m]
        d[1, m] = dsy[m]
    return d


def banded_lu_factor(a, piv, nb):
    """In-place LU with partial pivoting, P a = L U, of a (m, m) whose rows i < nb have zeros
    left of column i - 2 (lower bandwidth 2) and whose rows nb.. are full: at step k < nb only
    rows k..k+2 and the border rows can be non-zero in column k, and row swaps among them keep
    that shape. O(m^2) instead of O(m^3). False if singular."""
    m = a.shape[0]
    for k in range(m):
        hi = min(k + 3, nb) if k < nb else m
        lo2 = max(nb, k)
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, hi):
            if abs(a[i, k]) > big:
                big = abs(a[i, k])
                p = i
        if k < nb:
            for i in range(lo2, m):
                if abs(a[i, k]) > big:
                    big = abs(a[i, k])
                    p = i
        piv[k] = p
        if big == 0.0:
            return False
        if p != k:
            for q in range(m):
                tmp = a[k, q]
                a[k, q] = a[p, q]
                a[p, q] = tmp
        inv = 1.0 / a[k, k]
        for i in range(k + 1, m):
            if k < nb and hi <= i < lo2:
                continue
            a[i, k] *= inv
            lik = a[i, k]
            if lik != 0.0:
                for q in range(k + 1, m):
                    a[i, q] -= lik * a[k, q]
    return True


def factor(gm, lu, piv):
    """LU with partial pivoting of a matrix gm (N+2, N+2) with G's sparsity (G, or G plus
    terms within the moment rows' band, as the W-method's Newton matrix), in O(N^2): lu holds
    the factors of Q = M'^T, M' = gm in the order [omega_0..omega_{N-1}, U0x, U0y] (rows
    [moments, forces]). The cut-moment row of joint j reaches omega_{j+1} at most, so Q has
    lower bandwidth 2 apart from the two force rows (:func:`banded_lu_factor`). False if
    singular."""
    n = gm.shape[0] - 2
    m = n + 2
    for i in range(m):
        pi = i + 2 if i < n else i - n
        for jj in range(m):
            pj = jj + 2 if jj < n else jj - n
            lu[i, jj] = gm[pj, pi]
    return banded_lu_factor(lu, piv, n)


def factored_solve(lu, piv, g):
    """g <- gm^-1 g in place, with the factors of :func:`factor` (g in G's row order in, in
    z's order out): M' x' = g' with P Q = L U, Q = M'^T: U^T a = g', L^T b = a, x' = P^T b."""
    m = g.size
    n = m - 2
    gp = np.empty(m)
    for i in range(m):
        gp[i] = g[i + 2] if i < n else g[i - n]
    for i in range(m):
        acc = gp[i]
        for k in range(i):
            acc -= lu[k, i] * gp[k]
        gp[i] = acc / lu[i, i]
    for i in range(m - 1, -1, -1):
        acc = gp[i]
        for k in range(i + 1, m):
            acc -= lu[k, i] * gp[k]
        gp[i] = acc
    for k in range(m - 1, -1, -1):
        p = piv[k]
        if p != k:
            tmp = gp[k]
            gp[k] = gp[p]
            gp[p] = tmp
    for i in range(m):
        if i < n:
            g[i + 2] = gp[i]
        else:
            g[i - n] = gp[i]


def solve(theta, tn, weights, eta_par, eta_perp, h, b):
    """z = G^-1 b in O(N), without forming G, by :func:`substitute`, whose element growth
    (max |terms| / max |z| of z's sums) bounds its backward error. Where the growth exceeds
    :data:`GROWTH_MAX` G is assembled and solved with partial pivoting instead (O(N^2)): the
    substitution's pivots are not chosen for size, and at a kink of about 90 degrees between
    neighbouring segments (an under-resolved, strongly curled filament) one of them
    vanishes while G stays regular."""
    z, growth = substitute(theta, tn, weights, eta_par, eta_perp, h, b)
    if growth > GROWTH_MAX:
        m = b.size
        lu = np.empty((m, m))
        piv = np.empty(m, dtype=np.int64)
        if factor(assemble(theta, tn, weights, eta_par, eta_perp, h), lu, piv):
            z[:] = b
            factored_solve(lu, piv, z)
        else:
            z[:] = np.nan
    return z


def substitute(theta, tn, weights, eta_par, eta_perp, h, b):
    """(z, growth): z = G^-1 b in O(N) by forward substitution, without pivoting.

    G is bordered lower-triangular in the joint rates: the cut-moment row of joint j
    (j = 2..N) involves U0 and omega_0..omega_{j-2} only, with omega_{j-2} entering through
    the drag on joint j-1 alone. So, for the three right-hand sides (b with U0 = 0; 0 with
    U0 = e_x; 0 with U0 = e_y), omega_0..omega_{N-2} follow by forward substitution
    (running sums of the drag and of its moment, as in :func:`apply`); the border, rows
    0, 1 (total force) and 2 (moment at joint 1) in the unknowns U0x, U0y and omega_{N-1}
    (which enters the total force only), is a 3 x 3 dense solve. b, z: (N+2,).
    The pivots are the moments about joint j of the drag that omega_{j-2} puts on joint j-1;
    ``growth`` = max_k (|om0_k| + |U0x om1_k| + |U0y om2_k|) / max |z|, with the three
    substitutions' rates om: large where a small pivot's error cancels out of z."""
    n = theta.size
    cs = np.cos(theta)
    sn = np.sin(theta)
    om = np.zeros((3, n))
    vx = np.zeros(3)
    vy = np.zeros(3)
    sx = np.zeros(3)
    sy = np.zeros(3)
    p = np.zeros(3)
    vx[1] = 1.0
    vy[2] = 1.0
    rxx, rxy, ryy = resistance(tn[0], weights[0], eta_par, eta_perp)
    for c in range(3):
        sx[c] = -(rxx * vx[c] + rxy * vy[c])
        sy[c] = -(rxy * vx[c] + ryy * vy[c])
    xp = h * cs[0]  # X_{j-1}
    yp = h * sn[0]
    r2 = np.zeros(3)
    for c in range(3):
        r2[c] = p[c] - (xp * sy[c] - yp * sx[c])
    for j in range(2, n + 1):
        xj = xp + h * cs[j - 1]
        yj = yp + h * sn[j - 1]
        rxx, rxy, ryy = resistance(tn[j - 1], weights[j - 1], eta_par, eta_perp)
        nx = -h * sn[j - 2]
        ny = h * cs[j - 2]
        dfx = -(rxx * nx + rxy * ny)  # drag on joint j-1 per unit omega_{j-2}
        dfy = -(rxy * nx + ryy * ny)
        dx = xp - xj
        dy = yp - yj
        alpha = dx * dfy - dy * dfx
        for c in range(3):
            fx = -(rxx * vx[c] + rxy * vy[c])
            fy = -(rxy * vx[c] + ryy * vy[c])
            rk = p[c] - (xj * sy[c] - yj * sx[c]) + dx * fy - dy * fx
            target = b[1 + j] if c == 0 else 0.0
            w = (target - rk) / alpha
            om[c, j - 2] = w
            vx[c] += nx * w
            vy[c] += ny * w
            fx += dfx * w
            fy += dfy * w
            sx[c] += fx
            sy[c] += fy
            p[c] += xp * fy - yp * fx
        xp = xj
        yp = yj
    rxx, rxy, ryy = resistance(tn[n], weights[n], eta_par, eta_perp)
    m = np.zeros((3, 3))
    rhs = np.zeros(3)
    for c in range(3):
        fx = sx[c] - (rxx * vx[c] + rxy * vy[c])
        fy = sy[c] - (rxy * vx[c] + ryy * vy[c])
        if c == 0:
            rhs[0] = b[0] - fx
            rhs[1] = b[1] - fy
            rhs[2] = b[2] - r2[0]
        else:
            m[0, c - 1] = fx
            m[1, c - 1] = fy
            m[2, c - 1] = r2[c]
    nx = -h * sn[n - 1]
    ny = h * cs[n - 1]
    m[0, 2] = -(rxx * nx + rxy * ny)
    m[1, 2] = -(rxy * nx + ryy * ny)
    u = _solve3(m, rhs)
    z = np.empty(n + 2)
    z[0] = u[0]
    z[1] = u[1]
    big = max(abs(u[0]), abs(u[1]), abs(u[2]))
    size = big
    for k in range(n - 1):
        z[2 + k] = om[0, k] + u[0] * om[1, k] + u[1] * om[2, k]
        big = max(big, abs(om[0, k]) + abs(u[0] * om[1, k]) + abs(u[1] * om[2, k]))
        size = max(size, abs(z[2 + k]))
    z[n + 1] = u[2]
    return z, (big / size if size > 0.0 else 1.0)


def _solve3(m, r):
    """3 x 3 solve by Cramer's rule (m well scaled: rows of drag and moment)."""
    det = (m[0, 0] * (m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1]) - m[0, 1] * (m[1, 0] * m[2, 2] - m[1, 2] * m[2, 0])
           + m[0, 2] * (m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]))
    x = np.empty(3)
    for k in range(3):
        a = m.copy()
        for i in range(3):
            a[i, k] = r[i]
        x[k] = (a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]) - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
                + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0])) / det
    return x


def inverse(theta, tn, weights, eta_par, eta_perp, h):
    """G^-1 (N+2, N+2)."""
    return np.linalg.inv(assemble(theta, tn, weights, eta_par, eta_perp, h))
