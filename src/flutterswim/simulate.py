"""``simulate``: the nonlinear morphoelastic filament from an initial state.

The maths lives in :mod:`flutterswim.filament` (dimensionless); this module converts
units at the edge, drives the integrator and packages a :class:`SimulationResult`.
"""

from __future__ import annotations

import functools
import math
from typing import Callable

import numpy as np

from . import defaults
from ._validate import ParameterError, angle as _angle, finite, positive, positive_int, tolerance, tolerances_reachable
from ._validate import n_segments as segments_checked
from .field import Constant, Field
from .filament import Filament, centreline
from .initial import InitialState
from .integrators import DEFAULT_METHOD, METHODS, CompiledNDF, CompiledRosW, integrate, integrate_filament
from .params import Groups, Parameters
from .result import SimulationResult

__all__ = ["simulate", "DEFAULT_SEGMENTS"]

DEFAULT_SEGMENTS = defaults.N_SEGMENTS



class RunFailedWarning(RuntimeWarning):
    """:func:`simulate` ended on a solver failure and returns the frames up to it (callers that
    report the failure themselves, as ``settle`` and the command line, silence it)."""

def simulate(
    params: Parameters | Groups,
    t_end: float,
    *,
    field: Field | float | None = None,
    initial: InitialState | None = None,
    n_segments: int = DEFAULT_SEGMENTS,
    n_frames: int | None = None,
    frame_dt: float | None = None,
    t_start: float = 0.0,
    rtol: float = defaults.RTOL,
    atol: float = defaults.ATOL,
    method: str = DEFAULT_METHOD,
    max_step: float | None = None,
    stop_on_self_intersection: bool = False,
    forces: bool = False,
    progress: bool = False,
    check: Callable[[float, np.ndarray], str | None] | None = None,
) -> SimulationResult:
    """Simulate the filament from ``t_start`` to ``t_end``.

    Times (``t_end``, ``frame_dt``, field schedules) are in seconds for physical
    :class:`Parameters` and in units of tau for :class:`Groups`. ``field`` is a
    :class:`Field` or a constant direction in radians (default: along e1, full strength).
    ``initial`` defaults to the paper's straight filament tilted by 0.01 degree from the field's
    direction at ``t_start``.
    Output: ``n_frames`` equally spaced frames (default 50 per time unit tau) or one
    every ``frame_dt``. ``forces=True`` adds the internal force components A, V and the
    bending moment M. ``check(t, y)`` may stop the run by returning a reason.
    """
    groups = params.groups if isinstance(params, Parameters) else params
    if not isinstance(groups, Groups):
        raise ParameterError(f"params={params!r} must be flutterswim.Parameters or flutterswim.Groups")
    tau = params.tau if isinstance(params, Parameters) else 1.0
    t_start = finite("t_start", t_start, strict=True)  # "1" or True is no time
    t_end = finite("t_end", t_end, strict=True)
    if not t_end > t_start:
        raise ParameterError(f"t_end={t_end!r} must be greater than t_start={t_start!r}")
    n_segments = segments_checked(n_segments)
    rtol, atol = tolerance("rtol", rtol, strict=True), tolerance("atol", atol, strict=True)
    tolerances_reachable(rtol, atol)
    frame_dt = None if frame_dt is None else positive("frame_dt", frame_dt, strict=True)
    max_step = None if max_step is None else positive("max_step", max_step, strict=True)
    if method not in METHODS:
        raise ParameterError(f"method={method!r} is unknown; choose one of {sorted(METHODS)}")
    if field is None:
        field = Field()
    elif not isinstance(field, Field):
        # a number is a direction in radians: Constant, so that it is checked (and warned about) once, here
        field = Field(direction=field if callable(field) else Constant(_angle("field", finite("field", field, strict=True))))
    # (from the field's direction at the start: across a field at 90 degrees the filament was
    # trapped in a bent equilibrium at once)
    initial = InitialState.straight(0.01 + math.degrees(field.direction(t_start))) if initial is None else initial
    if not isinstance(initial, InitialState):
        raise ParameterError(f"initial={initial!r} must be a flutterswim.InitialState")

    # --- dimensionless problem ------------------------------------------------
    t0, t1 = t_start / tau, t_end / tau
    if not (math.isfinite(t1 - t0) and math.isfinite(t1) and math.isfinite(t0)):
        # (1.7e308 s: infinite in units of tau, called "within round-off of t_start", and the CLI
        # crashed on an OverflowError)
        raise ParameterError(f"t_end={t_end!r} and t_start={t_start!r} span more than a float holds in units of "
                             f"tau={tau!r} s; give a finite span (and at most {defaults.MAX_FRAMES} saved frames)")
    if t1 - t0 <= 1e-12 * max(1.0, abs(t1)):  # (the steppers stop within this of the end: no step was taken)
        raise ParameterError(f"t_end={t_end!r} is within round-off of t_start={t_start!r}: the run must span more than "
                             f"1e-12 of max(1, |t_end|) in units of tau ({tau:.6g} s here)")
    fld = field.scaled(tau)
    fil = Filament(n_segments, groups.eta_par, groups.eta_perp, groups.chi)
    y0 = initial.state(n_segments)
    t_eval = _frames(t0, t1, n_frames, None if frame_dt is None else frame_dt / tau, tau)
    direction, strength = fld.direction, fld.strength

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        return fil.rhs(y, direction(t), strength(t))

    def jac(t: float, y: np.ndarray) -> np.ndarray:
        return fil.jacobian(y, direction(t), strength(t))

    n = n_segments
    if stop_on_self_intersection:
        from .analysis.intersection import polyline_self_intersects as self_intersects

    def _check(t: float, y: np.ndarray) -> str | None:
        if stop_on_self_intersection:
            x, yy = centreline(y[:2], y[2 : n + 2])
            if self_intersects(x, yy):
                return f"self-intersection at t={t * tau:.6g}"
        return check(t * tau, y) if check is not None else None

    bar, tick = _progress(progress, t0, t1)
    try:
        with single_blas_thread():  # the matrices are small: BLAS threads only add overhead
            cap = np.r_[1.0, 1.0, np.full(n, np.pi), np.full(n + 1, np.inf)]
            chk = _check if (stop_on_self_intersection or check is not None) else None
            mstep = np.inf if max_step is None else max_step / tau
            if isinstance(METHODS[method], (CompiledRosW, CompiledNDF)) and fld.steady_between_breakpoints:
                edges = [t0] + sorted(b for b in fld.breakpoints if t0 < b < t1) + [t1]
                pieces = [(a, direction(0.5 * (a + b)), strength(0.5 * (a + b))) for a, b in zip(edges[:-1], edges[1:])]
                sol = integrate_filament(fil, pieces, t1, y0, t_eval, method=method, rtol=rtol, atol=atol,
                                         max_step=mstep, check=chk, progress=tick, scale_cap=cap)
            else:  # a field changing between breakpoints: Python-stepped (ndf: scipy's BDF; ros34pw2/3: ROS34PW2)
                sol = integrate(
                    fun, jac, (t0, t1), y0, t_eval, method=method, rtol=rtol, atol=atol, max_step=mstep,
                    breakpoints=fld.breakpoints, time_dependent=not fld.steady_between_breakpoints,
                    check=chk, progress=tick, scale_cap=cap, jumps=fld.jumps,
                )
    finally:
        if bar is not None:
            bar.close()
    res = _package(sol, fil, fld, groups, params, tau, forces, {
        "n_segments": n_segments, "method": method, "rtol": rtol, "atol": atol,
        # what ran: a field turning between breakpoints is stepped in Python by another method (ndf:
        # scipy's bdf; the settings said "ndf" where the stats named the method that ran)
        "method_used": getattr(sol.stats, "method", method),
        "field": field.describe(), "initial": initial.describe(), "t_start": t_start,
        "t_end": t_end, "stop_on_self_intersection": stop_on_self_intersection,
    })
    if res.status == "failed":  # (the frames up to the failure are returned: say so, not only in .status)
        import warnings

        warnings.warn(f"the run failed: {res.message}; the result holds the frames up to t = {res.t_final:.6g} "
                      f"{'s' if isinstance(params, Parameters) else 'tau'} (result.status 'failed')", RunFailedWarning,
                      stacklevel=2)
    return res


