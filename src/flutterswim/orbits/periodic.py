"""``periodic_orbit``: the stroke as a periodic orbit of the shape dynamics.

Unknowns (u0, T): a shape on the orbit and the period. Equations: the discrete flow map
closes, Phi(u0, T) = u0 (2N+1 rows; :mod:`.shooting`), and a phase condition fixes where on
the orbit u0 sits: the Poincare plane through the guess u_ref, normal to the flow there,
f(u_ref) . (u0 - u_ref) = 0. Newton's method with the monodromy S from the variational
equation: [[S - I, dPhi/dT], [f(u_ref)^T, 0]] (dPhi/dT = f(Phi)). The advance per cycle is
the quadrature of the velocity of r(0) along the orbit (the translation drops out of the
shape dynamics). Floquet multipliers: the eigenvalues of S; the trivial one (along the
flow) equals 1 and gauges the accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .._validate import ParameterError, finite, positive, positive_int
from .._validate import n_segments as segments_checked
from ..params import Groups, Parameters
from .shooting import Flow, StepFailure, flow
from ._threads import one_blas_thread
from .system import ShapeSystem

__all__ = ["PeriodicOrbit", "OrbitNotFound", "periodic_orbit", "solve_orbit", "DEFAULT_STEPS"]

#: Radau IIA steps per period (order 5): at the paper's parameters the period's time error is
#: about 4e-8 and the advance's 2e-6, relative (measured by halving, 32 -> 64 -> 128 steps);
#: elsewhere the advance's reached 6e-6 (Groups(150, 250, 60.14), N = 24; 1.8e-7 at 64 steps).
DEFAULT_STEPS = 32
#: A stroke found from scratch with the default steps is solved again with twice the steps,
#: doubling until the period and the advance per cycle change by less than these (relative;
#: the advance relative to max(|advance|, 1e-3 l)): half of what an orbit must meet against a
#: long simulation (1e-6 and 1e-5). 32 steps pass at the paper's point (2e-6 in the advance);
#: a strongly bent stroke (eta_perp / eta_par = 2.5, chi 3x its threshold) needs 64 (1.8e-5).
STEP_TOLERANCE = (5e-7, 5e-6)
MAX_STEPS = 512
#: Simulated onsets that seed a stroke, tried in turn until Newton finds a stable orbit:
#: (tilt of the straight start [degree], simulated time [tau], a fresh start (else going on
#: from the previous attempt's end)); each stops early once the end angle's swing is steady
SEED_TIME = 80.0
SEED_PLAN = ((0.01, SEED_TIME, True), (1.0, SEED_TIME, True), (1.0, 2 * SEED_TIME, False),
             (0.01, 4 * SEED_TIME, True))
DEFAULT_SEGMENTS = 48
#: Growth rate / frequency of the straight state below which a stroke is seeded from the Hopf
#: point (continuation) rather than from a simulation of the onset.
NEAR_ONSET = 0.02


class OrbitNotFound(RuntimeError):
    """Newton's method did not converge to a periodic orbit; the message says why."""


class _AtRest(OrbitNotFound):
    """The simulated onset came to rest (in a bent equilibrium): no stroke to seed from."""


