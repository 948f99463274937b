"""Time integrators for the stiff filament ODE y' = f(t, y).

``ndf`` (default): the compiled variable-order NDF (:mod:`flutterswim.ndf`, scipy's BDF
algorithm, orders 1-5) with the W-Jacobian kept until Newton fails and the structured LU
until the step or order changes; ``order`` 5, its highest (each order fitted).

Compiled Rosenbrock-W methods (:mod:`flutterswim.rosw`: the whole step loop in one numba
kernel, the filament's right-hand side and structured linear algebra inlined, Jacobian and
LU reused across steps), used by :func:`integrate_filament`:

``ros34pw3``: ROS34PW3 of Rang & Angermann (BIT 45, 2005), 4 stages, order 4 with
the exact Jacobian, order 3 as a W-method, embedded order 3; A-stable.
``ros34pw2`` (the default before ``ndf``): ROS34PW2 (same paper), order 3 as a W-method, embedded order 2, L-stable and
stiffly accurate.

``ros34pw2-wave1``: ROS34PW2 stepped in Python with a fresh Jacobian and a full (2N+3)-square
LU every step (the wave-1 default, kept as a baseline and for fields that change between
breakpoints). ``radau`` / ``bdf``: scipy.integrate.solve_ivp, baselines.

Each method states its order (``order``: the order it shows on this problem with the
W-Jacobian, fitted by tests/test_integrators_order.py).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg as sla

__all__ = ["SolverStats", "Solution", "METHODS", "DEFAULT_METHOD", "integrate", "integrate_filament"]

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
class CompiledRosW:
    """Tableau of a compiled Rosenbrock-W method in the transformed form (:mod:`flutterswim.rosw`):
    A (s, s), C (s, s), b, bt (error weights), gamma; ``order`` of the step, ``q`` of the
    error estimate (step-size exponent 1/(q+1))."""

    name: str
    order: int
    q: int
    gamma: float
    a: np.ndarray
    c: np.ndarray
    b: np.ndarray
    bt: np.ndarray
    w: bool = True  # a W-method: J and LU may be reused across steps

    @classmethod
    def from_hairer(cls, tab: RosenbrockW, q: int) -> "CompiledRosW":
        """Transform a tableau in Hairer's convention: with Gamma = gam + gamma I,
        A = a Gamma^-1, C = diag(1/gamma) - Gamma^-1, b_T = b Gamma^-1, bt_T = (b - bh) Gamma^-1."""
        gi = np.linalg.inv(tab.gam + tab.gamma * np.eye(len(tab.b)))
        c = np.diag(np.full(len(tab.b), 1.0 / tab.gamma)) - gi
        return cls(tab.name, tab.order, q, tab.gamma, np.tril(tab.a @ gi, -1), np.tril(c, -1), tab.b @ gi,
                   (tab.b - tab.bh) @ gi)


def _ros34pw3() -> CompiledRosW:
    """ROS34PW3, Rang & Angermann, BIT 45 (2005) 761-787, in the transformed form of
    OrdinaryDiffEq.jl (ROS34PW3 tableau: a, C, b, btilde, gamma), coefficients copied as given there."""
    a = np.zeros((4, 4))
    a[1, 0] = 2.3541034887609085
    a[2, 0], a[2, 1] = 2.1274518517432335, 0.7018666706430658
    a[3, 0], a[3, 1], a[3, 2] = 1.6573541366907125, 0.37998365119129385, 0.7677537933767512
    c = np.zeros((4, 4))
    c[1, 0] = -2.20302237067446
    c[2, 0], c[2, 1] = -2.750060114993467, -0.8408569631081119
    c[3, 0], c[3, 1], c[3, 2] = -3.0077871973155896, -0.7070774625618249, -1.1874362749274354
    b = np.array([2.5468758076906703, 0.5527809704437551, 0.920521963049926, 0.7201674983256354])
    bt = np.array([0.20632710213677674, 0.0026042321416049896, 0.006723394920071124, 0.7201674983256354])
    return CompiledRosW("ros34pw3", 4, 3, 1.0685790213016289, a, c, b, bt)



@dataclass(frozen=True)
class CompiledNDF:
    """Compiled variable-order NDF (:mod:`flutterswim.ndf`, scipy's BDF algorithm): ``order`` is
    the highest order it uses (each order k = 1..5 converges at order k)."""

    name: str
    order: int
    w: bool = True


@dataclass(frozen=True)
class ScipyMethod:
    name: str
    order: int
    scipy_name: str


DEFAULT_METHOD = "ndf"

METHODS: dict[str, RosenbrockW | CompiledRosW | CompiledNDF | ScipyMethod] = {
    "ndf": CompiledNDF("ndf", 5),
    "ros34pw3": _ros34pw3(),
    "ros34pw2": CompiledRosW.from_hairer(ROS34PW2, 2),
    "ros34pw2-wave1": ROS34PW2,
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
    method: str = "ros34pw2-wave1",
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
    jumps: tuple[float, ...] | None = None,
) -> Solution:
    """Integrate y' = fun(t, y) over t_span, returning y at t_eval (sorted, inside t_span).

    ``check(t, y)`` runs after each accepted step; a non-None string stops the run
    with that reason (status "stopped"). A non-finite state or step-size collapse
    ends it with status "failed" and the reason. ``scale_cap`` (n,) caps |y| in the
    relative part of the error weights, atol + rtol min(|y|, cap): for components such
    as positions and angles, whose size grows with distance swum or turned, not with
    what needs resolving (ros34pw2 only). A compiled method's name takes its Python-stepped
    counterpart: ``ndf`` scipy's BDF (the algorithm it compiles), ``ros34pw2``/``ros34pw3``
    the Python ROS34PW2. ``breakpoints``: times a one-step method steps to; ``jumps`` (default:
    all breakpoints): those where fun jumps, at which scipy's multistep BDF (and Radau) restart
    (a restart goes back to order 1: at the kinks of a continuous field it only costs).
    """
    scheme = METHODS.get(method)
    if scheme is None:
        from ._validate import ParameterError

        raise ParameterError(f"method={method!r} is unknown; choose one of {sorted(METHODS)}")
    if isinstance(scheme, CompiledNDF):
        # a Python right-hand side: scipy's BDF, the algorithm the compiled NDF compiles
        scheme = METHODS["bdf"]
    if isinstance(scheme, ScipyMethod):
        return _integrate_scipy(fun, jac, t_span, y0, t_eval, scheme, rtol, atol, max_step, check,
                                breakpoints if jumps is None else jumps, progress, max_steps)
    if isinstance(scheme, CompiledRosW):
        scheme = ROS34PW2  # a Python right-hand side: the Python-stepped ROS34PW2
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
            # the stages use J in (I - gamma h J) and in h J sum gamma_ij k_j: both must be the
            # same matrix (the method's order conditions). Keeping the LU of the last step's J
            # while the stage term used this one made the method first order wherever h
            # repeated (max_step, fixed steps): a review measured order 1.00 at fixed h.
            last_h_lu = None
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
    # (the Python-stepped ROS34PW2 is the wave-1 stepper, not the compiled method of the same tableau)
    stats = SolverStats(f"{tab.name}-wave1", tab.order, n_steps, n_rej, n_rhs, n_jac, n_lu,
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


def _integrate_scipy(fun, jac, t_span, y0, t_eval, scheme, rtol, atol, max_step, check, breakpoints=(),
                     progress=None, max_steps=10_000_000):
    """scipy's Radau or BDF stepped here (``OdeSolver.step``): restarted at each of
    ``breakpoints`` (those where the right-hand side jumps: :func:`integrate`'s ``jumps``), frames from each step's dense output, and
    ``check`` and ``progress`` after each accepted step, as on the other paths. The error
    weights are scipy's, atol + rtol |y| (no ``scale_cap``)."""
    from scipy import integrate as si

    wall0 = time.perf_counter()
    t0, t1 = float(t_span[0]), float(t_span[1])
    y = np.array(y0, dtype=float)
    out = np.full((len(t_eval), y.size), np.nan)
    n_out = 0
    while n_out < len(t_eval) and t_eval[n_out] <= t0:
        out[n_out] = y
        n_out += 1
    kw = {} if jac is None else {"jac": jac}
    status, message = "completed", "reached t_end"
    t = t0
    counts = np.zeros(4, dtype=np.int64)  # steps, rhs, jacobians, LUs
    for stop in sorted({b for b in breakpoints if t0 < b < t1} | {t1}):
        solver = getattr(si, scheme.scipy_name)(fun, t, y, stop, rtol=rtol, atol=atol, max_step=max_step, **kw)
        while solver.status == "running":
            if counts[0] >= max_steps:
                status, message = "failed", f"maximum number of steps ({max_steps}) reached at t={solver.t:.6g}"
                break
            reason = solver.step()
            if solver.status == "failed":
                status, message = "failed", f"{reason} at t={solver.t:.6g}"
                break
            counts[0] += 1
            if n_out < len(t_eval) and t_eval[n_out] <= solver.t:
                j = n_out
                while j < len(t_eval) and t_eval[j] <= solver.t:
                    j += 1
                out[n_out:j] = solver.dense_output()(t_eval[n_out:j]).T
                n_out = j
            if progress is not None:
                progress(solver.t)
            reason = check(solver.t, solver.y) if check is not None else None
            if reason is not None:
                status, message = "stopped", reason
                break
        counts[1:] += [solver.nfev, solver.njev, solver.nlu]
        t, y = float(solver.t), np.array(solver.y)
        if status != "completed":
            break
    stats = SolverStats(scheme.name, scheme.order, int(counts[0]), 0, int(counts[1]), int(counts[2]),
                        int(counts[3]), time.perf_counter() - wall0)
    return Solution(np.asarray(t_eval[:n_out]), out[:n_out], status, message, t, y, stats)


#: LU reuse window |gamma h / gamma h0 - 1| and the largest Jacobian age (accepted steps).
REUSE = 0.25
MAX_AGE = 20
RTOL_NO_REUSE = 1e-8
#: The compiled NDF returns to Python after this many steps (about 10 ms), where a Ctrl-C is
#: seen (a signal waits until compiled code returns); the integration is unchanged.
YIELD_STEPS = 400

_STATUS = {1: "step size collapsed", 2: "non-finite state", 3: "singular iteration matrix",
           4: "maximum number of steps reached"}


def _workspace(fil, pieces, y0, t_eval, scale_cap):
    """State, frames (those at or before the start filled), error-weight caps, W factor storage
    and counters of the compiled loops."""
    n = fil.n
    y = np.array(y0, dtype=float)
    out = np.full((len(t_eval), y.size), np.nan)
    t_eval = np.ascontiguousarray(t_eval, dtype=float)
    t = float(pieces[0][0])
    i_out = 0
    while i_out < len(t_eval) and t_eval[i_out] <= t:
        out[i_out] = y
        i_out += 1
    cap = np.full(y.size, np.inf) if scale_cap is None else np.asarray(scale_cap, float)
    lu, piv = np.zeros((n + 2, n + 2)), np.zeros(n + 2, dtype=np.int64)
    g0, s0 = np.zeros((n + 2, n + 2)), np.zeros(n + 1)
    return y, y.size, out, t_eval, t, i_out, cap, lu, piv, g0, s0, np.zeros(5, dtype=np.int64)


def integrate_filament(
    fil,
    pieces: list[tuple[float, float, float]],
    t_end: float,
    y0: np.ndarray,
    t_eval: np.ndarray,
    *,
    method: str = DEFAULT_METHOD,
    rtol: float = 1e-5,
    atol: float = 1e-7,
    max_step: float = np.inf,
    fixed_step: float = 0.0,
    check: Callable[[float, np.ndarray], str | None] | None = None,
    max_steps: int = 10_000_000,
    progress: Callable[[float], None] | None = None,
    scale_cap: np.ndarray | None = None,
    reuse: bool = True,
) -> Solution:
    """Integrate the filament (:class:`flutterswim.filament.Filament`) with a compiled
    Rosenbrock-W method (:mod:`flutterswim.rosw`). ``pieces``: (t_start, phi, sigma), the field
    steady from each t_start to the next (or ``t_end``). ``check(t, y)`` and ``progress(t)``
    run at every frame of ``t_eval`` (not every step). ``fixed_step`` > 0: constant steps,
    no error control. ``reuse=False``: a fresh Jacobian and LU every step."""
    from . import rosw

    tab = METHODS[method]
    if isinstance(tab, CompiledNDF):
        return _integrate_ndf(fil, pieces, t_end, y0, t_eval, tab, rtol, atol, max_step, fixed_step, check,
                              max_steps, progress, scale_cap)
    if not isinstance(tab, CompiledRosW):
        raise ValueError(f"{method!r} is not a compiled Rosenbrock-W method")
    k = rosw.kernels()
    wall0 = time.perf_counter()
    y, size, out, t_eval, t, i_out, cap, lu, piv, g0, s0, stats = _workspace(fil, pieces, y0, t_eval, scale_cap)
    t_first = t
    avg, diff, w = fil._avg, fil._diff, fil._weights
    f = np.empty(size)
    h = np.nan
    status, message = "completed", "reached t_end"
    every_frame = check is not None or progress is not None
    # Reuse pays at moderate tolerances only: below RTOL_NO_REUSE a stale J makes steps fail
    # (paper job, rtol 1e-8: 32k rejected of 80k), so every step gets a fresh J and LU.
    reuse = reuse and tab.w and rtol >= RTOL_NO_REUSE
    for p, (_ta, phi, sigma) in enumerate(pieces):
        tb = pieces[p + 1][0] if p + 1 < len(pieces) else t_end
        if tb <= t:
            continue
        chi_sigma = fil.chi * sigma
        wstate = np.zeros(3)  # the Jacobian depends on the field: new factors per piece
        k.rhs(y, avg, diff, w, fil.eta_par, fil.eta_perp, chi_sigma, phi, f)
        stats[2] += 1
        if not np.isfinite(h):
            scale = atol + rtol * np.minimum(np.abs(y), cap)
            h = min(max_step, 0.01 * max(1e-3, 1.0 / max(1e-12, float(np.sqrt(np.mean((f / scale) ** 2))))))
        stops = [tb]
        if every_frame:
            stops = [x for x in t_eval[i_out:] if t < x < tb] + [tb]
        code = 0
        chunk = max(1000, max_steps // 100)  # (returns now and then: the "too stiff" check)
        for stop in stops:
            while True:
                budget = min(max_steps, int(stats[0] + stats[1]) + chunk)
                t, h, i_out, code = k.run(y, f, t, stop, h, t_eval, out, i_out, tab.a, tab.c, tab.b, tab.bt,
                                          tab.gamma, float(tab.q), rtol, atol, cap, max_step, fixed_step, avg, diff,
                                          w, fil.eta_par, fil.eta_perp, chi_sigma, phi, budget,
                                          REUSE if reuse else -1.0, MAX_AGE if reuse else 1, lu, piv, g0, s0,
                                          wstate, stats)
                if code != 4 or budget >= max_steps:
                    break
                code = 0
                stiff = _too_stiff(t, t_first, t_end, int(stats[0] + stats[1]), max_steps, fixed_step)
                if stiff:
                    status, message = "failed", stiff
                    break
            if code or status != "completed":
                break
            if progress is not None:
                progress(t)
            reason = check(t, y) if check is not None else None
            if reason is not None:
                status, message = "stopped", reason
                break
        if code:
            status, message = "failed", f"{_STATUS[code]} at t={t:.6g} (h={h:.3g})"
        if status != "completed":
            break
    stats_ = SolverStats(tab.name, tab.order, int(stats[0]), int(stats[1]), int(stats[2]), int(stats[3]),
                         int(stats[4]), time.perf_counter() - wall0)
    return Solution(np.asarray(t_eval[:i_out]), out[:i_out], status, message, t, y, stats_)


def _too_stiff(t: float, t_first: float, t_end: float, taken: int, max_steps: int, fixed_step: float) -> str:
    """Why a run is hopelessly stiff, or "": a tenth of max_steps spent and, at its mean step so
    far (not the current one: small after each field piece's restart), ten times the steps
    left needed to reach t_end (kappa_E 1e9 times the paper's: 9.2 million steps of 5e-9 tau in
    110 s, then "maximum number of steps")."""
    mean_h = (t - t_first) / max(taken, 1)
    if fixed_step > 0.0 or taken < max_steps // 10 or not t_end - t > 10 * (max_steps - taken) * mean_h:
        return ""
    return (f"too stiff: at its mean step {mean_h:.3g} so far the run would need about "
            f"{(t_end - t) / mean_h if mean_h > 0 else np.inf:.2g} more steps to reach t_end, more than "
            f"max_steps={max_steps} (at t={t:.6g}, after {taken} steps)")


def _integrate_ndf(fil, pieces, t_end, y0, t_eval, tab, rtol, atol, max_step, fixed_step, check, max_steps,
                   progress, scale_cap, history=None, order=None):
    """:func:`integrate_filament` with the compiled NDF (:mod:`flutterswim.ndf`). ``history``
    (order + 1, n): exact values at t0 - order h, ..., t0 (oldest first) for fixed steps h at
    ``order`` from the start (order tests); otherwise each field piece starts at order 1."""
    from . import ndf, rosw

    k = ndf.kernels()
    wall0 = time.perf_counter()
    y, size, out, t_eval, t, i_out, cap, lu, piv, g0, s0, stats = _workspace(fil, pieces, y0, t_eval, scale_cap)
    t_first = t
    avg, diff, w = fil._avg, fil._diff, fil._weights
    d = np.zeros((ndf.MAX_ORDER + 3, size))
    f = np.empty(size)
    h_abs = np.nan
    status, message = "completed", "reached t_end"
    every_frame = check is not None or progress is not None
    alpha, gamma, econst = ndf.ALPHA, ndf.GAMMA, ndf.ERROR_CONST
    for p, (_ta, phi, sigma) in enumerate(pieces):
        tb = pieces[p + 1][0] if p + 1 < len(pieces) else t_end
        if tb <= t:
            continue
        chi_sigma = fil.chi * sigma
        # the field changes the ODE: restart at order 1 with a fresh Jacobian
        rosw.rhs(y, avg, diff, w, fil.eta_par, fil.eta_perp, chi_sigma, phi, f)
        stats[2] += 1
        if fixed_step > 0.0:
            h_abs = fixed_step
        elif not np.isfinite(h_abs):
            scale = atol + rtol * np.minimum(np.abs(y), cap)
            h_abs = min(max_step, 0.01 * max(1e-3, 1.0 / max(1e-12, float(np.sqrt(np.mean((f / scale) ** 2))))),
                        tb - t)
        d[:] = 0.0
        d[0] = y
        d[1] = f * h_abs
        ord0 = 1
        if history is not None:  # backward differences of equally spaced exact values
            ord0 = int(order)
            back = np.asarray(history, float)[::-1]  # newest first
            for j in range(ord0 + 1):
                d[j] = back[0]
                back = back[:-1] - back[1:] if j < ord0 else back
        istate = np.array([ord0, 0, 0, 0], dtype=np.int64)
        fstate = np.array([h_abs, 0.0])
        yj = y.copy()
        stats[3] += 1
        code = 0
        while True:
            i_before = i_out
            t, i_out, code = k.run(y, t, tb, d, istate, fstate, t_eval, out, i_out, rtol, atol, cap, max_step,
                                   fixed_step, avg, diff, w, fil.eta_par, fil.eta_perp, chi_sigma, phi, max_steps,
                                   ndf.MAX_ORDER if order is None else int(order),
                                   20 if fixed_step > 0.0 else ndf.NEWTON_MAXITER, every_frame, YIELD_STEPS,
                                   lu, piv, g0, s0,
                                   yj, alpha, gamma, econst, stats)
            if code not in (0, 5):
                break
            for i in range(i_before, i_out) if every_frame else ():  # each new frame, as the Rosenbrock path
                tf, yf = float(t_eval[i]), out[i]
                if progress is not None:
                    progress(tf)
                reason = check(tf, yf) if check is not None else None
                if reason is not None:
                    status, message = "stopped", reason
                    t, y, i_out = tf, yf.copy(), i + 1
                    break
            if code == 0 or status != "completed":
                break
            stiff = _too_stiff(t, t_first, t_end, int(stats[0] + stats[1]), max_steps, fixed_step)
            if stiff:
                status, message = "failed", stiff
                break
        h_abs = float(fstate[0])
        if code not in (0, 5):
            status, message = "failed", f"{_STATUS[code]} at t={t:.6g} (h={h_abs:.3g})"
        if status != "completed":
            break
    stats_ = SolverStats(tab.name, tab.order, int(stats[0]), int(stats[1]), int(stats[2]), int(stats[3]),
                         int(stats[4]), time.perf_counter() - wall0)
    return Solution(np.asarray(t_eval[:i_out]), out[:i_out], status, message, t, y, stats_)
