"""Map of the trap: whether the filament swims or stops in a bent equilibrium, against the
initial tilt of the straight state, and against the size and rate of a field turn made once
the stroke is established."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..params import Parameters

__all__ = ["TrapMap", "tilt_basin", "turn_basin", "plot_trap"]


@dataclass(frozen=True)
class TrapMap:
    """Swims (True) or trapped against the initial tilt, and against the size and rate of a
    field turn started at ``turn_time_s`` (during the onset) and at ``late_turn_time_s`` (once
    the stroke is established; optional)."""

    tilts_deg: np.ndarray
    tilt_swims: np.ndarray  # (n_tilt,) bool
    turn_angles_deg: np.ndarray
    turn_rates_deg_s: np.ndarray
    turn_swims: np.ndarray  # (n_angle, n_rate) bool
    late_turn_swims: np.ndarray | None = None
    turn_time_s: float = math.nan
    late_turn_time_s: float = math.nan


def tilt_basin(params: Parameters, tilts_deg, *, n_segments: int = 24) -> np.ndarray:
    """Swims (a limit cycle) or not (a bent equilibrium or straight) from each initial tilt."""
    from ..initial import InitialState
    from ..settle import settle

    out = []
    for a in tilts_deg:
        st = settle(params, initial=InitialState.straight(float(a)), n_segments=n_segments, frames_per_tau=25,
                    n_cycles=3, refine=False, t_max=60 * params.tau)
        out.append(st.outcome != "bent_equilibrium" and _oscillates(st.run))
    return np.array(out, bool)


def _oscillates(run) -> bool:
    """The last two seconds still hold a stroke: the end angle oscillates by more than 0.1 rad."""
    m = run.t > run.t[-1] - 2.0
    q = run.theta[m, 0]
    return bool(q.max() - q.min() > 0.1)


def turn_basin(params: Parameters, angles_deg, rates_deg_s, *, onset: float = 10.0, n_segments: int = 24) -> np.ndarray:
    """Swims or not after turning the field by each angle at each rate, starting at ``onset``
    s from the paper's 0.01 degree tilt (field along e1 until then): during the onset when
    ``onset`` is a few tau, from the established stroke when it is ~30 tau."""
    from ..simulate import simulate
    from .schedules import ramp

    base = simulate(params, onset, n_segments=n_segments, frame_dt=0.02)
    state = base.final_state()
    out = np.zeros((len(angles_deg), len(rates_deg_s)), bool)
    for i, a in enumerate(angles_deg):
        for j, r in enumerate(rates_deg_s):
            dur = abs(a) / r
            run = simulate(params, onset + dur + 6.0, t_start=onset, initial=state,
                           field=ramp(math.radians(a), onset, dur), n_segments=n_segments, frame_dt=0.02)
            out[i, j] = _oscillates(run)
    return out


def plot_trap(tm: TrapMap, path=None):
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    late = tm.late_turn_swims is not None
    fig, axes = plt.subplots(1, 3 if late else 2, figsize=(13 if late else 9, 3.6), constrained_layout=True)
    a1 = axes[0]
    a1.plot(tm.tilts_deg, tm.tilt_swims.astype(int), "o-", color="k")
    a1.set_xlabel("initial tilt of the straight state [deg]")
    a1.set_yticks([0, 1], ["trapped /\nno stroke", "swims"])
    a1.set_title("basin against the initial tilt", fontsize=9)
    panels = [(axes[1], tm.turn_swims, tm.turn_time_s)] + ([(axes[2], tm.late_turn_swims, tm.late_turn_time_s)] if late else [])
    for a2, z, t_turn in panels:
        a2.pcolormesh(tm.turn_rates_deg_s, tm.turn_angles_deg, z.astype(float), cmap="RdYlGn", vmin=0, vmax=1,
                      shading="nearest")
        if z.any() and (~z).any():
            a2.contour(tm.turn_rates_deg_s, tm.turn_angles_deg, z.astype(float), levels=[0.5], colors="k")
        a2.set_xscale("log")
        a2.set_yscale("log")
        a2.set_xlabel("field turn rate [deg/s]")
        a2.set_ylabel("field turn [deg]")
        a2.set_title(f"field turned from t = {t_turn:.3g} s (green: swims, red: trapped; line: boundary)", fontsize=8)
    if path is not None:
        from pathlib import Path

        from .._paths import atomic_path, figure_metadata

        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=150, **figure_metadata(Path(path).suffix))
        plt.close(fig)
    return fig