def frame_count(t_span: float, n_frames: int | None = None, dt: float | None = None) -> float:
    """Frames a run over ``t_span`` (in tau) saves: ``n_frames``, one every ``dt`` (in tau), or
    :data:`defaults.FRAMES_PER_TAU` per tau (a float: it may be far beyond any array)."""
    if n_frames is not None:
        return float(n_frames)
    if not math.isfinite(t_span):  # (beyond a float in units of tau: more frames than any limit)
        return math.inf
    if dt is not None:
        return max(2.0, math.floor(t_span / dt + 1e-9) + 1.0)
    return math.ceil(defaults.FRAMES_PER_TAU * t_span) + 1.0


def _frames(t0: float, t1: float, n_frames: int | None, dt: float | None, tau: float = 1.0) -> np.ndarray:
    if n_frames is not None and dt is not None:
        raise ParameterError("give n_frames or frame_dt, not both")
    count = frame_count(t1 - t0, n_frames, dt)
    if count > defaults.MAX_FRAMES:  # before anything is allocated (t_end=1e7 s grew to 6.6 GB in 15 s)
        if n_frames is not None:
            raise ParameterError(f"n_frames={n_frames!r} is too many; at most {defaults.MAX_FRAMES} frames are saved")
        rate = 1.0 / (dt * tau) if dt is not None else defaults.FRAMES_PER_TAU / tau
        longest = (defaults.MAX_FRAMES - 1) / rate
        raise ParameterError(
            f"t_end={t1 * tau:.6g} implies {count:.3g} saved frames ({rate:.6g} per time unit from t_start="
            f"{t0 * tau:.6g}); at most {defaults.MAX_FRAMES} are saved: simulate at most {longest:.6g} time units "
            "at this frame rate (frame_dt sets a slower one), or continue from the end state in several runs")
    if dt is not None:
        t = np.arange(t0, t1 + 0.5 * dt, dt)[: int(np.floor((t1 - t0) / dt + 1e-9)) + 1]
        # a last frame at t_end by the count may lie past it by round-off (7.300000000000001 for
        # t_end = 7.3, frame_dt = 0.1): no step reaches it, and it was dropped
        t = np.minimum(t, t1)
        # a run shorter than one frame interval still saves its end (it saved only its start)
        return t if t.size >= 2 else np.array([t0, t1])
    if n_frames is None:
        n_frames = int(np.ceil(defaults.FRAMES_PER_TAU * (t1 - t0))) + 1
    n_frames = positive_int("n_frames", n_frames, minimum=2)
    return np.linspace(t0, t1, n_frames)


