"""The settle engine: from an initial state to what the filament settles into.

One engine for :func:`flutterswim.run_to_limit_cycle` and the sweep points: simulate in
chunks, watch the end segment's angle (extrema and upward crossings, found chunk by chunk,
so the cost is linear in the run's length), and as soon as the oscillation is steady refine
it with the periodic-orbit solver (:mod:`flutterswim.orbits`). The stroke's descriptors then
come from the orbit: exact to the solver's tolerance and smooth in the parameters.

Outcomes, each with its reason:
- ``straight``: the oscillation decays and the filament stays (nearly) straight;
- ``bent_equilibrium``: it stops in one of the bent equilibria theta_s = kappa = -chi sin(theta);
- ``limit_cycle``: a stable periodic orbit; ``reached`` says whether the run came within 1 % of
  it (period and end-angle peak-to-peak of every later cycle) before ``t_max``; if not (near
  the Hopf point the approach is slow), the orbit comes from continuation from the Hopf point;
- ``not_periodic``: an oscillation that is not a (stable) periodic orbit: its maxima wander;
- ``capped``: nothing decided by ``t_max`` (among them an oscillation on which Newton has not
  converged yet and whose maxima do not wander: it may still be on its way to a stroke);
- ``failed``: the solver failed (the reason says why).

Time to the limit cycle: the start of the first cycle from which every cycle's period and
end-angle peak-to-peak stay within 1 % of the orbit's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from . import defaults
from ._validate import positive, positive_int
from ._validate import n_segments as segments_checked
from .orbits._threads import one_blas_thread
from .params import Groups, Parameters

__all__ = ["Settled", "settle", "OUTCOMES", "SETTLE_TOLERANCE"]

#: an oscillation whose half-range changed by less than this (log) over its last 3 chunks is steady
STEADY_LOG_CHANGE = 0.02

OUTCOMES = ("straight", "bent_equilibrium", "limit_cycle", "not_periodic", "capped", "failed")
#: Relative closeness to the orbit (period and peak-to-peak) that counts as on the limit cycle.
SETTLE_TOLERANCE = 1e-2
#: End-angle half-range [rad] below which an oscillation counts as gone, and above which a
#: steady one is refined as a stroke.
DAMPED_AMPLITUDE = 1e-5
SWIM_AMPLITUDE = 1e-2
#: End-angle half-range [rad] below which a linearly stable oscillation that no longer decays
#: is at the integrator's noise (its tolerances), not a motion
NOISE_AMPLITUDE = 10 * DAMPED_AMPLITUDE
#: Largest deviation of the tangent angle from the field [rad] of a filament called straight.
STRAIGHT_ANGLE = 0.1


@dataclass(frozen=True)
class Settled:
    """What the filament settled into. Times in s and lengths in m for physical parameters
    (in tau and l for :class:`Groups`). ``run``: the simulated run; ``orbit``: the stroke as a
    :class:`flutterswim.orbits.PeriodicOrbit` or None."""

    outcome: str
    reason: str
    run: Any
    orbit: Any
    reached: bool
    time_to_limit_cycle: float
    growth_rate_linear: float
    angular_frequency_linear: float
    growth_rate_measured: float
    t_simulated: float
    units: str = "SI"
    extra: dict = field(default_factory=dict)

    def values(self) -> dict[str, float]:
        """Flat numeric record (flags 0/1, NaN where unknown), named by the sweep conventions:
        *_s times, *_mm lengths in mm (1e-3 l for groups), *_per_s rates."""
        si = self.units == "SI"
        mm = 1e3 if si else 1e3  # m -> mm, or l -> 1e-3 l
        length = self.orbit.params.l if (self.orbit is not None and si) else (self.extra.get("length", 1.0))
        out = {k: float(self.outcome == k) for k in OUTCOMES if k != "failed"}
        out.update(reached_limit_cycle=float(self.reached), t_simulated=self.t_simulated,
                   time_to_limit_cycle_s=self.time_to_limit_cycle,
                   growth_rate_linear_per_s=self.growth_rate_linear,
                   angular_frequency_linear_per_s=self.angular_frequency_linear,
                   growth_rate_measured_per_s=self.growth_rate_measured)
        keys = ("period_s", "frequency_hz", "advance_per_cycle_mm", "advance_per_cycle_bl", "speed_mm_s",
                "speed_bl_s", "lateral_leading_mm", "lateral_trailing_mm", "nonreciprocity",
                "self_intersecting", "stable", "max_multiplier", "swim_direction_deg")
        out.update({k: math.nan for k in keys})
        o = self.orbit
        if o is not None:
            from .orbits.dataset import _half_open_degrees

            out.update(period_s=o.period, frequency_hz=1.0 / o.period, advance_per_cycle_mm=o.advance * mm,
                       advance_per_cycle_bl=o.advance / length, speed_mm_s=o.speed * mm,
                       speed_bl_s=o.speed / length, lateral_leading_mm=o.lateral_leading * mm,
                       lateral_trailing_mm=o.lateral_trailing * mm, nonreciprocity=o.nonreciprocity,
                       self_intersecting=float(o.self_intersecting), stable=float(o.stable),
                       max_multiplier=o.max_multiplier,
                       # in (-180, 180] as the branch files (a sweep had read -180 and 180 for one direction)
                       swim_direction_deg=float(_half_open_degrees(np.asarray(o.swim_direction))))
        return out


class _Watch:
    """Extrema and upward crossings of the end angle q(t), chunk by chunk (linear time)."""

    def __init__(self, atol: float = defaults.ATOL) -> None:
        self.atol = atol  # the run's absolute tolerance: the envelope's floor is a few times it
        self.ext_t: list[float] = []
        self.ext_v: list[float] = []
        self.up_t: list[float] = []
        self.up_i: list[tuple[int, int, float]] = []  # (chunk, frame, fraction)
        self.amps: list[float] = []
        self.unstable = None  # the periodic orbit the last Newton shooting found, if unstable
        self._prev: tuple[np.ndarray, np.ndarray] | None = None  # last two frames (t, q) seen so far

    def add(self, k: int, t: np.ndarray, q: np.ndarray, skipped: int = 0) -> float:
        """Add chunk k (frames t, q, the chunk's own frames from its ``skipped``-th: those
        before repeat the previous chunk's last); return the half-range of q over its second
        half. ``up_i`` indexes the chunk's own frames.

        The last two frames seen are carried into the next chunk: an extremum on the last
        frame of a chunk needs the frame after it, and a crossing between chunks the frame
        before."""
        if self._prev is not None:
            off = self._prev[0].size
            t = np.r_[self._prev[0], t]
            q = np.r_[self._prev[1], q]
        else:
            off = 0
        if q.size >= 3:
            i = np.nonzero(((q[1:-1] - q[:-2]) * (q[2:] - q[1:-1]) < 0))[0] + 1
            for j in i:  # parabola through three frames: sub-frame extremum
                y0, y1, y2 = q[j - 1], q[j], q[j + 1]
                den = y0 - 2 * y1 + y2
                d = 0.5 * (y0 - y2) / den if den != 0 else 0.0
                self.ext_t.append(float(t[j] + d * (t[j + 1] - t[j])))
                self.ext_v.append(float(y1 - 0.25 * (y0 - y2) * d))
        half = q[q.size // 2:]
        mid = 0.5 * (half.max() + half.min())
        c = np.nonzero((q[:-1] < mid) & (q[1:] >= mid))[0]
        c = c[c >= off - 1]  # the pair of carried frames was looked at with the previous chunk
        for j in c:
            f = (mid - q[j]) / (q[j + 1] - q[j])
            self.up_t.append(float(t[j] + f * (t[j + 1] - t[j])))
            self.up_i.append((k, j - off + skipped, float(f)))
        self._prev = (t[-2:].copy(), q[-2:].copy())
        amp = float(0.5 * (half.max() - half.min()))
        self.amps.append(amp)
        return amp

    def cycles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per cycle between upward crossings: start time, period and peak-to-peak of q."""
        up = np.array(self.up_t)
        et, ev = np.array(self.ext_t), np.array(self.ext_v)
        starts, periods, p2p = [], [], []
        for a, b in zip(up[:-1], up[1:]):
            m = (et >= a) & (et < b)
            if np.count_nonzero(m) >= 2:
                starts.append(a)
                periods.append(b - a)
                p2p.append(ev[m].max() - ev[m].min())
        return np.array(starts), np.array(periods), np.array(p2p)

    def irregular(self, n_peaks: int = 10) -> str | None:
        """What makes the last ``n_peaks`` maxima of q irregular, or None (too few, or regular):
        :func:`flutterswim.orbits.periodic.irregular_maxima`."""
        from .orbits.periodic import irregular_maxima

        ev = np.array(self.ext_v)
        if ev.size < 2 * n_peaks + 1:
            return None
        i = np.nonzero((ev[1:-1] > ev[:-2]) & (ev[1:-1] >= ev[2:]))[0] + 1
        if i.size < n_peaks:
            return None
        # (a twentieth of the swing: the chunked run's maxima are refined to 1e-3 of it, and a
        # transient on its way to the stroke moves them one way, without turns)
        return irregular_maxima(ev[i[-n_peaks:]], float(np.ptp(ev[i[-n_peaks]:])), spread=0.05)

    def growth_rate(self) -> float:
        """Exponential rate of the envelope of q (half the differences of consecutive extrema).

        Growing: over the early, small-amplitude part (past the first two cycles, until the
        half-range first reaches 10 % of the largest: nothing of the saturated part, whatever
        its shape). Decaying: from two relaxation times after the first extremum (the start's
        faster modes gone) while the envelope stands above 30 times the run's absolute
        tolerance (below, the integrator's error sets it: at rtol 1e-4 the whole envelope gave
        -0.0145/tau where linear theory says -0.0589, kappa_E ratio 0.65), and only if the
        rates of its two halves agree within 10 % (a single exponential). NaN otherwise, or if
        too few extrema: then linear theory alone gives the rate. The integrator's own damping
        remains: at rtol 1e-4 the decay is 0.003-0.008/tau faster (ratio 0.6: -0.156 against
        -0.148; 0.65: -0.0644 against -0.0589); at rtol 1e-7 it is gone (-0.0591)."""
        et, ev = np.array(self.ext_t), np.array(self.ext_v)
        if ev.size < 6:
            return math.nan
        h = 0.5 * np.abs(np.diff(ev))
        th = 0.5 * (et[1:] + et[:-1])
        top = h.max()
        idx = np.arange(h.size)
        if h[-1] < 0.5 * top:  # decaying
            use = (h > 30 * self.atol) & (h > 1e-14) & (th > th[0] + 2.0)
            if np.count_nonzero(use) < 6:
                return math.nan
            t, y = th[use], np.log(h[use])
            m = t.size // 2
            rate = float(np.polyfit(t, y, 1)[0])
            halves = np.polyfit(t[:m], y[:m], 1)[0], np.polyfit(t[m:], y[m:], 1)[0]
            return rate if abs(halves[0] - halves[1]) <= 0.1 * abs(rate) else math.nan
        use = (idx < np.argmax(h >= 0.1 * top)) & (h > 1e-14) & (idx >= 4)
        if np.count_nonzero(use) < 3:
            return math.nan
        return float(np.polyfit(th[use], np.log(h[use]), 1)[0])


@one_blas_thread
def settle(params: Parameters | Groups, *, initial=None, n_cycles: int = defaults.N_CYCLES,
           t_max: float | None = None, chunk: float | None = None, n_segments: int = defaults.N_SEGMENTS,
           rtol: float = defaults.RTOL, atol: float = defaults.ATOL,
           frames_per_tau: int = defaults.FRAMES_PER_TAU, refine: bool = True, progress: bool = False,
           steps: int | None = None) -> Settled:
    """Simulate from ``initial`` (default: straight, tilted 0.01 degree) until the outcome is
    decided (see the module docstring). Times in s for :class:`Parameters`, tau for Groups;
    defaults: ``chunk`` 10 tau, ``t_max`` 200 tau."""
    from .initial import InitialState
    from .orbits.linear import leading_mode
    from .result import concatenate
    import warnings

    from .simulate import RunFailedWarning, simulate

    si = isinstance(params, Parameters)
    tau = params.tau if si else 1.0
    groups = params.groups if si else params
    n_cycles = positive_int("n_cycles", n_cycles)
    n_segments = segments_checked(n_segments)
    chunk = positive("chunk", 10.0 * tau if chunk is None else chunk)
    t_max = positive("t_max", 200.0 * tau if t_max is None else t_max)
    frames_per_tau = positive_int("frames_per_tau", frames_per_tau, minimum=4)
    state = InitialState.straight() if initial is None else initial
    lam = leading_mode(groups, n_segments)
    watch = _Watch(atol)
    parts = []
    t0 = 0.0
    orbit = None
    outcome, reason = None, ""
    after = 0
    t_lc = math.nan
    bar = _bar(progress, t_max / tau)
    k = 0
    next_len = chunk
    while outcome is None:
        t1 = min(t0 + next_len, t_max)
        with warnings.catch_warnings():  # (a failure is this run's outcome, with its reason)
            warnings.simplefilter("ignore", RunFailedWarning)
            part = simulate(params, t1, t_start=t0, initial=state, n_segments=n_segments, rtol=rtol, atol=atol,
                            frame_dt=tau / frames_per_tau)
        parts.append(part)
        if bar is not None:
            bar.update(round((t1 - t0) / tau, 3))
        if not part.ok:
            # (in tau for groups: a sweep's point run as groups had said "t=3.88 s" with a cap of 5 tau)
            outcome, reason = "failed", f"the solver failed at t={part.t_final:.6g} {'s' if si else 'tau'}: {part.message}"
            break
        sl = slice(1, None) if k else slice(None)
        amp = watch.add(k, part.t[sl] / tau, part.theta[sl, 0], skipped=sl.start or 0)
        k += 1
        state, t0 = part.final_state(), t1
        amps = watch.amps
        if len(amps) >= 2 and amps[-1] < DAMPED_AMPLITUDE and amps[-1] <= max(amps[-2], 1e-12):
            dev = float(np.max(np.abs(part.theta[-1] - part.field_angle[-1])))
            if dev > STRAIGHT_ANGLE:
                outcome = "bent_equilibrium"
                reason = (f"settled into a bent equilibrium (the tangent angle departs by up to "
                          f"{math.degrees(dev):.1f} degrees from the field; oscillation {amps[-1]:.2g} rad)")
            else:
                outcome = "straight"
                reason = f"the oscillation decayed to {amps[-1]:.2g} rad; the filament is straight"
            break
        if orbit is None and refine and amp > SWIM_AMPLITUDE and len(amps) >= 2 \
                and abs(math.log(amps[-1] / max(amps[-2], 1e-300))) < 0.05 and len(watch.up_t) >= 3:
            orbit = _refine(params, parts, watch, n_segments, steps)
        if orbit is not None:
            starts, periods, p2p = watch.cycles()
            T_ref = orbit.period / tau
            ref = _orbit_p2p(orbit)
            ok = (np.abs(periods / T_ref - 1) < SETTLE_TOLERANCE) & (np.abs(p2p / ref - 1) < SETTLE_TOLERANCE)
            bad = np.nonzero(~ok)[0]
            first = 0 if bad.size == 0 else int(bad[-1]) + 1
            after = len(ok) - first
            if after > 0:
                t_lc = float(starts[first]) * tau
            if after >= n_cycles:
                outcome = "limit_cycle"
                reason = (f"stable periodic orbit (max non-trivial multiplier {orbit.max_multiplier:.4f}); "
                          f"within {SETTLE_TOLERANCE:.0%} of it from t={t_lc:.4g} {'s' if si else 'tau'}")
                break
            next_len = max((n_cycles - after + 0.5) * T_ref * tau, 0.05 * tau)
        if t0 >= t_max * (1 - 1e-12):
            break
    if bar is not None:
        bar.close()
    if outcome is None:
        dev = float(np.max(np.abs(parts[-1].theta[-1] - parts[-1].field_angle[-1])))
        outcome, reason, orbit = _at_cap(params, groups, orbit, watch, lam, n_segments, steps, t_max / tau, dev)
    run = concatenate(parts) if parts else None
    reached = outcome == "limit_cycle" and after >= n_cycles
    if outcome == "limit_cycle" and not reached:
        t_lc = math.nan
    if outcome != "limit_cycle":
        orbit = None if outcome != "not_periodic" else orbit
    rate = watch.growth_rate()
    a = [x for x in watch.amps if x > 1e-14]
    if not math.isfinite(rate) and len(watch.ext_v) < 3 and len(a) >= 2 and len(parts) >= 2:
        # no oscillation to follow (an overdamped mode): the chunk-to-chunk change of the range
        dt = (parts[-1].t[-1] - parts[-2].t[-1]) / tau
        rate = math.log(a[-1] / a[-2]) / dt
    settled = Settled(outcome, reason, run, orbit if outcome == "limit_cycle" else None, reached, t_lc,
                      lam.real / tau, lam.imag / tau, rate / tau, t0 / tau,
                      units="SI" if si else "dimensionless",
                      extra={"length": params.l if si else 1.0})
    return settled


def _orbit_p2p(orbit) -> float:
    from .orbits.periodic import _p2p

    return _p2p(orbit.theta[:, 0])


def _refine(params, parts, watch: _Watch, n_segments: int, steps: int | None):
    """Newton shooting from the state at the last upward crossing; None if it fails or
    finds an unstable or trivial orbit."""
    from .orbits.periodic import DEFAULT_STEPS, OrbitNotFound, _checked_steps, _packaged, orbit_from_flow, solve_orbit
    from .orbits.system import ShapeSystem
    from .orbits.shooting import StepFailure

    watch.unstable = None
    k, j, f = watch.up_i[-1]
    part = parts[k]
    n = n_segments
    if j + 1 >= part.t.size or j < 0:
        k, j, f = watch.up_i[-2]
        part = parts[k]
    ua = np.concatenate((part.dimensionless().theta[j], part.dimensionless().kappa[j]))
    ub = np.concatenate((part.dimensionless().theta[j + 1], part.dimensionless().kappa[j + 1]))
    u0 = ua + f * (ub - ua)
    T0 = float(np.median(np.diff(watch.up_t[-3:])))
    sysm = ShapeSystem.of(params, n)
    check = steps is None
    steps = DEFAULT_STEPS if steps is None else steps
    try:
        u, T, fl, res, it = solve_orbit(sysm, u0, T0, steps=steps, max_newton=10)
    except (OrbitNotFound, StepFailure, np.linalg.LinAlgError):
        return None
    orb = (_packaged if check else orbit_from_flow)(params, sysm, fl, res, it, steps)
    if orb.amplitude < 1e-6:
        return None
    if not orb.stable:
        watch.unstable = orb  # (said at the cap: a motion near it will not settle on it)
        return None
    if not check:
        return orb
    # as periodic_orbit: the steps per period doubled until the period and advance hold
    try:
        return _checked_steps(params, sysm, orb, 1e-10, 10).compact()
    except (StepFailure, np.linalg.LinAlgError):
        return orb.compact()


def _at_cap(params, groups, orbit, watch: _Watch, lam: complex, n_segments: int, steps, t_cap_tau: float,
            dev: float):
    """Decide at the time cap."""
    amps = watch.amps
    # an oscillation below NOISE_AMPLITUDE no longer decays chunk to chunk (the integrator's
    # tolerances): 1.2e-5 rad at kappa_E_ratio 0.62, linearly stable, was left "capped"
    at_noise = len(amps) >= 2 and amps[-1] < NOISE_AMPLITUDE
    if lam.real < 0 and len(amps) >= 2 and (amps[-1] < amps[-2] or at_noise) and amps[-1] < SWIM_AMPLITUDE:
        rate = watch.growth_rate()
        what = ("bent_equilibrium", "towards a bent equilibrium") if dev > STRAIGHT_ANGLE else ("straight", "")
        how = "down to the integrator's noise" if at_noise and not amps[-1] < amps[-2] else "still decaying"
        measured = f"{rate:.3g}/tau" if math.isfinite(rate) else "not measured"  # (it read "nan/tau")
        return (what[0], f"{how} {what[1]} at t_max={t_cap_tau:g} tau (half-range {amps[-1]:.2g} rad, measured rate "
                f"{measured}, linear theory {lam.real:.3g}/tau): the straight state is stable".replace("  ", " "),
                None)
    if orbit is not None:
        return ("limit_cycle", f"stable periodic orbit found, but the run had not come within "
                f"{SETTLE_TOLERANCE:.0%} of it for enough cycles by t_max={t_cap_tau:g} tau", orbit)
    growing = len(amps) >= 2 and amps[-1] > amps[-2] * 1.001
    # linearly unstable, but growing by less than a factor e over the whole run: the decaying
    # modes of the start hide the growth (kappa_E_ratio 0.684, 2.5e-4/tau, was left "capped")
    slow = lam.real * t_cap_tau < 1.0
    if lam.real > 0 and (growing or slow):
        # slow onset near the Hopf point: the orbit by continuation from the Hopf point
        from .orbits.continuation import continue_orbits
        from .orbits.periodic import DEFAULT_STEPS

        try:
            br = continue_orbits(groups, "chi", groups.chi, n_points=6, n_segments=n_segments,
                                 steps=DEFAULT_STEPS if steps is None else steps,
                                 look_beyond=0.0)  # the stroke reached first from the straight state
            if not br.ends_at(groups.chi):  # (its last orbit is at another chi)
                return ("capped", f"still growing at t_max={t_cap_tau:g} tau and continuation from the Hopf "
                        f"point did not reach this point ({br.message})", None)
            orb = br.orbits[-1]
            if isinstance(params, Parameters):
                from .orbits.periodic import PeriodicOrbit  # noqa: F401

                orb = _to_physical(orb, params)
            if orb.stable:
                return ("limit_cycle", f"the onset is slow (growth rate {lam.real:.3g}/tau): the run had not "
                        f"reached the stroke by t_max={t_cap_tau:g} tau; the stable orbit comes from continuation "
                        "from the Hopf point", orb)
        except Exception as exc:  # noqa: BLE001 - the cap outcome below says what happened
            return ("capped", f"still growing at t_max={t_cap_tau:g} tau and continuation from the Hopf "
                    f"point failed ({exc})", None)
    irregular = watch.irregular()
    if amps and amps[-1] > SWIM_AMPLITUDE and irregular:
        return ("not_periodic", f"an oscillation (half-range {amps[-1]:.3g} rad) that is not a stable periodic "
                f"orbit: {irregular}", None)
    near = watch.unstable
    from .orbits.continuation import leading_multiplier, multiplier_kind

    kind = None if near is None else {"torus": "a complex pair: quasi-periodic motion about it",
                                      "period doubling": "real and negative: period doubling"}.get(multiplier_kind(near))
    steady = len(amps) >= 3 and abs(math.log(amps[-1] / max(amps[-3], 1e-300))) < STEADY_LOG_CHANGE
    if amps and amps[-1] > SWIM_AMPLITUDE and kind and steady \
            and abs(math.log(2 * amps[-1] / max(_orbit_p2p(near), 1e-300))) < math.log(1.5):
        # Newton found the periodic orbit this motion oscillates about, it lost its stability to
        # a torus or a period doubling, and the motion's size stays put (Groups(10, 20, 100) at
        # N = 48, |mu| = 1.013, quasi-periodic for 800 tau, had been "capped ... a longer t_max
        # may reach the stroke"). A saddle (a real multiplier above 1: the small orbit of a
        # subcritical Hopf point) is passed on the way to a stroke or to rest: still "capped".
        return ("not_periodic", f"an oscillation (half-range {amps[-1]:.3g} rad, steady) about a periodic orbit that "
                f"is unstable (largest multiplier |mu| = {abs(leading_multiplier(near)):.4f}, {kind}): no stable "
                "stroke here, and a longer t_max will not reach one", None)
    if amps and amps[-1] > SWIM_AMPLITUDE:
        # a motion that may still be on its way to a stroke (eta_perp = 30 < eta_par: reached at
        # 110 tau) is not called "not periodic" at the cap
        return ("capped", f"undecided at t_max={t_cap_tau:g} tau: an oscillation (half-range {amps[-1]:.3g} rad) "
                "on which Newton shooting has not converged yet, and whose maxima are not irregular; a longer "
                "t_max may reach the stroke", None)
    return ("capped", f"undecided at t_max={t_cap_tau:g} tau (oscillation half-range "
            f"{amps[-1] if amps else math.nan:.3g} rad)", None)


def _to_physical(orb, params: Parameters):
    """A dimensionless orbit in the units of ``params``."""
    tau, l = params.tau, params.l
    return replace(orb, params=params, period=orb.period * tau, advance=orb.advance * l,
                   speed=orb.speed * l / tau, lateral_leading=orb.lateral_leading * l,
                   lateral_trailing=orb.lateral_trailing * l, units="SI")


def _bar(enabled: bool, total: float):
    if not enabled:
        return None
    from tqdm.auto import tqdm

    from .simulate import TAU_BAR

    return tqdm(total=round(total, 3), unit="tau", desc="settle", leave=False, bar_format=TAU_BAR)
