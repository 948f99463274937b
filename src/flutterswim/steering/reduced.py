"""The reduced model of steering, identified from simulations of the full model.

A unicycle: the cycle-averaged swimmer moves at speed U along its heading psi, which relaxes
towards the field direction phi at rate k: dpsi/dt = -k sin(psi - phi). In a field turning at
rate Omega the heading lags by delta with sin(delta) = Omega / k and the path is a circle of
radius U / Omega. Above a step-out rate Omega_max the swimmer cannot follow: in this model the
stroke is lost (the filament stops in a bent equilibrium turning with the field) well before
the unicycle limit Omega = k, so Omega_max is found from the full model, by bisection on the
rotation rate. The smallest turning radius is U / Omega_max.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import positive
from ..params import Parameters
from .schedules import rotation
from .turning import cycle_average, describe_turning

__all__ = ["ReducedModel", "identify", "established_time", "rotating_run", "follows"]


@dataclass(frozen=True)
class ReducedModel:
    """U [m/s], stroke period [s], heading relaxation rate k [1/s], step-out rate Omega_max
    [rad/s] (bracketed to ``omega_max_bracket``), smallest turning radius U/Omega_max [m]."""

    U: float
    period: float
    k: float
    omega_max: float
    omega_max_bracket: tuple[float, float]
    r_min: float
    onset_time: float

    def radius(self, omega: float) -> float:
        return self.U / abs(omega)

    def lag(self, omega: float) -> float:
        return math.asin(min(1.0, abs(omega) / self.k))


#: turns of the field a rotation rate must be followed for. Near Omega_max the stroke is lost
#: late (1.3 kappa_E: after 1.08 turns at 0.531 rad/s, none in 2 turns at 0.514): runs of 0.6
#: turns, judged on their mean speed, put Omega_max at 0.571 rad/s; 1.5 turns judged on the
#: least speed at 0.529, 3 turns at 0.524 (the paper's point: 0.2606 rad/s in each)
FOLLOW_TURNS = 3.0


def rotating_run(params: Parameters, omega: float, *, turns: float = FOLLOW_TURNS, onset: float = 12.0,
                 n_segments: int = 24, period: float | None = None):
    """Simulate the onset until ``onset`` [s] (12 s: the paper's stroke is established), then a
    field turning at ``omega`` [rad/s] for ``turns``."""
    from ..simulate import simulate

    t_end = onset + turns * 2 * math.pi / abs(omega) + 4 * (period or 0.4)
    return simulate(params, t_end, field=rotation(2 * math.pi / omega, onset), n_segments=n_segments, frame_dt=0.02)


def follows(run, omega: float, U: float, period: float, onset: float) -> tuple[bool, object]:
    """Whether the swimmer follows the turning field: the heading turns with the field (rate
    within 5 %) and the cycle-averaged speed stays above half the straight-line speed
    throughout (not only on average: a stroke lost part-way through the window averaged
    above it)."""
    cx, cy = run.x.mean(axis=1), run.y.mean(axis=1)
    avg = cycle_average(run.t, cx, cy, run.field_angle, period)
    t0, t1 = onset + 4 * period, run.t[-1] - period
    d = describe_turning(avg, t0, t1)
    w = (avg.t >= t0) & (avg.t <= t1)
    return bool(d.following and d.speed_turning > 0.5 * U and np.min(avg.speed[w]) > 0.5 * U), d


#: halvings of the slow rotation rate tried where the swimmer does not follow it
SLOW_HALVINGS = 4

#: periods after the settle engine's limit-cycle time at which the stroke counts as established
ESTABLISHED_PERIODS = 2.0


def established_time(params: Parameters, *, n_segments: int = 24) -> float:
    """The time [s] from which the stroke, started from the straight state along the field (the
    start of :func:`flutterswim.simulate`), is established: the settle engine's limit-cycle
    time (every later cycle within 1 % of the periodic orbit) and ``ESTABLISHED_PERIODS``
    periods. The paper's point: 6.7 s + 0.76 s; it grows towards the onset (0.75 kappa_E:
    28.5 s), where a field turned at a fixed time trapped the filament mid-onset."""
    from ..settle import settle

    st = settle(params, n_cycles=3, n_segments=n_segments)
    if not st.reached:
        raise RuntimeError(f"no established stroke to steer: the run from the straight state ended as "
                           f"{st.outcome} ({st.reason})")
    return float(st.time_to_limit_cycle + ESTABLISHED_PERIODS * st.orbit.period)


def identify(params: Parameters, *, n_segments: int = 24, onset: float | None = None, rel_tol: float = 0.02,
             orbit=None) -> ReducedModel:
    """U and the period from the periodic orbit (``orbit``: one already found for these
    ``params`` and ``n_segments``); k from the heading lag at a slow rotation; Omega_max by
    bisection on the rotation rate to ``rel_tol``. The field starts turning at ``onset`` [s],
    by default once the stroke is established (:func:`established_time`); the model records it
    as ``onset_time``, where :func:`~flutterswim.steering.steer.steer` starts control.

    Raises RuntimeError if the swimmer does not follow even the slow rotation (no step-out
    rate to bracket). Where the heading leads the field instead of lagging (strong fields),
    the unicycle's relaxation rate is undefined: k is NaN, with a warning."""
    import warnings

    from ..orbits import periodic_orbit

    orb = periodic_orbit(params, n_segments=n_segments) if orbit is None else orbit
    U, T = orb.speed, orb.period
    along = math.cos(orb.swim_direction - getattr(orb, "phi", 0.0))
    if along < 0:  # (2.5 kappa_E: its heading read as leading the field by 178 degrees)
        off = math.degrees(math.remainder(orb.swim_direction - getattr(orb, "phi", 0.0), 2 * math.pi))
        raise RuntimeError(f"the stroke swims against the field (at {off:.1f} degrees "
                           "to it): the steering model is of a swimmer along the field, which turning the field "
                           "steers; this one it would steer the wrong way")
    onset = established_time(params, n_segments=n_segments) if onset is None else positive("onset", onset)
    slow = 0.05 / T  # rad/s: about a hundredth of a turn per stroke
    hi = None
    for _ in range(SLOW_HALVINGS + 1):
        ok, d = follows(rotating_run(params, slow, turns=0.3, onset=onset, n_segments=n_segments, period=T),
                        slow, U, T, onset)
        if ok:
            break
        # near the onset even this rate can be above step-out (0.75 kappa_E: Omega_max ~ 0.09 rad/s)
        hi, slow = slow, slow / 2.0
    else:
        raise RuntimeError(f"the swimmer does not follow a field turning at {2 * slow:.3g} rad/s or faster from "
                           f"t = {onset:.3g} s (speed while turning {d.speed_turning / U:.2f} U): no step-out rate "
                           "to identify")
    # lag = heading - field: a heading that lags a field turning at slow > 0 has lag < 0
    if d.heading_lag < 0:
        k = slow / math.sin(-d.heading_lag)
    else:
        k = math.nan
        warnings.warn(f"the heading leads the turning field by {math.degrees(d.heading_lag):.2f} degrees at "
                      f"{slow:.3g} rad/s: the unicycle's relaxation rate k is undefined (NaN); U, the step-out "
                      "rate and the smallest radius stand", stacklevel=2)
    lo = w = slow
    while hi is None:  # grow until the swimmer fails to follow
        w *= 2.0
        if not follows(rotating_run(params, w, onset=onset, n_segments=n_segments, period=T), w, U, T, onset)[0]:
            hi = w
        else:
            lo = w
        if w > 100 / T:
            hi = w
    while hi / lo - 1 > rel_tol:
        mid = math.sqrt(lo * hi)
        if follows(rotating_run(params, mid, onset=onset, n_segments=n_segments, period=T), mid, U, T, onset)[0]:
            lo = mid
        else:
            hi = mid
    om = math.sqrt(lo * hi)
    return ReducedModel(U, T, k, om, (lo, hi), U / om, onset)


