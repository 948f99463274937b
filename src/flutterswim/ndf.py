"""Compiled variable-order NDF/BDF stepping of the filament ODE (the whole step loop in one kernel).

The algorithm is that of scipy.integrate.BDF (Shampine & Reichelt, SIAM J. Sci. Comput. 18
(1997): the numerical differentiation formulas NDF1-5 in the quasi-constant step form with
modified divided differences D, orders 1 to 5, error constants, order selection from the
neighbouring orders' estimates), compiled end to end, with the filament's structured linear
algebra of :mod:`flutterswim.rosw` for the Newton matrix I - c J (c = h / alpha_k):

* The Jacobian (the W-Jacobian: without the change of G with theta) is kept with its state
  and evaluated again only when the simplified Newton iteration fails to converge with it
  (as scipy and CVODE do); the LU of I - c J is kept until the step size or the order
  changes, or Newton fails.
* Frames are the method's own interpolant (the order-k polynomial through D), not a cut
  of the step: stopping at frames would restart the quasi-constant step sequence.

State across calls: ``D`` (MAX_ORDER + 3, n), ``istate`` = [order, steps at this size,
LU valid, J current], ``fstate`` = [h_abs, c of the LU].
"""

from __future__ import annotations

import numpy as np

from . import _jit, rosw

KERNELS = ("compute_r", "change_d", "norm", "run")

MAX_ORDER = 5
NEWTON_MAXITER = 4
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
KAPPA = np.array([0.0, -0.1850, -1.0 / 9.0, -0.0823, -0.0415, 0.0])
GAMMA = np.concatenate(([0.0], np.cumsum(1.0 / np.arange(1, MAX_ORDER + 1))))
ALPHA = (1.0 - KAPPA) * GAMMA
ERROR_CONST = KAPPA * GAMMA + 1.0 / np.arange(1, MAX_ORDER + 2)


def kernels():
    """This module with its kernels compiled (numba), callees (rosw) first."""
    import sys

    rosw.kernels()
    mod = sys.modules[__name__]
    _jit.compile_module(mod, KERNELS)
    return mod


def compute_r(order, factor):
    """The matrix that changes the differences array for a step size ratio ``factor``."""
    m = np.zeros((order + 1, order + 1))
    for j in range(order + 1):
        m[0, j] = 1.0
    for i in range(1, order + 1):
        for j in range(1, order + 1):
            m[i, j] = (i - 1.0 - factor * j) / i
    for i in range(1, order + 1):
        for j in range(order + 1):
            m[i, j] *= m[i - 1, j]
    return m


def change_d(d, order, factor):
    """D[:order+1] <- (R U)^T D[:order+1] (scipy's change_D), in place."""
    r = compute_r(order, factor)
    u = compute_r(order, 1.0)
    ru = r @ u
    k = order + 1
    n = d.shape[1]
    tmp = np.zeros((k, n))
    for i in range(k):
        for j in range(k):
            w = ru[j, i]
            if w != 0.0:
                for m in range(n):
                    tmp[i, m] += w * d[j, m]
    d[:k, :] = tmp


def norm(x, y, rtol, atol, cap):
    """RMS norm of x / (atol + rtol min(|y|, cap))."""
    e = 0.0
    for m in range(x.size):
        e += (x[m] / (atol + rtol * min(abs(y[m]), cap[m]))) ** 2
    return np.sqrt(e / x.size)