#: |trivial Floquet multiplier - 1| above which an orbit's time discretisation is called out
#: (a warning from continue_orbits and from periodic_orbit with steps given; the branch
#: dataset's n_inaccurate_orbits): at 32 steps it stays below 1e-8 up to kappa_E ratio 2 but
#: reaches 6e-6..1.8e-4 on strongly bent strokes (ratio 1.95 upper branch, ratio 3; period
#: errors 1.6e-5..4.6e-5 against 128 steps)
ACCURACY_GAUGE = 1e-6
#: phases per stroke on which an orbit is tested for crossing itself (``self_intersecting``)
SELF_INTERSECTION_PHASES = 2048


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic stroke. Lengths and times in SI (m, s) for physical parameters, in l and
    tau for :class:`Groups` (``units``). Shapes are dimensionless on the phase grid ``phase``
    (M,) in [0, 1): theta (M, N), kappa (M, N+1)."""

    params: Parameters | Groups
    n_segments: int
    steps: int
    period: float
    advance: float
    speed: float
    swim_direction: float  # radians, of the advance per cycle
    lateral_leading: float
    lateral_trailing: float
    leading_end: str  # "s=0" or "s=l": the end that leads
    nonreciprocity: float
    self_intersecting: bool
    #: 2 |first Fourier coefficient of the shape u = (theta, kappa l)| / sqrt(2N + 1): the root
    #: mean square over the 2N + 1 shape components of the first harmonic's amplitude
    #: (dimensionless; independent of the resolution, as the sum over components is not)
    amplitude: float
    multipliers: np.ndarray
    trivial_multiplier_error: float
    stable: bool
    residual: float
    n_newton: int
    phase: np.ndarray = field(repr=False)
    theta: np.ndarray = field(repr=False)
    kappa: np.ndarray = field(repr=False)
    r0: np.ndarray = field(repr=False)  # (M, 2), dimensionless, r(0) = 0 at phase 0
    units: str = "SI"
    #: field direction (radians) the orbit was computed at; its swim_direction is in the same frame
    phi: float = 0.0
    #: relative change of the period or the advance (the larger) when the steps per period are
    #: doubled: the time discretisation's error, estimated (NaN where not checked: an orbit
    #: from a neighbour, or with ``steps`` given)
    step_error: float = math.nan
    #: the converged flow (stages, step matrices, monodromy, parameter sensitivity): a warm
    #: start for a neighbouring orbit (``periodic_orbit(params, guess=this)``). It holds the
    #: step matrices (about 2 MB at N = 24, 9 MB at N = 48): :meth:`compact` drops it, and
    #: it is not pickled or copied (``copy.copy``, ``copy.deepcopy``: orbits sent to workers
    #: stay small; ``dataclasses.replace`` keeps it).
    warm_start: Flow | None = field(default=None, repr=False, compare=False)

    def compact(self) -> "PeriodicOrbit":
        """This orbit without its warm start (for keeping many orbits in memory)."""
        return replace(self, warm_start=None) if self.warm_start is not None else self

    def __getstate__(self):
        state = dict(self.__dict__)
        state["warm_start"] = None
        return state

    def __setstate__(self, state):
        state = {"phi": 0.0, "step_error": math.nan, **state}  # (orbits pickled before these were recorded)
        for k, v in state.items():
            object.__setattr__(self, k, v)

    @property
    def u0(self) -> np.ndarray:
        """The shape at phase 0, (2N+1,), a seed for neighbouring orbits."""
        return np.concatenate((self.theta[0], self.kappa[0]))

    @property
    def period_dimensionless(self) -> float:
        return self.period / _scales(self.params)[0]

    @property
    def max_multiplier(self) -> float:
        """Largest modulus among the non-trivial Floquet multipliers."""
        mods = np.abs(self.multipliers)
        i = int(np.argmin(np.abs(self.multipliers - 1.0)))
        return float(np.max(np.delete(mods, i)))

    def descriptors(self) -> dict[str, float | bool | str]:
        """The stroke descriptors as a JSON-ready dict."""
        keys = ("period", "advance", "speed", "swim_direction", "lateral_leading", "lateral_trailing",
                "leading_end", "nonreciprocity", "self_intersecting", "amplitude", "stable",
                "trivial_multiplier_error", "step_error", "residual", "n_newton")
        out = {k: getattr(self, k) for k in keys}
        out["max_multiplier"] = self.max_multiplier
        return {k: (bool(v) if isinstance(v, (bool, np.bool_)) else v if isinstance(v, str) else
                    int(v) if isinstance(v, (int, np.integer)) else float(v)) for k, v in out.items()}

    def to_result(self, n_cycles: int = 1, frames_per_cycle: int | None = None):
        """The orbit as a :class:`flutterswim.SimulationResult` over ``n_cycles`` periods,
        positions rebuilt by the quadrature: for describe, plots, kymographs. Frames: one per
        solver step, or ``frames_per_cycle`` by trigonometric interpolation of the periodic
        shape and of r(0) less its mean drift (spectrally accurate for the smooth stroke)."""
        from ..field import Field
        from ..filament import Filament
        from ..integrators import SolverStats, Solution
        from ..simulate import _package

        n_cycles = positive_int("n_cycles", n_cycles)
        tau, length = _scales(self.params)
        g = self.params.groups if isinstance(self.params, Parameters) else self.params
        m = self.phase.size
        T = self.period_dimensionless
        d = (self.advance / length) * np.array([math.cos(self.swim_direction), math.sin(self.swim_direction)])
        theta, kappa = self.theta, self.kappa
        r0 = self.r0 - np.outer(self.phase, d)  # periodic part of r(0)
        if frames_per_cycle is not None:
            k = positive_int("frames_per_cycle", frames_per_cycle, minimum=4)
            theta, kappa, r0 = (_resample(a, k) for a in (theta, kappa, r0))
            m = k
        phase = np.arange(m) / m
        r0 = r0 + np.outer(phase, d)
        reps = [np.concatenate((r0 + c * d, theta, kappa), axis=1) for c in range(n_cycles)]
        last = np.concatenate((r0[:1] + n_cycles * d, theta[:1], kappa[:1]), axis=1)
        y = np.concatenate(reps + [last])
        t = np.arange(n_cycles * m + 1) * (T / m)
        stats = SolverStats("periodic_orbit", 5, self.steps, 0, 0, 0, 0, 0.0)
        sol = Solution(t, y, "completed", "periodic orbit", float(t[-1]), y[-1], stats)
        fil = Filament(self.n_segments, g.eta_par, g.eta_perp, g.chi)
        return _package(sol, fil, Field(direction=self.phi).scaled(tau), g, self.params, tau, False,
                        {"n_segments": self.n_segments, "source": "periodic_orbit",
                         "limit_cycle": True, "limit_cycle_time": 0.0})


def _resample(a: np.ndarray, k: int) -> np.ndarray:
    """Periodic samples (M, ...) along axis 0 to k samples, by zero-padding the spectrum."""
    m = a.shape[0]
    c = np.fft.rfft(a, axis=0)
    if m % 2 == 0:
        c[-1] *= 0.5  # split the Nyquist term between +-m/2
    return np.fft.irfft(c, k, axis=0) * (k / m)


def _scales(params) -> tuple[float, float]:
    if isinstance(params, Parameters):
        return params.tau, params.l
    return 1.0, 1.0


def _check_params(params) -> None:
    if not isinstance(params, (Parameters, Groups)):
        raise ParameterError(f"params={params!r} must be flutterswim.Parameters or flutterswim.Groups")


@one_blas_thread
def solve_orbit(system: ShapeSystem, u0: np.ndarray, period: float, *, steps: int = DEFAULT_STEPS,
                tol: float = 1e-10, max_newton: int = 12, u_ref: np.ndarray | None = None,
                warm: Flow | None = None, exact_multipliers: bool = True,
                sensitivity: bool = False, floor: float | None = None
                ) -> tuple[np.ndarray, float, Flow, float, int]:
    """Newton shooting from the guess (u0, period). Returns (u0, T, flow, residual, steps).

    Each Newton step integrates the variational equation with the step matrices formed at
    the warm-started stages (exact to the size of the last correction, which is all Newton
    needs); once the orbit closes, a final pass from the converged stages gives the exact
    monodromy, so the Floquet multipliers are those of the orbit itself (that pass must close
    the orbit too: the residual returned is its own, below ``tol``). With
    ``exact_multipliers=False`` that pass is skipped: the orbit and its descriptors are the
    same, the multipliers are those of the last derivative formed (within 1e-3 of the final
    stages, or the warm start's: good enough to tell a stable orbit unless a multiplier is near 1).

    From a neighbouring orbit (``warm`` a converged flow with its monodromy and parameter
    sensitivity, and (u0, period) its start and period), the change of the groups gives a
    first-order predictor, and the neighbour's monodromy serves as a chord (no derivative
    passes until the last, which is exact): Newton only if the chord converges slowly.
    ``sensitivity``: the returned flow carries the parameter sensitivity too (a seed for
    the next neighbour). ``floor``: a residual below it counts as closed once Newton stops
    reducing it tenfold per step (the round-off floor of the stiff steps)."""
    u = np.array(u0, float)
    T = float(period)
    u_ref = u.copy() if u_ref is None else np.asarray(u_ref, float)
    normal = system.f(u_ref)
    normal /= np.linalg.norm(normal)
    m = u.size
    res = math.inf
    fl = warm
    mono, chord, exact_next = None, False, False
    predicted = _is_neighbour(warm, system, u, T, steps)
    if predicted:
        fil = system.filament
        dg = np.array([fil.eta_par, fil.eta_perp, fil.chi]) - np.array(warm.groups[:3])
        T = float(warm.t[-1])  # (the guess's period may have passed through seconds and back)
        closing = warm.y[-1, 2:] - u + warm.sensitivity @ dg  # first order in the change
        dx = np.linalg.solve(_bordered(warm.monodromy, warm.f[-1, 2:], normal), np.concatenate((-closing, [0.0])))
        lam = min(1.0, 0.2 * T / max(abs(dx[m]), 1e-300))
        u, T = u + lam * dx[:m], T + lam * dx[m]
        mono, chord = warm.monodromy, True
    verify = False  # this pass is the exact one at an iterate that already closed
    for it in range(1, max_newton + 2):
        if it > max_newton and not verify:
            break
        try:
            # stages solved to a fraction of the last residual (exactly once it is small), the
            # derivative from the reused step matrices unless the stages moved by > 1e-3; once
            # the residual is small and falling fast, the last monodromy is kept (chord steps)
            # and the pass expected to close the orbit is the exact one
            stage_tol = min(1e-6, max(1e-13, 1e-4 * res)) if math.isfinite(res) else 1e-6
            if exact_next or verify:  # from a neighbour, its matrices stay the warm start
                fl = flow(system, u, T, steps, variational=True, warm=fl, sensitivity=sensitivity,
                          keep_matrices=predicted)
            else:
                fl = flow(system, u, T, steps, variational=not chord, warm=fl, derivative_tol=1e-3,
                          stage_tol=stage_tol)
        except StepFailure as exc:  # the iterate left the region where the steps converge
            raise OrbitNotFound(f"Newton iteration {it}: {exc}") from None
        r = fl.y[-1, 2:] - u
        res_before, res = res, float(np.max(np.abs(r)))
        if fl.monodromy is not None:
            mono = fl.monodromy
        stalled = floor is not None and res < floor and math.isfinite(res_before) and res > 0.1 * res_before
        if res < tol or stalled:
            if exact_next or verify:
                return u, T, fl, res, it
            if not exact_multipliers:
                return u, T, replace(fl, monodromy=mono), res, it
            verify = True  # the exact pass at this iterate gives the multipliers, and must close too
            continue
        verify = False
        rate = res / res_before if math.isfinite(res_before) else math.inf
        if chord and math.isfinite(rate) and not exact_next and (
                rate > 0.3 or math.log(tol / res) / math.log(max(rate, 1e-300)) > max_newton - it - 1):
            chord = False  # the chord converges too slowly: Newton with fresh derivatives
        elif not chord:
            chord = res < 1e-6 and rate < 0.01
        exact_next = chord and exact_multipliers and not exact_next and res * rate < 0.3 * tol
        dx = np.linalg.solve(_bordered(mono, fl.f[-1, 2:], normal),
                             np.concatenate((-r, [-(normal @ (u - u_ref))])))
        # damp steps that would change the period by more than a fifth
        lam = min(1.0, 0.2 * T / max(abs(dx[m]), 1e-300))
        u = u + lam * dx[:m]
        T = T + lam * dx[m]
        if not (np.all(np.isfinite(u)) and T > 0):
            raise OrbitNotFound(f"Newton left the admissible region at iteration {it} (T={T:.4g})")
    raise OrbitNotFound(f"Newton shooting did not converge in {max_newton} iterations "
                        f"(residual {res:.3g}, tolerance {tol:.3g})")


def _bordered(mono: np.ndarray, f_end: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The shooting Jacobian [[S - I, dPhi/dT], [phase-condition normal, 0]]."""
    m = normal.size
    a = np.zeros((m + 1, m + 1))
    a[:m, :m] = mono - np.eye(m)
    a[:m, m] = f_end
    a[m, :m] = normal
    return a


