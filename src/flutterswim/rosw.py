"""Compiled Rosenbrock-W stepping of the filament ODE (the whole step loop in one kernel).

State y = [x0, y0, theta (N), kappa (N+1)] (:mod:`flutterswim.filament`), field direction phi
and strength sigma constant over a call (piecewise-steady fields are integrated piece by piece).

Stages in the transformed form of Hairer & Wanner (IV.7) as in OrdinaryDiffEq.jl:
    (I/(gamma h) - J) u_i = f(y + sum_j A_ij u_j) + sum_j (C_ij / h) u_j,
    y1 = y + sum_i b_i u_i,  error = sum_i bt_i u_i.
W-method: J is the Jacobian without the change of G with theta (non-stiff), and it is kept
with its LU for several steps. A factorisation made at step size h0 solves the stage
equation at h exactly for the approximate Jacobian (h0/h) J0 (a W-method keeps its order
with any approximation), so the LU is reused while h stays within ``reuse`` of h0 and J is
younger than ``max_age`` accepted steps; a rejected step with a reused J refreshes it
(CVODE's heuristics: refactor when gamma h changes by more than ~30 %, re-evaluate after a
failure or every ~20-50 steps).

The linear algebra follows the problem's shape. With c = gamma h0, G the mobility matrix,
E the injection of the interior moments into G's rows, D the theta_s stencil, A the joint
average and S = d kappa_t/d theta at the joints, (I - c J) x = r reduces to
    (G + c E D - c^2/(1+c) E S A) x_z = G r_z + c/(1+c) E r_kappa,
    x_kappa = (r_kappa + c S A x_theta) / (1 + c),
an (N+2)-square dense LU (instead of 2N+3), G r_z with the G kept from the factorisation;
the right-hand side uses the O(N) forward
substitution :func:`flutterswim.mobility.solve`.
"""

from __future__ import annotations

import numpy as np

from . import _jit, activity, mobility

KERNELS = ("band_product", "moment_load", "rhs", "jacobian", "group_derivatives", "w_factor", "w_solve", "hermite", "run")


def kernels():
    """This module with its kernels compiled (numba), callees first."""
    import sys

    mobility.kernels()
    _jit.compile_module(activity, ("activity_rate", "activity_slope"))
    mod = sys.modules[__name__]
    _jit.compile_module(mod, KERNELS)
    return mod


def band_product(mat, x, offset, out):
    """out_r = sum_k mat[r, k] x_k over the stencil band k = j-2..j+1 of joint j = r + offset
    (the joint average (offset 0, rows summing to 1) and theta_s (offset 1, rows summing to 0)
    operators of the filament). Summed as row_sum x_k0 + sum_k mat[r, k] (x_k - x_k0), so a
    uniform x gives exactly x (average) and 0 (theta_s): a straight filament stays at rest."""
    ncol = mat.shape[1]
    base = 1.0 if offset == 0 else 0.0
    for r in range(mat.shape[0]):
        j = r + offset
        k0 = max(0, j - 2)
        x0 = x[k0]
        acc = 0.0
        for k in range(k0 + 1, min(ncol, j + 2)):
            acc += mat[r, k] * (x[k] - x0)
        out[r] = base * x0 + acc
    return out


def moment_load(y, avg, diff):
    """(theta, kappa, joint angles, b): the state's parts and the mobility problem's
    right-hand side b = -(theta_s - kappa) at the interior joints (N+2,)."""
    n = avg.shape[1]
    theta = y[2 : n + 2]
    kappa = y[n + 2 :]
    tn = band_product(avg, theta, 0, np.empty(n + 1))
    ts = band_product(diff, theta, 1, np.empty(n - 1))
    b = np.zeros(n + 2)
    for j in range(1, n):
        b[1 + j] = kappa[j] - ts[j - 1]
    return theta, kappa, tn, b


def rhs(y, avg, diff, weights, eta_par, eta_perp, chi_sigma, phi, dy):
    """dy = f(y) (2N+3,): z = G^-1 b with b = -(theta_s - kappa) at the interior joints,
    kappa_t from :func:`flutterswim.activity.activity_rate`."""
    n = avg.shape[1]
    theta, kappa, tn, b = moment_load(y, avg, diff)
    z = mobility.solve(theta, tn, weights, eta_par, eta_perp, 1.0 / n, b)
    dy[: n + 2] = z
    dy[n + 2 :] = activity.activity_rate(kappa, tn, chi_sigma, phi)
    return dy