def run(y, t, t_stop, d, istate, fstate, t_eval, out, i_out, rtol, atol, cap, max_step, fixed, avg, diff,
        weights, eta_par, eta_perp, chi_sigma, phi, max_steps, max_order, newton_maxiter, yield_frames,
        yield_steps, lu, piv, g0, s0, yj, alpha, gamma, error_const, stats):
    """Integrate from t to t_stop (the last step cut to end there); y is the state at the end.
    Frames at t_eval[i_out:] <= t are written to out by the interpolant. Returns (t, i_out,
    status): 0 reached t_stop, 1 step size collapsed, 2 non-finite state, 3 singular matrix,
    4 too many steps, 5 returned early: after a step that wrote frames (``yield_frames``) or
    after ``yield_steps`` steps (> 0), so that the caller regains control (a Ctrl-C is seen
    only between compiled calls); calling again continues exactly as without the return.
    ``fixed`` > 0: steps of that size at the order in istate, Newton to convergence, no error
    control (order tests, with D prepared from exact back values).
    ``stats`` (int64) += [steps, rejected, rhs, jacobians, LUs]."""
    n = y.size
    order = istate[0]
    n_equal = istate[1]
    h_abs = fstate[0]
    # scipy's max(10 eps / rtol, min(0.03, rtol^0.5)), floored at 1e-5 instead: the same above
    # rtol 1e-10, and a converged Newton (not 0.2 of the tolerance) when atol dominates
    newton_tol = max(1e-5, min(0.03, np.sqrt(rtol)))
    y_pred = np.empty(n)
    psi = np.empty(n)
    ynew = np.empty(n)
    dd = np.empty(n)
    f = np.empty(n)
    rr = np.empty(n)
    dy = np.empty(n)
    scale = np.empty(n)
    status = 0
    steps = 0
    while t < t_stop - 1e-12 * max(1.0, abs(t_stop)):
        if stats[0] + stats[1] >= max_steps:
            status = 4
            break
        if fixed > 0.0:
            h_abs = fixed
        elif h_abs > max_step:
            change_d(d, order, max_step / h_abs)
            h_abs = max_step
            n_equal = 0
            istate[2] = 0
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        accepted = False
        n_iter = 0
        t_new = t
        while not accepted:
            if h_abs < min_step:
                status = 1
                break
            t_new = t + h_abs
            # a step ending within the loop's slack of t_stop ends at t_stop: the loop stopped
            # there (1e-12 short) and the frame at t_stop was never written
            if t_new > t_stop - 1e-12 * max(1.0, abs(t_stop)) and fixed <= 0.0:
                t_new = t_stop
                change_d(d, order, (t_new - t) / h_abs)
                n_equal = 0
                istate[2] = 0
            h = t_new - t
            h_abs = h
            for m in range(n):
                acc = 0.0
                for j in range(order + 1):
                    acc += d[j, m]
                y_pred[m] = acc
                acc = 0.0
                for j in range(1, order + 1):
                    acc += gamma[j] * d[j, m]
                psi[m] = acc / alpha[order]
                scale[m] = atol + rtol * min(abs(y_pred[m]), cap[m])
            c = h / alpha[order]
            converged = False
            while not converged:
                if istate[2] == 0 or fstate[1] <= 0.0:
                    ok = rosw.w_factor(yj, c, avg, diff, weights, eta_par, eta_perp, chi_sigma, phi, lu, piv, g0, s0)
                    stats[4] += 1
                    if not ok:
                        status = 3
                        break
                    istate[2] = 1
                    fstate[1] = c
                # simplified Newton (scipy's solve_bdf_system) with the factors at c_lu
                ynew[:] = y_pred
                dd[:] = 0.0
                rate_ok = False
                dy_old = -1.0
                for k in range(newton_maxiter):
                    rosw.rhs(ynew, avg, diff, weights, eta_par, eta_perp, chi_sigma, phi, f)
                    stats[2] += 1
                    finite = True
                    for m in range(n):
                        if not np.isfinite(f[m]):
                            finite = False
                    if not finite:
                        break
                    for m in range(n):
                        rr[m] = c * f[m] - psi[m] - dd[m]
                    rosw.w_solve(rr, fstate[1], avg, lu, piv, g0, s0, dy)
                    dn = 0.0
                    for m in range(n):
                        dn += (dy[m] / scale[m]) ** 2
                    dn = np.sqrt(dn / n)
                    n_iter = k + 1
                    if dy_old >= 0.0:
                        rate = dn / dy_old if dy_old > 0.0 else 0.0
                        if fixed <= 0.0 and (rate >= 1.0 or rate ** (newton_maxiter - k) / (1.0 - rate) * dn > newton_tol):
                            break
                    else:
                        rate = -1.0
                    for m in range(n):
                        ynew[m] += dy[m]
                        dd[m] += dy[m]
                    if dn == 0.0 or (rate >= 0.0 and rate < 1.0 and rate / (1.0 - rate) * dn < newton_tol):
                        rate_ok = True
                        break
                    dy_old = dn
                converged = rate_ok
                if not converged:
                    if istate[3] == 1:  # the J is current: cut the step
                        break
                    yj[:] = y_pred  # a fresh Jacobian at the prediction
                    stats[3] += 1
                    istate[3] = 1
                    istate[2] = 0
            if status != 0:
                break
            if not converged:
                if fixed > 0.0:
                    status = 1
                    break
                stats[1] += 1
                h_abs *= 0.5
                change_d(d, order, 0.5)
                n_equal = 0
                istate[2] = 0
                continue
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
            for m in range(n):
                scale[m] = atol + rtol * min(abs(ynew[m]), cap[m])
                rr[m] = error_const[order] * dd[m]
            err = 0.0
            for m in range(n):
                err += (rr[m] / scale[m]) ** 2
            err = np.sqrt(err / n)
            if fixed <= 0.0 and err > 1.0:
                stats[1] += 1
                factor = max(MIN_FACTOR, safety * err ** (-1.0 / (order + 1)))
                h_abs *= factor
                change_d(d, order, factor)
                n_equal = 0
            else:
                accepted = True
        if status != 0:
            break
        stats[0] += 1
        n_equal += 1
        istate[3] = 0  # the J ages: a later convergence failure re-evaluates it
        for m in range(n):
            d[order + 2, m] = dd[m] - d[order + 1, m]
            d[order + 1, m] = dd[m]
        for i in range(order, -1, -1):
            for m in range(n):
                d[i, m] += d[i + 1, m]
        wrote = False
        while i_out < t_eval.size and t_eval[i_out] <= t_new:
            te = t_eval[i_out]
            for m in range(n):
                out[i_out, m] = d[0, m]
            p = 1.0
            for j in range(order):
                p *= (te - (t_new - h * j)) / (h * (1.0 + j))
                for m in range(n):
                    out[i_out, m] += p * d[j + 1, m]
            i_out += 1
            wrote = True
        t = t_new
        y[:] = d[0]
        if fixed <= 0.0 and n_equal >= order + 1:
            em = np.inf
            if order > 1:
                for m in range(n):
                    rr[m] = error_const[order - 1] * d[order, m]
                em = norm(rr, ynew, rtol, atol, cap)
            ep = np.inf
            if order < max_order:
                for m in range(n):
                    rr[m] = error_const[order + 1] * d[order + 2, m]
                ep = norm(rr, ynew, rtol, atol, cap)
            fm = em ** (-1.0 / order) if em > 0.0 else np.inf
            f0 = err ** (-1.0 / (order + 1)) if err > 0.0 else np.inf
            fp = ep ** (-1.0 / (order + 2)) if ep > 0.0 else np.inf
            best = fm  # the first of the largest, as numpy's argmax in scipy
            delta = -1
            if f0 > best:
                best = f0
                delta = 0
            if fp > best:
                best = fp
                delta = 1
            order += delta
            factor = min(MAX_FACTOR, safety * best)
            h_abs *= factor
            change_d(d, order, factor)
            n_equal = 0
            istate[2] = 0
        steps += 1
        if (yield_frames and wrote) or steps == yield_steps:
            status = 5
            break
    istate[0] = order
    istate[1] = n_equal
    fstate[0] = h_abs
    return t, i_out, status