def _is_neighbour(warm: Flow | None, system: ShapeSystem, u: np.ndarray, T: float, steps: int) -> bool:
    """Whether ``warm`` is a converged flow started at (u, T), in the same field direction,
    with what a predictor needs."""
    return (warm is not None and warm.monodromy is not None and warm.sensitivity is not None
            and warm.stages.shape[0] == steps and warm.monodromy.shape[0] == u.size
            and warm.groups[3] == system.phi
            and np.array_equal(warm.y[0, 2:], u) and math.isclose(warm.t[-1], T, rel_tol=1e-12))


def orbit_from_flow(params, system: ShapeSystem, fl: Flow, residual: float, n_newton: int,
                    steps: int) -> PeriodicOrbit:
    """Package a converged flow as a :class:`PeriodicOrbit` with its descriptors."""
    n = system.n
    y = fl.y[:-1]
    T = float(fl.t[-1])
    d = fl.y[-1, :2] - fl.y[0, :2]
    adv = float(np.hypot(*d))
    e = d / adv if adv > 0 else np.array([math.cos(system.phi), math.sin(system.phi)])
    ep = np.array([-e[1], e[0]])
    theta, kappa, r0 = y[:, 2 : n + 2], y[:, n + 2 :], y[:, :2]
    h = 1.0 / n
    tip = r0 + h * np.stack((np.cos(theta).sum(axis=1), np.sin(theta).sum(axis=1)), axis=1)
    lat0, lat1 = _p2p(r0 @ ep), _p2p(tip @ ep)
    s_l_leads = float(np.mean((tip - r0) @ e)) > 0
    leading, trailing = (lat1, lat0) if s_l_leads else (lat0, lat1)
    mult = np.linalg.eigvals(fl.monodromy)
    mult = mult[np.argsort(-np.abs(mult))]
    i1 = int(np.argmin(np.abs(mult - 1.0)))
    others = np.delete(np.abs(mult), i1)
    shape = np.concatenate((theta, kappa), axis=1)
    c1 = np.fft.fft(shape, axis=0)[1] / shape.shape[0]  # (2N + 1,)
    tau, length = _scales(params)
    orb = PeriodicOrbit(
        params=params, n_segments=n, steps=steps, period=T * tau, advance=adv * length,
        speed=adv / T * length / tau, swim_direction=float(math.atan2(e[1], e[0])),
        lateral_leading=leading * length, lateral_trailing=trailing * length,
        leading_end="s=l" if s_l_leads else "s=0", nonreciprocity=float("nan"),
        self_intersecting=False, amplitude=float(2 * np.linalg.norm(c1) / math.sqrt(c1.size)), multipliers=mult,
        trivial_multiplier_error=float(abs(mult[i1] - 1.0)),
        stable=bool(others.size == 0 or others.max() < 1.0), residual=residual, n_newton=n_newton,
        phase=np.arange(y.shape[0]) / y.shape[0], theta=theta, kappa=kappa, r0=r0,
        units="SI" if isinstance(params, Parameters) else "dimensionless", phi=float(system.phi),
    )
    return _with_shape_descriptors(orb)


