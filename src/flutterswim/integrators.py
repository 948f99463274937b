"""Time integrators for the stiff filament ODE y' = f(t, y).

``ros34pw2`` (default): the 4-stage, order-3 Rosenbrock-W method ROS34PW2 of
Rang & Angermann (BIT 45, 2005), L-stable and stiffly accurate. A W-method keeps
its order with an approximate Jacobian, so the mobility matrix's dependence on the
shape (a non-stiff term) may be left out of J. One LU per step, no Newton iterations.
Adaptive steps from the embedded order-2 solution; output at requested times by
cubic Hermite interpolation (order 3, like the method).

``radau`` / ``bdf``: scipy.integrate.solve_ivp, the baseline of the benchmarks.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg as sla

__all__ = ["SolverStats", "Solution", "METHODS", "integrate"]

Fun = Callable[[float, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class SolverStats:
    method: str
    order: int
    n_steps: int
    n_rejected: int
    n_rhs: int
    n_jac: int
    n_lu: int
    wall_time: float

    def to_dict(self) -> dict[str, float | int | str]:
        return dict(self.__dict__)


@dataclass(frozen=True)
class Solution:
    t: np.ndarray  # (T,)
    y: np.ndarray  # (T, n)
    status: str  # "completed", "stopped", "failed"
    message: str
    t_final: float
    y_final: np.ndarray
    stats: SolverStats


@dataclass(frozen=True)
class RosenbrockW:
    """Tableau in Hairer's convention: (I - g h J) k_i = h f(t + c_i h, y + sum a_ij k_j)
    + h J sum gam_ij k_j + h^2 d_i f_t;  y1 = y + sum b_i k_i,  error = sum (b - bh)_i k_i."""

    name: str
    order: int
    gamma: float
    a: np.ndarray
    gam: np.ndarray
    b: np.ndarray
    bh: np.ndarray

    @property
    def c(self) -> np.ndarray:
        return self.a.sum(axis=1)

    @property
    def d(self) -> np.ndarray:
        return self.gamma + self.gam.sum(axis=1)


def _ros34pw2() -> RosenbrockW:
    g = 4.3586652150845900e-01
    a = np.zeros((4, 4))
    a[1, 0] = 8.7173304301691801e-01
    a[2, 0], a[2, 1] = 8.4457060015369423e-01, -1.1299064236397981e-01
    a[3, 2] = 1.0
    gam = np.zeros((4, 4))
    gam[1, 0] = -8.7173304301691801e-01
    gam[2, 0], gam[2, 1] = -9.0338057013044082e-01, 5.4180672388095326e-02
    gam[3, 0], gam[3, 1], gam[3, 2] = 2.4212380706095346e-01, -1.2232505839045147e00, 5.4526025533510214e-01
    b = np.array([2.4212380706095346e-01, -1.2232505839045147e00, 1.5452602553351023e00, g])
    bh = np.array([3.7810903145819369e-01, -9.6042292212423178e-02, 0.5, 2.1793326075422950e-01])
    return RosenbrockW("ros34pw2", 3, g, a, gam, b, bh)


ROS34PW2 = _ros34pw2()


@dataclass(frozen=True)
class ScipyMethod:
    name: str
    order: int
    scipy_name: str


METHODS: dict[str, RosenbrockW | ScipyMethod] = {
    "ros34pw2": ROS34PW2,
    "radau": ScipyMethod("radau", 5, "Radau"),
    "bdf": ScipyMethod("bdf", 5, "BDF"),
}


def _hermite(t0, y0, f0, t1, y1, f1, t):
    h = t1 - t0
    u = (np.asarray(t) - t0) / h
    u = u[:, None]
    h00 = (1 + 2 * u) * (1 - u) ** 2
    h10 = u * (1 - u) ** 2
    h01 = u * u * (3 - 2 * u)
    h11 = u * u * (u - 1)
    return h00 * y0 + h10 * h * f0 + h01 * y1 + h11 * h * f1


def integrate(
    fun: Fun,
    jac: Callable[[float, np.ndarray], np.ndarray] | None,
    t_span: tuple[float, float],
    y0: np.ndarray,
    t_eval: np.ndarray,
    *,
    method: str = "ros34pw2",
    rtol: float = 1e-5,
    atol: float = 1e-7,
    max_step: float = np.inf,
    first_step: float | None = None,
    breakpoints: tuple[float, ...] = (),
    time_dependent: bool = True,
    check: Callable[[float, np.ndarray], str | None] | None = None,
    max_steps: int = 10_000_000,
    progress: Callable[[float], None] | None = None,
    scale_cap: np.ndarray | None = None,
) -> Solution:
    """Integrate y' = fun(t, y) over t_span, returning y at t_eval (sorted, inside t_span).

    ``check(t, y)`` runs after each accepted step; a non-None string stops the run
    with that reason (status "stopped"). A non-finite state or step-size collapse
    ends it with status "failed" and the reason. ``scale_cap`` (n,) caps |y| in the
    relative part of the error weights, atol + rtol min(|y|, cap): for components such
    as positions and angles, whose size grows with distance swum or turned, not with
    what needs resolving (ros34pw2 only).
    """
    scheme = METHODS.get(method)
    if scheme is None:
        from ._validate import ParameterError

        raise ParameterError(f"method={method!r} is unknown; choose one of {sorted(METHODS)}")
    if isinstance(scheme, ScipyMethod):
        return _integrate_scipy(fun, t_span, y0, t_eval, scheme, rtol, atol, max_step, check)
    return _integrate_rosw(
        fun, jac, t_span, y0, t_eval, scheme, rtol, atol, max_step, first_step,
        breakpoints, time_dependent, check, max_steps, progress, scale_cap,
    )


def _integrate_rosw(fun, jac, t_span, y0, t_eval, tab, rtol, atol, max_step, first_step,
                    breakpoints, time_dependent, check, max_steps, progress, scale_cap):
    wall0 = time.perf_counter()
    t0, t1 = float(t_span[0]), float(t_span[1])
    y = np.array(y0, dtype=float)
    n = y.size
    eye = np.eye(n)
    out = np.full((len(t_eval), n), np.nan)
    n_out = 0
    while n_out < len(t_eval) and t_eval[n_out] <= t0:
        out[n_out] = y
        n_out += 1
    stops = sorted({b for b in breakpoints if t0 < b < t1} | {t1})
    t = t0
    f = fun(t, y)
    n_rhs, n_jac, n_lu, n_steps, n_rej = 1, 0, 0, 0, 0
    scale = atol + rtol * np.abs(y)
    h = first_step or min(max_step, 0.01 * max(1e-3, 1.0 / max(1e-12, np.sqrt(np.mean((f / scale) ** 2)))), t1 - t0)
    status, message = "completed", "reached t_end"
    a, gam, b, bh, c, d, g = tab.a, tab.gam, tab.b, tab.bh, tab.c, tab.d, tab.gamma
    e = b - bh
    s = len(b)
    k = np.empty((s, n))
    jmat = None
    last_h_lu = None
    ft = np.zeros(n)
    # LAPACK directly: scipy.linalg.lu_factor/lu_solve wrappers cost more than the
    # factorisation itself at these sizes.
    getrf, getrs = sla.get_lapack_funcs(("getrf", "getrs"), (eye,))
    while t < t1:
        if n_steps + n_rej >= max_steps:
            status, message = "failed", f"maximum number of steps ({max_steps}) reached at t={t:.6g}"
            break
        target = next(x for x in stops if x > t)
        h = min(h, max_step)
        if t + h >= target - 1e-12 * max(1.0, abs(target)):
            h = target - t
        if jmat is None:
            jmat = jac(t, y) if jac is not None else _fd_jac(fun, t, y, f)
            n_jac += 1
            if jac is None:
                n_rhs += n
        if last_h_lu != h:
            lu, piv, info = getrf(eye - (g * h) * jmat, overwrite_a=True)
            n_lu += 1
            last_h_lu = h if info == 0 else None
            if info != 0:
                status, message = "failed", f"singular iteration matrix at t={t:.6g}, h={h:.3g}"
                break
        if time_dependent:
            dt = 1e-7 * max(1.0, abs(t))
            ft = (fun(t + dt, y) - f) / dt
            n_rhs += 1
        for i in range(s):
            if i == 0:
                fi = f
                rhs = h * fi
            else:
                yi = y + a[i, :i] @ k[:i]
                fi = fun(t + c[i] * h, yi)
                n_rhs += 1
                rhs = h * fi + h * (jmat @ (gam[i, :i] @ k[:i]))
            if time_dependent:
                rhs = rhs + (h * h * d[i]) * ft
            k[i] = getrs(lu, piv, rhs)[0]
        y_new = y + b @ k
        finite = np.all(np.isfinite(y_new))
        if finite:
            size = np.maximum(np.abs(y), np.abs(y_new))
            if scale_cap is not None:
                size = np.minimum(size, scale_cap)
            err_vec = (e @ k) / (atol + rtol * size)
            err = float(np.sqrt(np.mean(err_vec**2)))
        else:
            err = np.inf
        if err > 1.0:
            n_rej += 1
            h *= 0.2 if not np.isfinite(err) else max(0.2, 0.9 * err ** (-1.0 / 3.0))
            if h < 1e-14 * max(1.0, abs(t)):
                status = "failed"
                message = (f"step size collapsed to {h:.3g} at t={t:.6g}" if finite
                           else f"non-finite state at t={t:.6g}")
                break
            continue
        t_new = t + h
        f_new = fun(t_new, y_new)
        n_rhs += 1
        n_steps += 1
        while n_out < len(t_eval) and t_eval[n_out] <= t_new:
            j = n_out
            while j < len(t_eval) and t_eval[j] <= t_new:
                j += 1
            out[n_out:j] = _hermite(t, y, f, t_new, y_new, f_new, t_eval[n_out:j])
            n_out = j
        t, y, f = t_new, y_new, f_new
        jmat = None
        if progress is not None:
            progress(t)
        reason = check(t, y) if check is not None else None
        if reason is not None:
            status, message = "stopped", reason
            break
        h *= min(5.0, max(0.2, 0.9 * max(err, 1e-10) ** (-1.0 / 3.0)))
    keep = n_out
    stats = SolverStats(tab.name, tab.order, n_steps, n_rej, n_rhs, n_jac, n_lu,
                        time.perf_counter() - wall0)
    return Solution(np.asarray(t_eval[:keep]), out[:keep], status, message, t, y, stats)


def _fd_jac(fun, t, y, f0):
    n = y.size
    jmat = np.empty((n, n))
    for i in range(n):
        dy = 1e-7 * max(1.0, abs(y[i]))
        yp = y.copy()
        yp[i] += dy
        jmat[:, i] = (fun(t, yp) - f0) / dy
    return jmat


def _integrate_scipy(fun, t_span, y0, t_eval, scheme, rtol, atol, max_step, check):
    from scipy.integrate import solve_ivp

    wall0 = time.perf_counter()
    sol = solve_ivp(fun, t_span, y0, method=scheme.scipy_name, t_eval=t_eval, rtol=rtol,
                    atol=atol, max_step=max_step)
    stats = SolverStats(scheme.name, scheme.order, int(sol.t.size and len(sol.t)), 0,
                        int(sol.nfev), int(sol.njev), int(sol.nlu), time.perf_counter() - wall0)
    status = "completed" if sol.success else "failed"
    y_final = sol.y[:, -1] if sol.y.size else np.asarray(y0)
    t_final = float(sol.t[-1]) if sol.t.size else float(t_span[0])
    return Solution(sol.t, sol.y.T, status, sol.message, t_final, y_final, stats)
