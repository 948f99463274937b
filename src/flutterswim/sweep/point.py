"""One sweep point: simulate to a converged limit cycle (or a time cap), then describe it.

The point function takes a plain task dict and returns a plain dict of floats (flags as
0/1), so it pickles to any worker; it never writes anything. Times in the returned values
are in s for physical parameters and in tau for dimensionless groups.
"""

from __future__ import annotations

import math
import time
from typing import Any, Mapping

import numpy as np

from ..analysis.cycles import detect_cycles
from ..analysis.descriptors import Descriptors, describe
from ..analysis.track import Track
from ..initial import InitialState
from ..params import Parameters
from ..simulate import simulate
from .spec import PointSettings, base_from_dict, point_params

__all__ = ["run_point", "VARIABLES", "DESCRIPTOR_VARIABLES", "FLAG_VARIABLES", "CORE_VARIABLES"]

#: Numeric and boolean fields of the analysis descriptors (strings such as leading_end are left out).
DESCRIPTOR_VARIABLES = tuple(
    name for name, f in Descriptors.__dataclass_fields__.items()
    if str(getattr(f.type, "__name__", f.type)) in ("float", "int", "bool")
)
#: Classification of the point (0/1), independent of the descriptors.
FLAG_VARIABLES = ("straight", "unstable", "swimming", "limit_cycle_reached", "saturated", "capped")
#: Always finite for a successful point (else the point is recorded as failed).
CORE_VARIABLES = ("t_simulated", "oscillation_amplitude", "amplitude_growth_rate", "n_chunks")
VARIABLES = FLAG_VARIABLES + CORE_VARIABLES + ("cycle_amplitude", "cycle_amplitude_std") + DESCRIPTOR_VARIABLES


class PointFailure(RuntimeError):
    """The simulation of a point failed (solver failure or non-finite state)."""


def _osc_amplitude(theta: np.ndarray) -> float:
    """Half-range in time of the body-frame shape angle, maximised along s [rad]."""
    sh = theta - theta.mean(axis=1, keepdims=True)
    return float(((sh.max(axis=0) - sh.min(axis=0)) / 2).max()) if sh.shape[0] else 0.0