def _with_shape_descriptors(orb: PeriodicOrbit) -> PeriodicOrbit:
    from ..analysis.descriptors import shape_modes, stroke_area
    from ..analysis.intersection import polyline_self_intersects
    from ..filament import centreline

    coef, *_ = shape_modes(orb.to_result(1))
    nr = stroke_area(coef[:-1, 0], coef[:-1, 1]) if coef.shape[1] >= 2 else 0.0
    # on a fine phase grid (trigonometric interpolation of the periodic shape): near its onset a
    # crossing lasts a few % of the stroke or less, between the solver's 32-64 phases (a review: at
    # kappa_E ratio 1.725, N = 48, 2.1 % of the stroke crossing, none of 32 phases did)
    k = max(orb.theta.shape[0], SELF_INTERSECTION_PHASES)
    theta = orb.theta if k == orb.theta.shape[0] else _resample(orb.theta, k)
    x, y = centreline(np.zeros((k, 2)), theta)
    crossing = bool(np.any(polyline_self_intersects(x, y)))
    return replace(orb, nonreciprocity=float(nr), self_intersecting=bool(crossing))


def _p2p(q: np.ndarray) -> float:
    """Peak-to-peak of a periodic signal sampled uniformly over one period: the extremes of
    its trigonometric interpolant, located on a grid 16 times finer and refined by Newton's
    method on the interpolant's derivative (to rounding: no dependence on the phase origin)."""
    m = q.size
    c = np.fft.rfft(q) / m
    if m % 2 == 0:
        c[-1] *= 0.5
    k = np.arange(c.size)
    w = np.where(k == 0, 1.0, 2.0) * c

    def deriv(phi, order):
        e = np.exp(2j * np.pi * np.outer(np.atleast_1d(phi), k))
        return np.real(e @ (w * (2j * np.pi * k) ** order))

    fine = np.fft.irfft(np.fft.rfft(q), 16 * m) * 16
    ext = []
    for i in (int(np.argmax(fine)), int(np.argmin(fine))):
        phi = i / (16 * m)
        for _ in range(6):
            d1, d2 = deriv(phi, 1)[0], deriv(phi, 2)[0]
            if d2 == 0:
                break
            step = d1 / d2
            phi -= step
            if abs(step) < 1e-15:
                break
        ext.append(deriv(phi, 0)[0])
    return float(ext[0] - ext[1])