def jacobian(y, avg, diff, weights, eta_par, eta_perp, chi_sigma, phi, exact, jac):
    """jac = df/dy (2N+3, 2N+3) of :func:`rhs`. z = G^-1 b depends on theta through b (the
    moments, -D theta) and, with ``exact``, through G itself: -G^-1 d(G z)/d theta
    (:func:`flutterswim.mobility.apply_theta_derivative`; a W-method may leave it out);
    on kappa through b; kappa_t through the activity law."""
    n = avg.shape[1]
    theta, _, tn, b = moment_load(y, avg, diff)
    ginv = mobility.inverse(theta, tn, weights, eta_par, eta_perp, 1.0 / n)
    jac[:, :] = 0.0
    for i in range(n + 2):
        for c in range(n):  # -G^-1[:, moments] D
            acc = 0.0
            for j in range(max(0, c - 2), min(n - 1, c + 2)):
                acc += ginv[i, 2 + j] * diff[j, c]
            jac[i, 2 + c] = -acc
        for j in range(1, n):  # kappa_j enters the moment of joint j
            jac[i, n + 2 + j] = ginv[i, 1 + j]
    if exact:
        z = ginv @ b
        dgz = mobility.apply_theta_derivative(theta, tn, avg, weights, eta_par, eta_perp, 1.0 / n, z)
        corr = ginv @ dgz
        for i in range(n + 2):
            for c in range(n):
                jac[i, 2 + c] -= corr[i, c]
    slope = activity.activity_slope(tn, chi_sigma, phi)
    for j in range(n + 1):
        for c in range(max(0, j - 2), min(n, j + 2)):
            jac[n + 2 + j, 2 + c] = slope[j] * avg[j, c]
        jac[n + 2 + j, n + 2 + j] = -1.0
    return jac


def group_derivatives(y, avg, diff, weights, eta_par, eta_perp, sigma, phi, out):
    """out = d f / d (eta_par, eta_perp, chi) (2N+3, 3) of :func:`rhs` at field strength
    ``sigma``. The drag is linear in the two coefficients, G = eta_par G_par + eta_perp
    G_perp, so dz/d eta = -G^-1 (G_eta z) (two O(N) solves); chi enters only the activity
    law, linearly."""
    n = avg.shape[1]
    h = 1.0 / n
    theta, _, tn, b = moment_load(y, avg, diff)
    z = mobility.solve(theta, tn, weights, eta_par, eta_perp, h, b)
    out[:, :] = 0.0
    for col in range(2):
        g_z = mobility.apply(theta, tn, weights, 1.0 - col, float(col), h, z)
        dz = mobility.solve(theta, tn, weights, eta_par, eta_perp, h, g_z)
        for i in range(n + 2):
            out[i, col] = -dz[i]
    out[n + 2 :, 2] = activity.activity_rate(np.zeros(n + 1), tn, sigma, phi)
    return out


def w_factor(y, c, avg, diff, weights, eta_par, eta_perp, chi_sigma, phi, lu, piv, g0, s0):
    """Factor M = G + c E D - c^2/(1+c) E S A at state y; keep G (g0) and S (s0) at y for
    :func:`w_solve`. False if singular."""
    n = avg.shape[1]
    th0 = y[2 : n + 2].copy()
    tn0 = band_product(avg, th0, 0, np.empty(n + 1))
    s0[:] = activity.activity_slope(tn0, chi_sigma, phi)
    g0[:, :] = mobility.assemble(th0, tn0, weights, eta_par, eta_perp, 1.0 / n)
    q = c * c / (1.0 + c)
    mm = g0.copy()
    for j in range(1, n):
        for k in range(max(0, j - 2), min(n, j + 2)):
            mm[1 + j, 2 + k] += c * diff[j - 1, k] - q * s0[j] * avg[j, k]
    return mobility.factor(mm, lu, piv)


def w_solve(r, c, avg, lu, piv, g0, s0, x):
    """x = (I - c J0)^-1 r with the factors of :func:`w_factor` (G r_z as a dense product with
    the kept G: cheaper than the O(N) :func:`flutterswim.mobility.apply`, whose cost is its
    2N + 2 sines and cosines)."""
    n = avg.shape[1]
    m = n + 2
    g = np.zeros(m)
    for i in range(m):
        acc = 0.0
        for q in range(m):
            acc += g0[i, q] * r[q]
        g[i] = acc
    f = c / (1.0 + c)
    for j in range(1, n):
        g[1 + j] += f * r[n + 2 + j]
    mobility.factored_solve(lu, piv, g)
    x[: n + 2] = g
    a = band_product(avg, g[2:], 0, np.empty(n + 1))
    for j in range(n + 1):
        x[n + 2 + j] = (r[n + 2 + j] + c * s0[j] * a[j]) / (1.0 + c)
    return x


def hermite(t0, y0, f0, t1, y1, f1, t, out):
    """Cubic Hermite interpolant of the step at time t."""
    h = t1 - t0
    u = (t - t0) / h
    h00 = (1 + 2 * u) * (1 - u) ** 2
    h10 = u * (1 - u) ** 2
    h01 = u * u * (3 - 2 * u)
    h11 = u * u * (u - 1)
    for i in range(out.size):
        out[i] = h00 * y0[i] + h10 * h * f0[i] + h01 * y1[i] + h11 * h * f1[i]


