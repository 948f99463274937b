"""One sweep point: simulate to a converged limit cycle (or a time cap), then describe it.

The point function takes a plain task dict and returns a plain dict of floats (flags as
0/1), so it pickles to any worker; it never writes anything. The returned values are in the
base's units: s and mm for physical parameters (also where an eta_par or eta_perp axis runs the
point as dimensionless groups: converted with the point's tau and l), tau and l for groups.
"""

from __future__ import annotations

import math
import time
from typing import Any, Mapping

import numpy as np

from .._interrupt import interrupted
from ..initial import InitialState
from ..params import Parameters
from ..settle import OUTCOMES, Settled, settle
from .spec import PointSettings, base_from_dict, point_params

__all__ = ["run_point", "VARIABLES", "DESCRIPTOR_VARIABLES", "FLAG_VARIABLES", "CORE_VARIABLES"]

#: What the point settled into (0/1), from the settle engine, and flags of the stroke.
FLAG_VARIABLES = tuple(k for k in OUTCOMES if k != "failed") + ("reached_limit_cycle", "self_intersecting",
                                                                 "stable")
#: Always finite for a successful point (else the point is recorded as failed).
CORE_VARIABLES = ("t_simulated", "growth_rate_linear_per_s", "angular_frequency_linear_per_s")
#: The stroke's descriptors (from its periodic orbit; NaN when there is no stroke).
DESCRIPTOR_VARIABLES = tuple(k for k in Settled("straight", "", None, None, False, math.nan, 0.0, 0.0, math.nan,
                                                0.0).values()
                             if k not in FLAG_VARIABLES + CORE_VARIABLES)
VARIABLES = FLAG_VARIABLES + CORE_VARIABLES + DESCRIPTOR_VARIABLES


class PointFailure(RuntimeError):
    """The simulation of a point failed (solver failure or non-finite state)."""


def run_point(task: Mapping[str, Any]) -> dict[str, Any]:
    """Run one point with the settle engine (:func:`flutterswim.settle.settle`, the same as
    :func:`flutterswim.run_to_limit_cycle`). ``task``: {"base": base dict, "values": swept
    values, "settings": PointSettings dict, "initial": None or a state vector to start from}.

    Returns {"values": {VARIABLES: float}, "final_state": array}."""
    st = PointSettings(**task["settings"])
    base = base_from_dict(task["base"])
    params = point_params(base, task["values"])

    tunit = params.tau if isinstance(params, Parameters) else 1.0
    init = task.get("initial")
    n = st.n_segments
    state = (InitialState.straight(st.initial_angle_deg) if init is None
             else InitialState.from_state(np.asarray(init, float), n))
    res = settle(params, initial=state, n_cycles=st.n_cycles, t_max=st.t_cap * tunit, chunk=st.chunk * tunit,
                 n_segments=n, rtol=st.rtol, atol=st.atol, frames_per_tau=st.frames_per_tau)
    if res.outcome == "failed":
        raise PointFailure(res.reason)
    if not np.all(np.isfinite(res.run.state_final)):
        raise PointFailure(f"non-finite state by t={res.run.t_final:.6g}")
    values = res.values()
    if isinstance(base, Parameters) and not isinstance(params, Parameters):
        # eta_par / eta_perp on a physical base: the point ran as dimensionless groups (times in
        # tau, lengths in l); the store's units are the base's (s, mm), with its tau and l
        from .spec import PHYSICAL

        phys = point_params(base, {k: v for k, v in task["values"].items() if k in PHYSICAL})
        values = in_physical_units(values, phys.tau, phys.l)
    return {"values": {k: float(values[k]) for k in VARIABLES}, "final_state": np.asarray(res.run.state_final, float),
            "reason": res.reason}


def in_physical_units(values: Mapping[str, float], tau: float, l: float) -> dict[str, float]:
    """A point's record from dimensionless groups (times in tau, lengths in 1e-3 l under the
    *_mm names) in the sweep's physical units, with the time scale ``tau`` [s] and length ``l``
    [m]: *_s times x tau, rates and frequencies / tau, *_mm x l (1e-3 l -> mm), speeds x l / tau;
    body-length ratios, angles, flags and ``t_simulated`` (always in tau) unchanged."""
    out = dict(values)
    for k, v in values.items():
        if k == "speed_mm_s":
            out[k] = v * l / tau
        elif k == "speed_bl_s" or k.endswith("_per_s") or k.endswith("_hz"):
            out[k] = v / tau
        elif k.endswith("_mm"):
            out[k] = v * l
        elif k.endswith("_s") and k != "t_simulated":
            out[k] = v * tau
    return out


def timed(fn, task):
    """Call ``fn(task)``; return (result or None, error message or "", wall time)."""
    t0 = time.perf_counter()
    try:
        r = fn(task)
        return r, "", time.perf_counter() - t0
    except BaseException as e:  # noqa: BLE001 - any failure of a point is recorded, never raised
        if isinstance(e, (KeyboardInterrupt, SystemExit)):
            raise
        if interrupted(e):  # Ctrl-C inside a compiled kernel surfaces as its SystemError
            raise KeyboardInterrupt from e
        msg = f"{type(e).__name__}: {e}".strip()
        return None, msg or type(e).__name__, time.perf_counter() - t0