@one_blas_thread
def periodic_orbit(params: Parameters | Groups, guess: "PeriodicOrbit | None" = None, *,
                   n_segments: int | None = None, steps: int | None = None, tol: float = 1e-10,
                   max_newton: int = 12, phi: float = 0.0) -> PeriodicOrbit:
    """The stroke at ``params`` as a periodic orbit of the shape dynamics.

    ``guess``: a neighbouring :class:`PeriodicOrbit` (same resolution), or None to seed from
    a simulation of the onset from the straight state (or, near the Hopf point where that
    onset is too slow, from the Hopf eigenvector by continuation). ``n_segments`` and
    ``steps`` default to the guess's, else to 48 segments (the paper's) and 32 Radau steps
    per period. ``phi``: the field direction (radians); a guess computed at another direction
    is turned to this one (the model is invariant under turning the filament with the field:
    theta + (phi - guess.phi), kappa unchanged). ``tol``: the closing residual max|Phi(u) - u|; where Newton stalls above it
    (round-off), ``tol`` (1 + max|u|) is enough (as in
    :func:`~flutterswim.orbits.continuation.continue_orbits`). Raises
    :class:`OrbitNotFound` if the straight state is stable (no stroke to find), the onset
    simulated from it is irregular (no stroke to seed from), or Newton fails."""
    _check_params(params)
    check_steps = guess is None and steps is None
    if isinstance(guess, PeriodicOrbit):
        n_segments = guess.n_segments if n_segments is None else n_segments
        steps = guess.steps if steps is None else steps
    n_segments = segments_checked(DEFAULT_SEGMENTS if n_segments is None else n_segments)
    steps = positive_int("steps", DEFAULT_STEPS if steps is None else steps, minimum=8, maximum=MAX_STEPS)
    tol = positive("tol", tol)
    max_newton = positive_int("max_newton", max_newton)
    phi = finite("phi", phi, strict=True)
    system = ShapeSystem.of(params, n_segments, phi)
    warm = None
    if guess is None:
        g = params.groups if isinstance(params, Parameters) else params
        lam = _leading_pair(g, n_segments)
        if 0 < lam.real < NEAR_ONSET * lam.imag:
            # near the Hopf point the onset is too slow to simulate: continue from the Hopf
            # eigenvector (normal-form amplitude) along chi to this point
            from .continuation import continue_orbits

            try:
                br = continue_orbits(g, "chi", g.chi, n_points=8, n_segments=n_segments, steps=steps, tol=tol,
                                     look_beyond=0.0)  # the stroke reached first
            except ParameterError as exc:
                # its inputs are checked above: this point is outside the branch it continues
                # (past the Hopf point on the side without strokes, or no Hopf point near it)
                raise OrbitNotFound(f"no stroke at chi={g.chi:.6g}, eta_perp={g.eta_perp:.6g}: the continuation "
                                    f"from the Hopf point does not reach it ({exc})") from None
            if not br.ends_at(g.chi):  # (its last orbit is at another chi)
                raise OrbitNotFound(f"no stroke found at chi={g.chi:.6g}, eta_perp={g.eta_perp:.6g}: the "
                                    f"continuation from the Hopf point did not reach it ({br.message})")
            u0, T = br.orbits[-1].u0, br.orbits[-1].period_dimensionless
            if not br.orbits[-1].stable:
                # the branch from the Hopf point is unstable here (it can be with l1 < 0, where
                # eta_perp < eta_par: a real multiplier above 1): the stroke a run settles into
                # is another, found from a simulation
                try:
                    orb = _from_simulation(params, system, steps, tol, max_newton)
                except OrbitNotFound:
                    orb = None
                if orb is not None and orb.stable:
                    return _checked_steps(params, system, orb, tol, max_newton) if check_steps else orb
        else:
            orb = _from_simulation(params, system, steps, tol, max_newton)
            return _checked_steps(params, system, orb, tol, max_newton) if check_steps else orb
    else:
        if not isinstance(guess, PeriodicOrbit):
            raise ParameterError(f"guess={guess!r} must be a PeriodicOrbit or None")
        if guess.n_segments != n_segments:
            raise ParameterError(f"guess has n_segments={guess.n_segments}; this orbit needs {n_segments}")
        u0, T = guess.u0, guess.period_dimensionless
        warm = guess.warm_start
        turn = phi - getattr(guess, "phi", 0.0)
        if turn != 0.0:
            # the guess's stroke turned with the field: exactly this orbit's (its flow, at the
            # other direction, is no warm start)
            u0 = u0.copy()
            u0[:n_segments] += turn
            warm = None
    # where Newton stalls, the closing residual relative to the state's scale is enough, as in
    # continuation (continuation._scaled: an absolute 1e-10 can be below the round-off floor of
    # strongly bent strokes; chi = 150 at N = 12 stalled at 4e-9)
    floor = _floor(tol, u0)
    try:
        u, T, fl, res, it = solve_orbit(system, u0, T, steps=steps, tol=tol, max_newton=max_newton, warm=warm,
                                        sensitivity=True, floor=floor)
    except OrbitNotFound:
        if warm is None:
            raise
        # the predictor and chord from the neighbour failed (near a fold, say): Newton from its shape
        u, T, fl, res, it = solve_orbit(system, u0, T, steps=steps, tol=tol, max_newton=max_newton,
                                        sensitivity=True, floor=floor)
    orb = _packaged(params, system, fl, res, it, steps)
    if check_steps:
        return _checked_steps(params, system, orb, tol, max_newton)
    if orb.trivial_multiplier_error > ACCURACY_GAUGE:
        import warnings

        warnings.warn(f"the orbit's trivial Floquet multiplier is off 1 by {orb.trivial_multiplier_error:.2g} "
                      f"(> {ACCURACY_GAUGE:g}): {steps} steps per period limit its accuracy; leave steps=None (and "
                      "guess=None) to have them chosen and checked, or give more", UserWarning, stacklevel=2)
    return orb


