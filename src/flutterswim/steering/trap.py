"""Map of the trap: whether the filament swims or stops in a bent equilibrium, against the
initial tilt of the straight state, and against the size and rate of a field turn made once
the stroke is established."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..params import Parameters

__all__ = ["SWIMS", "TrapMap", "tilt_basin", "turn_basin", "plot_trap"]


#: outcomes of the settle engine that count as swimming
SWIMS = ("limit_cycle",)


@dataclass(frozen=True)
class TrapMap:
    """Outcomes of the settle engine (``limit_cycle``: swims; ``bent_equilibrium``: trapped;
    ``straight``, ``capped``, ...) against the initial tilt, and against the size and rate of a
    field turn started at ``turn_time_s`` (during the onset) and at ``late_turn_time_s`` (once
    the stroke is established; optional)."""

    tilts_deg: np.ndarray
    tilt_outcomes: np.ndarray  # (n_tilt,) str
    turn_angles_deg: np.ndarray
    turn_rates_deg_s: np.ndarray
    turn_outcomes: np.ndarray  # (n_angle, n_rate) str
    late_turn_outcomes: np.ndarray | None = None
    turn_time_s: float = math.nan
    late_turn_time_s: float = math.nan


def _outcome(params: Parameters, initial, n_segments: int) -> str:
    from ..settle import settle

    st = settle(params, initial=initial, n_segments=n_segments, frames_per_tau=25, n_cycles=3, refine=True,
                t_max=80 * params.tau)
    return st.outcome


def tilt_basin(params: Parameters, tilts_deg, *, n_segments: int = 24) -> np.ndarray:
    """The settle engine's outcome (str array) from the straight state at each initial tilt
    [deg] to the field: ``limit_cycle`` swims, ``bent_equilibrium`` is the trap."""
    from ..initial import InitialState

    return np.array([_outcome(params, InitialState.straight(float(a)), n_segments) for a in tilts_deg])


def turn_basin(params: Parameters, angles_deg, rates_deg_s, *, onset: float = 10.0, n_segments: int = 24) -> np.ndarray:
    """The outcome (str array (angles, rates)) after turning the field by each angle [deg] at
    each rate [deg/s], starting at ``onset`` s from the paper's 0.01 degree tilt (during the
    onset when ``onset`` is a few tau, from the established stroke when it is ~30 tau). Once
    the turn ends the field is steady: the state is rotated back by the turn (the model is
    invariant under rotating filament and field together) and settled from there."""
    from ..initial import InitialState
    from ..simulate import simulate
    from .schedules import _ramp

    n = n_segments
    state = simulate(params, onset, n_segments=n, frame_dt=0.02).final_state()
    out = np.empty((len(angles_deg), len(rates_deg_s)), dtype=object)
    for i, a in enumerate(angles_deg):
        for j, r in enumerate(rates_deg_s):
            dur = abs(a) / r
            run = simulate(params, onset + dur, t_start=onset, initial=state,
                           field=_ramp(math.radians(a), onset, dur, 0.0), n_segments=n, frame_dt=0.02)
            y = np.asarray(run.state_final, float)
            back = InitialState(theta=y[2:n + 2] - math.radians(a), kappa=y[n + 2:].copy())
            out[i, j] = _outcome(params, back, n)
    return out.astype(str)


def plot_trap(tm: TrapMap, path=None):
    from ..plotting._common import new_figure

    late = tm.late_turn_outcomes is not None
    fig = new_figure((13 if late else 9, 3.6), shown=path is None)
    axes = fig.subplots(1, 3 if late else 2)
    a1 = axes[0]
    a1.plot(tm.tilts_deg, np.isin(tm.tilt_outcomes, SWIMS).astype(int), "o-", color="k")
    a1.set_xlabel("initial tilt of the straight state [deg]")
    a1.set_yticks([0, 1], ["bent\nequilibrium", "swims"])
    a1.set_title("basin against the initial tilt", fontsize=9)
    panels = [(axes[1], tm.turn_outcomes, tm.turn_time_s)] + ([(axes[2], tm.late_turn_outcomes, tm.late_turn_time_s)]
                                                              if late else [])
    from matplotlib.colors import ListedColormap

    for a2, oc, t_turn in panels:
        z = np.isin(oc, SWIMS)
        code = np.where(z, 1.0, np.where(oc == "bent_equilibrium", 0.0, 0.5))
        a2.pcolormesh(tm.turn_rates_deg_s, tm.turn_angles_deg, code,
                      cmap=ListedColormap(["#b2182b", "0.75", "#1a9850"]), vmin=0, vmax=1, shading="nearest")
        if z.any() and (~z).any():
            a2.contour(tm.turn_rates_deg_s, tm.turn_angles_deg, z.astype(float), levels=[0.5], colors="k")
        a2.set_xscale("log")
        a2.set_yscale("log")
        a2.set_xlabel("field turn rate [deg/s]")
        a2.set_ylabel("field turn [deg]")
        a2.set_title(f"field turned from t = {t_turn:.3g} s\n(green: swims, red: bent equilibrium, grey: other; "
                     "line: boundary)", fontsize=8)
    if path is not None:

        from .._paths import save_figure_file

        save_figure_file(fig, path, dpi=150)
    return fig