def plot_radius(model: ReducedModel, omegas, radii, path=None, *, lost=()):
    """Turning radius against the rotation rate: measured points (circle fits of the full
    model), U / Omega, the step-out rate; ``lost``: rates at which the swimmer did not follow."""
    from ..plotting._common import new_figure
    from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter

    fig = new_figure((5, 3.6), shown=path is None)
    ax = fig.subplots()
    w = np.geomspace(min(omegas) * 0.8, model.omega_max * 1.3, 100)
    ax.loglog(w, model.U / w * 1e3, "-", color="0.4", label=r"$U/\Omega$ (U from the periodic orbit)")
    ax.loglog(omegas, np.asarray(radii) * 1e3, "o", color="tab:red", label="full model (circle fit)")
    ax.axvspan(model.omega_max, w[-1], color="tab:blue", alpha=0.12, lw=0)
    ax.axvline(model.omega_max, color="tab:blue", ls="--", lw=1,
               label=rf"step-out $\Omega_{{max}}$ = {model.omega_max:.3f} rad/s")
    for k, om in enumerate(lost):
        ax.plot([om], [model.U / om * 1e3], "x", color="tab:blue", ms=8, label="does not follow" if k == 0 else None)
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FormatStrFormatter("%g"))
        axis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(r"field rotation rate $\Omega$ [rad/s]")
    ax.set_ylabel("turning radius [mm]")
    ax.legend(fontsize=7)
    if path is not None:

        from .._paths import save_figure_file

        save_figure_file(fig, path, dpi=150)
    return fig