def _packaged(params, system: ShapeSystem, fl: Flow, res: float, it: int, steps: int) -> PeriodicOrbit:
    """The orbit with its converged flow kept as a warm start."""
    return replace(orbit_from_flow(params, system, fl, res, it, steps),
                   warm_start=replace(fl, matrices=fl.matrices.without_jacobians()))


def _floor(tol: float, u: np.ndarray) -> float:
    return tol * (1.0 + float(np.max(np.abs(u))))


def _from_simulation(params, system: ShapeSystem, steps: int, tol: float, max_newton: int) -> PeriodicOrbit:
    """Newton from a simulated onset, in up to SEED_PLAN's attempts. Where Newton fails, or
    closes on an unstable orbit (the run still in its transient), the simulation goes on from
    where it stopped for twice as long (past an unstable orbit without stopping at a steady
    stretch: it lingers near that orbit). The first onset starts from simulate's, settle's and
    the sweeps' 0.01 degree tilt, so that where two strokes coexist this is the one they reach
    (at N = 12 the onset from 1 degree reaches another, with its end turned back); then 1
    degree (a faster onset: where there is no stroke, the irregular motion is named sooner),
    continued; last 0.01 degree for 320 tau (a larger tilt can trap the onset in a bent
    equilibrium, or, where eta_perp < eta_par, in an oscillating hooked end that is no stroke).
    The last attempt's orbit is returned even if unstable (its ``stable`` says so)."""
    start, settle_check, last = None, True, None
    for tilt, t_len, fresh in SEED_PLAN:
        if fresh:
            start, settle_check = None, True
        elif start is None:
            continue  # (the attempt it continues came to rest)
        try:
            u0, T, start = seed_from_simulation(system, t_max=t_len, start=start, stop_settled=settle_check,
                                                tilt=tilt)
        except _AtRest as exc:
            start, last = None, exc
            continue
        try:
            u, T, fl, res, it = solve_orbit(system, u0, T, steps=steps, tol=tol, max_newton=max_newton,
                                            sensitivity=True, floor=_floor(tol, u0))
        except OrbitNotFound as exc:
            last, settle_check = exc, True
            continue
        orb = _packaged(params, system, fl, res, it, steps)
        if orb.stable:
            return orb
        last, settle_check = orb, False
    if isinstance(last, PeriodicOrbit):
        return last
    raise last