def run(y, f, t, t_stop, h, t_eval, out, i_out, tab_a, tab_c, tab_b, tab_bt, gamma, q, rtol, atol, cap,
        max_step, fixed, avg, diff, weights, eta_par, eta_perp, chi_sigma, phi, max_steps, reuse, max_age,
        lu, piv, g0, s0, wstate, stats):
    """Integrate from t to t_stop (y, f = f(y) updated in place); frames at t_eval[i_out:] <= t
    are written to out. Returns (t, h, i_out, status): status 0 reached t_stop, 1 step size
    collapsed, 2 non-finite state, 3 singular matrix, 4 too many steps.

    ``fixed`` > 0: constant steps of that size, no error control (order tests).
    ``wstate`` = [c0 = gamma h0 of the factors (0: none), J age, unused]; ``stats`` (int64) += [steps,
    rejected, rhs, jacobians, LUs]; the factors persist across calls."""
    n_state = y.size
    s = tab_b.size
    u = np.zeros((s, n_state))
    yi = np.empty(n_state)
    fi = np.empty(n_state)
    rr = np.empty(n_state)
    ynew = np.empty(n_state)
    fnew = np.empty(n_state)
    err = np.empty(n_state)
    status = 0
    expo = -1.0 / (q + 1.0)
    while t < t_stop:
        if stats[0] + stats[1] >= max_steps:
            status = 4
            break
        if fixed > 0.0:
            h = fixed
        h = min(h, max_step)
        if t + h >= t_stop - 1e-12 * max(1.0, abs(t_stop)):
            h = t_stop - t
        c = gamma * h
        c0 = wstate[0]
        if c0 <= 0.0 or abs(c / c0 - 1.0) > reuse or wstate[1] >= max_age:
            ok = w_factor(y, c, avg, diff, weights, eta_par, eta_perp, chi_sigma, phi, lu, piv, g0, s0)
            stats[3] += 1
            stats[4] += 1
            if not ok:
                status = 3
                wstate[0] = 0.0
                break
            wstate[0] = c
            wstate[1] = 0.0
            c0 = c
        for i in range(s):
            if i == 0:
                fi[:] = f
            else:
                yi[:] = y
                for j in range(i):
                    a = tab_a[i, j]
                    if a != 0.0:
                        for m in range(n_state):
                            yi[m] += a * u[j, m]
                rhs(yi, avg, diff, weights, eta_par, eta_perp, chi_sigma, phi, fi)
                stats[2] += 1
            for m in range(n_state):
                rr[m] = fi[m]
            for j in range(i):
                cc = tab_c[i, j] / h
                if cc != 0.0:
                    for m in range(n_state):
                        rr[m] += cc * u[j, m]
            for m in range(n_state):
                rr[m] *= c  # (I - c0 J0) u = c (f + sum C u / h)
            w_solve(rr, c0, avg, lu, piv, g0, s0, yi)
            u[i, :] = yi
        ynew[:] = y
        err[:] = 0.0
        for i in range(s):
            for m in range(n_state):
                ynew[m] += tab_b[i] * u[i, m]
                err[m] += tab_bt[i] * u[i, m]
        e = 0.0
        finite = True
        for m in range(n_state):
            if not np.isfinite(ynew[m]):
                finite = False
                break
            size = min(max(abs(y[m]), abs(ynew[m])), cap[m])
            e += (err[m] / (atol + rtol * size)) ** 2
        e = np.sqrt(e / n_state) if finite else np.inf
        if fixed <= 0.0 and e > 1.0:
            stats[1] += 1
            if wstate[1] > 0:  # the J was reused: retry the same step with a fresh one (CVODE)
                wstate[0] = 0.0
                continue
            h *= 0.2 if not np.isfinite(e) else max(0.2, 0.9 * e**expo)
            if h < 1e-14 * max(1.0, abs(t)):
                status = 1 if finite else 2
                break
            continue
        if not finite:
            status = 2
            break
        rhs(ynew, avg, diff, weights, eta_par, eta_perp, chi_sigma, phi, fnew)
        stats[2] += 1
        stats[0] += 1
        wstate[1] += 1.0
        t_new = t + h
        while i_out < t_eval.size and t_eval[i_out] <= t_new:
            hermite(t, y, f, t_new, ynew, fnew, t_eval[i_out], out[i_out])
            i_out += 1
        t = t_new
        y[:] = ynew
        f[:] = fnew
        if fixed <= 0.0:
            h *= min(5.0, max(0.2, 0.9 * max(e, 1e-10) ** expo))
    return t, h, i_out, status