def single_blas_thread():
    """Context manager: BLAS limited to one thread for the duration (threadpoolctl). At
    N = 96 default BLAS threads made a run 120x slower on a busy machine."""
    return _blas_controller().limit(limits=1, user_api="blas")


@functools.lru_cache(maxsize=1)
def _blas_controller():
    """The threadpoolctl controller of the loaded BLAS libraries (numpy's and scipy's),
    made once: finding the libraries costs milliseconds, limiting them microseconds."""
    import scipy.linalg  # noqa: F401  (loads scipy's BLAS before the libraries are listed)
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


# progress in time (tau): its float count to one decimal (tqdm's default shows 41.88000000000001/160)
TAU_BAR = "{desc}: {percentage:3.0f}%|{bar}| {n:.1f}/{total:.1f} tau [{elapsed}<{remaining}]"


def _progress(enabled: bool, t0: float, t1: float):
    if not enabled:
        return None, None
    from tqdm.auto import tqdm

    bar = tqdm(total=round(t1 - t0, 3), unit="tau", desc="simulate", leave=False, bar_format=TAU_BAR)
    state = {"last": t0}

    def tick(t: float) -> None:
        if t - state["last"] > 0.01 * (t1 - t0):
            bar.update(round(t - state["last"], 3))
            state["last"] = t

    return bar, tick


def _message_in_seconds(message: str, tau: float) -> str:
    """The integrator's message with its times (in tau) in seconds, as the run's: a failed sweep
    point read 'the solver failed at t=19.2331: step size collapsed at t=51.2882', one moment
    twice in two units, neither named."""
    import re

    return re.sub(r"\bt=([-+0-9.eE]+)", lambda m: f"t={float(m.group(1)) * tau:.6g} s", message)


def _package(sol, fil: Filament, fld: Field, groups, params, tau, forces, settings) -> SimulationResult:
    n = fil.n
    y = sol.y
    r0, theta, kappa = y[:, :2], y[:, 2 : n + 2], y[:, n + 2 :]
    x, yy = centreline(r0, theta)
    t = sol.t
    angle = np.array([fld.direction(ti) for ti in t])
    strength = np.array([fld.strength(ti) for ti in t])
    a = v = m = None
    if forces and len(t):
        avm = np.array([fil.forces(yi) for yi in y])
        a, v, m = avm[:, 0], avm[:, 1], avm[:, 2]
    res = SimulationResult(
        t=t, s=fil.s_nodes, s_mid=fil.s_mid, x=x, y=yy, theta=theta, kappa=kappa, r0=r0,
        field_angle=angle, field_strength=strength, groups=groups,
        params=params if isinstance(params, Parameters) else None, stats=sol.stats,
        status=sol.status, message=sol.message, state_final=sol.y_final, t_final=sol.t_final,
        settings=settings, A=a, V=v, M=m, units="dimensionless",
    )
    if isinstance(params, Parameters):
        L, F = params.l, params.force_scale
        from dataclasses import replace

        res = replace(
            res, t=t * tau, s=res.s * L, s_mid=res.s_mid * L, x=x * L, y=yy * L, kappa=kappa / L,
            r0=r0 * L, t_final=sol.t_final * tau, units="SI",
            # (a stop's reason comes from the check, already in s: only the integrator's failures)
            message=_message_in_seconds(sol.message, tau) if sol.status == "failed" else sol.message,
            A=None if a is None else a * F, V=None if v is None else v * F,
            M=None if m is None else m * F * L,
        )
    return res