def _checked_steps(params, system: ShapeSystem, orb: PeriodicOrbit, tol: float, max_newton: int) -> PeriodicOrbit:
    """``orb`` solved again with twice its steps per period, doubling until the period and the
    advance agree to STEP_TOLERANCE; the coarsest that agrees is returned (a neighbour seeded
    from it keeps its steps), with ``step_error`` the change measured. Past MAX_STEPS, the
    finest is returned with a warning."""
    length = _scales(orb.params)[1]
    steps = orb.steps
    while True:
        screened = _step_screen(system, orb)
        if screen_passes(screened):
            return replace(orb, step_error=max(screened))
        try:
            u, T, fl, res, it = solve_orbit(system, orb.u0, orb.period_dimensionless, steps=2 * steps, tol=tol,
                                            max_newton=max_newton, sensitivity=True, floor=_floor(tol, orb.u0))
        except OrbitNotFound:
            return orb  # (not checked: step_error stays NaN)
        fine = _packaged(params, system, fl, res, it, 2 * steps)
        e_T = abs(fine.period / orb.period - 1.0)
        e_a = abs(fine.advance - orb.advance) / max(abs(fine.advance), 1e-3 * length)
        err = max(e_T, e_a)
        if e_T <= STEP_TOLERANCE[0] and e_a <= STEP_TOLERANCE[1]:
            return replace(orb, step_error=err)
        steps *= 2
        if 2 * steps > MAX_STEPS:
            import warnings

            warnings.warn(f"the stroke's period and advance still change by {err:.2g} (relative) between "
                          f"{steps // 2} and {steps} Radau steps per period (tolerance {STEP_TOLERANCE[1]:g}); "
                          f"the orbit with {steps} is returned", RuntimeWarning, stacklevel=3)
            return replace(fine, step_error=err)
        orb = fine


def _step_screen(system: ShapeSystem, orb: PeriodicOrbit) -> tuple[float, float] | None:
    """A cheap estimate of what doubling the steps changes (relative period, advance), or None
    without the orbit's monodromy: :func:`step_screen` on the orbit's kept flow."""
    warm = orb.warm_start
    if warm is None or warm.monodromy is None:
        return None
    return step_screen(system, orb.u0, orb.period_dimensionless, orb.steps, warm.monodromy,
                       orb.advance / _scales(orb.params)[1])


def step_screen(system: ShapeSystem, u0: np.ndarray, T: float, steps: int, monodromy: np.ndarray,
                advance: float, advance_floor: float = 1e-3) -> tuple[float, float] | None:
    """A cheap estimate of what doubling the steps changes (relative period, advance) for the
    orbit through ``u0`` of period ``T`` (tau) solved with ``steps``, its ``monodromy`` and its
    ``advance`` (in l), or None if the estimate fails: one flow with twice the steps from u0
    (no variational equation) and one Newton step with the monodromy. The period's change is
    the full solve's to 1e-3 of it. The advance's is the flow's change plus the shape
    correction's, 2 |(u0 - u_s).du| / |u0 - u_s|^2 (the advance goes as the amplitude squared,
    u_s the straight state): near the Hopf point, where the orbit attracts weakly (a multiplier
    near 1), the Newton step's shape correction is most of it, and the flow's change alone was
    1000 times short (a review: 1.7e-7 recorded where the full solve moved the advance 8.9e-5).
    A screen that passes only below half the tolerance (else the full solve decides). About a
    quarter of the full solve's time. The advance's change is relative to max(advance,
    ``advance_floor``) (in l)."""
    try:
        fine = flow(system, u0, T, 2 * steps)
    except StepFailure:
        return None
    normal = system.f(u0)
    normal /= np.linalg.norm(normal)
    try:
        dx = np.linalg.solve(_bordered(monodromy, fine.f[-1, 2:], normal),
                             np.concatenate((u0 - fine.y[-1, 2:], [0.0])))
    except np.linalg.LinAlgError:
        return None
    adv = float(np.hypot(*(fine.y[-1, :2] - fine.y[0, :2])))
    dev = u0 - system.straight()
    shape = 2.0 * abs(float(dev @ dx[:-1])) / max(float(dev @ dev), 1e-300)
    scale = max(adv, advance_floor)
    return abs(dx[-1]) / T, (abs(adv - advance) + shape * adv) / scale


def screen_passes(screened: tuple[float, float] | None, tolerance: tuple[float, float] = STEP_TOLERANCE) -> bool:
    """The screen's estimate is below half of ``tolerance`` (period, advance) in both."""
    return screened is not None and screened[0] <= 0.5 * tolerance[0] and screened[1] <= 0.5 * tolerance[1]


def _leading_pair(groups: Groups, n_segments: int) -> complex:
    """The straight state's leading complex eigenvalue, or OrbitNotFound if it has none (no
    oscillatory mode, e.g. at chi = 0: nothing to flutter; not a bad input)."""
    from .linear import leading_pair

    try:
        return leading_pair(groups, n_segments)
    except ParameterError as exc:
        raise OrbitNotFound(f"no stroke at chi={groups.chi:.6g}, eta_perp={groups.eta_perp:.6g}: {exc}") from None