def run_point(task: Mapping[str, Any]) -> dict[str, Any]:
    """Run one point. ``task``: {"base": base dict, "values": swept values, "settings":
    PointSettings dict, "initial": None or a state vector to start from}.

    Returns {"values": {VARIABLES: float}, "final_state": array}.
    """
    st = PointSettings(**task["settings"])
    params = point_params(base_from_dict(task["base"]), task["values"])
    tunit = params.tau if isinstance(params, Parameters) else 1.0
    length = params.l if isinstance(params, Parameters) else 1.0
    init = task.get("initial")
    n = st.n_segments
    state = (InitialState.straight(st.initial_angle_deg) if init is None
             else InitialState.from_state(np.asarray(init, float), n))
    ts, xs, ys = [], [], []
    amps: list[float] = []
    t = 0.0
    chunk = st.chunk * tunit
    t_cap = st.t_cap * tunit
    limit = capped = saturated = False
    straight = False
    cyc = None
    res = None
    while True:
        t1 = min(t + chunk, t_cap)
        res = simulate(params, t1, t_start=t, initial=state, n_segments=n, rtol=st.rtol, atol=st.atol,
                       frame_dt=tunit / st.frames_per_tau)
        if res.status == "failed":
            raise PointFailure(f"solver failed at t={res.t_final:.6g}: {res.message}")
        if not (np.all(np.isfinite(res.state_final)) and np.all(np.isfinite(res.x))):
            raise PointFailure(f"non-finite state by t={res.t_final:.6g}")
        sl = slice(1, None) if ts else slice(None)
        ts.append(res.t[sl])
        xs.append(res.x[sl])
        ys.append(res.y[sl])
        state = res.final_state()
        t = float(res.t_final)
        # oscillation amplitude over the second half of the chunk (past fast transients)
        th = res.theta[res.theta.shape[0] // 2 :]
        a = _osc_amplitude(th)
        amps.append(a)
        done = t >= t_cap * (1 - 1e-12)
        if a > st.swim_tol:
            tt = np.concatenate(ts)
            # analyse a window long enough for n_cycles + transient check
            per = float(np.median(cyc.periods[-5:])) if (cyc is not None and cyc.n_cycles) else None
            t0w = tt[0] if per is None else max(tt[0], t - (st.n_cycles + 6) * per)
            m = tt >= t0w
            tr = Track(t=tt[m], x=np.concatenate(xs)[m], y=np.concatenate(ys)[m], length=length, units="m",
                       meta={"params": params} if isinstance(params, Parameters) else {})
            try:
                cyc = detect_cycles(tr)
            except Exception:
                cyc = None
            if cyc is not None and cyc.limit_cycle:
                n_on = int(np.count_nonzero(cyc.starts[:-1] >= cyc.limit_cycle_time - 1e-12))
                steady = len(amps) >= 2 and abs(math.log(amps[-1] / amps[-2])) / st.chunk < st.rate_tol
                if n_on >= st.n_cycles and steady:
                    limit = True
                    break
            # a stationary but not strictly periodic oscillation (e.g. self-intersecting strokes):
            # amplitude steady over the last chunks covering at least n_cycles cycles
            k_sat = st.saturated_chunks
            if (cyc is not None and len(amps) > k_sat and cyc.n_cycles >= st.n_cycles
                    and all(a_ > st.swim_tol for a_ in amps[-k_sat - 1:])
                    and all(abs(math.log(amps[-j] / amps[-j - 1])) / st.chunk < st.rate_tol
                            for j in range(1, k_sat + 1))
                    ):
                per_ = float(np.median(cyc.periods[-5:]))
                if k_sat * chunk >= st.n_cycles * per_:
                    saturated = True
                    break
        elif len(amps) >= 3 and a <= amps[-2] <= amps[-3] and a < st.damped_tol:
            straight = True
            break
        if done:
            capped = True
            break
    tt = np.concatenate(ts)
    x, y = np.concatenate(xs), np.concatenate(ys)
    # growth rate of the oscillation amplitude [1/tau] over the last two chunks
    if len(amps) >= 3 and amps[-1] > 0 and amps[-2] > 0:
        rate = math.log(amps[-1] / amps[-2]) / st.chunk
    elif amps and amps[-1] == 0.0:
        rate = -math.inf
    else:
        rate = 0.0
    rate = max(rate, -1e3)
    a_last = amps[-1]
    growing, decaying = rate > st.rate_tol, rate < -st.rate_tol
    unstable = (not straight) and (limit or growing or (not decaying and a_last > st.swim_tol))
    if not straight:
        straight = (not unstable) and a_last < st.straight_tol
    out: dict[str, float] = {k: math.nan for k in VARIABLES}
    out.update(straight=float(straight), unstable=float(unstable), limit_cycle_reached=float(limit),
               capped=float(capped), saturated=float(saturated), t_simulated=t / tunit, oscillation_amplitude=a_last,
               amplitude_growth_rate=rate, n_chunks=float(len(amps)))
    swimming = False
    if a_last > st.swim_tol:
        T_win = None
        if cyc is not None and cyc.n_cycles:
            T_win = max(tt[0], tt[-1] - (st.n_cycles + 4) * float(np.median(cyc.periods[-5:])))
        m = tt >= (tt[0] if T_win is None else T_win)
        tr = Track(t=tt[m], x=x[m], y=y[m], length=length, units="m",
                   meta={"params": params} if isinstance(params, Parameters) else {})
        try:
            c = detect_cycles(tr)
            d = describe(tr, n_last=st.n_cycles, cycles=c)
            for k, v in d.to_dict().items():
                if k in out and (v is None or isinstance(v, (int, float))):
                    out[k] = math.nan if v is None else float(v)
            idx = c.last(st.n_cycles)
            amp = c.amplitudes[idx] / length
            out["cycle_amplitude"] = float(np.mean(amp))
            out["cycle_amplitude_std"] = float(np.std(amp, ddof=1)) if amp.size > 1 else 0.0
            swimming = d.n_cycles_used >= 1 and not decaying
        except Exception:
            swimming = False
    out["swimming"] = float(swimming)
    return {"values": out, "final_state": np.asarray(res.state_final, float)}


def timed(fn, task):
    """Call ``fn(task)``; return (result or None, error message or "", wall time)."""
    t0 = time.perf_counter()
    try:
        r = fn(task)
        return r, "", time.perf_counter() - t0
    except BaseException as e:  # noqa: BLE001 - any failure of a point is recorded, never raised
        if isinstance(e, (KeyboardInterrupt, SystemExit)):
            raise
        msg = f"{type(e).__name__}: {e}".strip()
        return None, msg or type(e).__name__, time.perf_counter() - t0