def seed_from_simulation(system: ShapeSystem, *, t_max: float = SEED_TIME, start: np.ndarray | None = None,
                         stop_settled: bool = True, tilt: float = 1.0) -> tuple[np.ndarray, float, np.ndarray]:
    """A point near the stroke, its period and the simulation's final state, from a simulation
    of the onset (tau units) over ``t_max``: the last upward crossing of the trailing segment's
    angle through its mean. ``start``: the full state to go on from (a previous call's last),
    else the straight state tilted by ``tilt`` degrees; ``stop_settled``: stop once the end angle's
    oscillation is steady (else run the whole ``t_max``)."""
    from ..integrators import integrate

    fil = system.filament
    lam = _leading_pair(Groups(fil.eta_par, fil.eta_perp, fil.chi), fil.n)
    if lam.real <= 0:
        raise OrbitNotFound(f"the straight state is linearly stable here (leading eigenvalue "
                            f"{lam.real:.4g}{lam.imag:+.4g}i per tau): no stroke grows from it; "
                            "pass a neighbouring orbit as guess to look for one elsewhere")
    n = fil.n
    if start is None:
        y0 = np.zeros(fil.size)
        y0[2 : n + 2] = system.phi + math.radians(tilt)
    else:
        y0 = np.array(start, float)
        y0[:2] = 0.0  # (the position drops out)
    t_eval = np.arange(0.0, t_max, 0.02)
    sol = integrate(lambda t, y: system.rhs_full(y), lambda t, y: fil.jacobian(y, system.phi, 1.0),
                    (0.0, t_max), y0, t_eval, rtol=1e-6, atol=1e-8,
                    check=_settled_check(n, system.phi) if stop_settled else None)
    q = sol.y[:, 2] - system.phi
    tail = q[q.size // 2 :]
    if np.ptp(tail) < 1e-6 and sol.t[-1] >= t_max - 0.04:
        raise _AtRest(f"no periodic stroke from the onset at chi={fil.chi:.6g}, eta_perp={fil.eta_perp:.6g}: the "
                      f"filament comes to rest (the end angle's last half spans {np.ptp(tail):.2g} rad, at "
                      f"{math.degrees(tail[-1]):.3g} degrees from the field: a bent equilibrium)")
    mean = tail.mean()
    up = np.nonzero((q[:-1] - mean < 0) & (q[1:] - mean >= 0))[0]
    if up.size < 3:
        raise OrbitNotFound(f"no periodic stroke within {t_max:g} tau of the onset")
    if sol.t[-1] >= t_max - 0.04:  # not stopped by the settled check
        irregular = _irregular_peaks(q)
        if irregular:
            raise OrbitNotFound(f"no periodic stroke from the onset at chi={fil.chi:.6g}, eta_perp={fil.eta_perp:.6g}: "
                                f"after {t_max:g} tau {irregular} (the motion is irregular, not a stroke); pass a "
                                "neighbouring orbit as guess to look for an unstable one")
    i, j = up[-2], up[-1]
    frac = lambda k: (mean - q[k]) / (q[k + 1] - q[k])  # noqa: E731
    t_i, t_j = sol.t[i] + frac(i) * 0.02, sol.t[j] + frac(j) * 0.02
    u = sol.y[j, 2:] + frac(j) * (sol.y[j + 1, 2:] - sol.y[j, 2:])
    return u, float(t_j - t_i), sol.y[-1].copy()


def _irregular_peaks(q: np.ndarray, n_peaks: int = 10) -> str | None:
    """What makes the last ``n_peaks`` maxima of the end angle ``q`` irregular, or None
    (:func:`irregular_maxima`)."""
    i = np.nonzero((q[1:-1] > q[:-2]) & (q[1:-1] >= q[2:]))[0] + 1
    if i.size < n_peaks:
        return None
    return irregular_maxima(q[i[-n_peaks:]], float(np.ptp(q[i[-n_peaks]:])))


def irregular_maxima(pk: np.ndarray, swing: float, spread: float = 0.2) -> str | None:
    """What makes the maxima ``pk`` of an oscillation of range ``swing`` irregular, or None:
    they differ by more than ``spread`` times the swing, rise and fall in turn more than twice
    (an onset still growing or decaying towards its stroke moves them one way) and do not
    repeat every 1-4 maxima (a stroke with several maxima per period)."""
    n_peaks = pk.size
    if any(np.max(np.abs(pk[m:] - pk[:-m])) < 0.02 * swing for m in range(1, 5)):
        return None  # a stroke of m maxima per period (period doubled, say)
    turns = int(np.count_nonzero(np.diff(np.sign(np.diff(pk))) != 0))
    if swing > 0 and np.ptp(pk) > spread * swing and turns > 2:
        return (f"the end angle's last {n_peaks} maxima still range over {np.ptp(pk):.3g} rad of its "
                f"{swing:.3g} rad swing, rising and falling {turns} times")
    return None


def _settled_check(n: int, phi: float):
    """Stop once ten consecutive oscillations of the end angle have equal amplitude to 1%."""
    state = {"last": None, "peaks": [], "rising": False}

    def check(t, y):
        q = y[2] - phi
        last = state["last"]
        state["last"] = q
        if last is None:
            return None
        rising = q > last
        if state["rising"] and not rising:
            state["peaks"].append(abs(last))
        state["rising"] = rising
        pk = state["peaks"]
        if len(pk) >= 12 and max(pk[-10:]) < 1.01 * min(pk[-10:]) and pk[-1] > 1e-3:
            return "settled"
        return None

    return check
