"""``continue_orbits``: the branch of strokes by pseudo-arclength continuation from the Hopf
point of the discrete model.

Unknowns X = (u0, T, p): a shape on the orbit, the period and the parameter. Equations:
Phi(u0, T; p) = u0 (the discrete flow closes), the Poincare phase condition through the
previous orbit, and the arclength condition <t, X - X_k>_w = ds with t the secant tangent in
the scaled metric |dX|_w^2 = (dp / L_p)^2 + (|du| / L_u)^2 (L_p: the parameter range asked
for, L_u: the shape amplitude the normal form predicts over it), so the branch is followed
through folds. The first orbit comes from the Hopf normal form (:mod:`.normal_form`).
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from .. import defaults
from .._validate import ParameterError, finite, positive, positive_int, within
from .._validate import n_segments as segments_checked
from .linear import hopf_bracket, hopf_point
from .normal_form import normal_form
from .parameter import Axis
from ..params import Parameters
from .periodic import ACCURACY_GAUGE, MAX_STEPS, OrbitNotFound, PeriodicOrbit, _scales, orbit_from_flow, screen_passes, step_screen
from .shooting import StepFailure, flow
from ._threads import one_blas_thread
from .system import ShapeSystem

__all__ = ["Branch", "continue_orbits"]

#: Radau steps per period a branch starts with (``steps=None``: doubled where the step screen
#: asks for it, as for an orbit from scratch). Against 48 steps at kappa_E ratio 1.5 (N = 24):
#: period 2.5e-7 and advance 7.7e-6 relative, far below the N = 24 space errors (1.7e-3,
#: 1.4e-2); the trivial multiplier within 1e-9 of 1 from the Hopf point to kappa_E ratio 2
#: (24 steps: period 1.2e-6, advance 3.6e-5, trivial multiplier 1.2e-7 off at ratio 2).
BRANCH_STEPS = 32
#: The step screen's tolerance along a branch (relative period, advance): 20 times looser than
#: an orbit's from scratch (periodic.STEP_TOLERANCE), about 3 % of the space error of the
#: paper's resolution (N = 48: period 3.8e-4, advance 3.6e-3), 1 % of the sweeps' N = 24 one.
#: At the orbit from scratch's tolerance a branch to kappa_E ratio 2 took 4.4 times as long
#: (35 s against 8 s, N = 24), most of its orbits at 64-256 steps.
BRANCH_STEP_TOLERANCE = (1e-5, 1e-4)
#: the NetCDF title of a branch, before " in <parameter>" (a branch replaces only these)
BRANCH_TITLE = "flutterswim periodic-orbit branch"
#: most orbits a branch is asked for (each keeps its shape on its phase grid, ~50 kB at N = 24)
MAX_POINTS = 20000
#: the fraction of a branch's range it is followed past its end for a fold back into the range:
#: along kappa_E_ratio (N = 24 and 48) the branch folds at 2.108 and back at 1.899, so the range
#: to 2 holds a second stable stroke that stopping at 2 missed
LOOK_BEYOND = 0.2
#: the farthest past ``to`` a branch may be followed, in ranges
MAX_LOOK_BEYOND = 10.0
#: Largest amplitude (along the unit Hopf eigenvector) of the branch's first orbit
START_AMPLITUDE_CAP = 6.0


@dataclass(frozen=True)
class Branch:
    """The orbits along the branch, with the Hopf point and normal form. ``amplitude2_slope``:
    d(amplitude^2)/d(parameter) at the Hopf point for the orbits' RMS ``amplitude``
    (:attr:`NormalForm.amplitude2_slope_rms`). ``steps``: the largest Radau steps per period
    of its orbits (each orbit's own: ``orbits[i].steps``)."""

    axis: Axis
    values: np.ndarray
    orbits: list[PeriodicOrbit] = field(repr=False)
    hopf_value: float
    hopf_omega: float
    lyapunov_coefficient: float
    amplitude2_slope: float
    n_segments: int
    steps: int
    wall_time: float
    message: str

    def to_dataset(self):
        """The branch as an xarray Dataset (CF attributes, units), along the dimension ``orbit``
        (0 at the Hopf point's side, in the order continued), the parameter an auxiliary
        coordinate: past a fold the parameter turns back, and a coordinate variable must be
        monotonic (CF) and unique (xarray's indexing)."""
        from .dataset import orbits_dataset

        name = self.axis.name
        si = isinstance(self.axis.base, Parameters)
        tu = "s" if si else "tau"
        tau_hopf = _scales(self.axis.at(self.hopf_value))[0]  # (1 for groups: periods in tau)
        ds = orbits_dataset(self.orbits, si=si, orbit_long_name="orbit number along the branch, from the Hopf point")
        ds = ds.assign_coords({name: (("orbit",), self.values, {"units": self.axis.units,
                                                                 "long_name": self.axis.long_name})})
        crossings = self.stability_changes()
        from .. import __version__
        from .._cf import cf_dataset

        ds.attrs.update({
            "Conventions": "CF-1.10",
            "title": f"{BRANCH_TITLE} in {name}",
            "source": f"flutterswim {__version__}: Newton shooting (Radau IIA, {_step_range(self.orbits)} steps per "
                      "period) and pseudo-arclength continuation",
            "parameter": name,
            f"hopf_{name}": self.hopf_value,
            f"hopf_{name}_units": self.axis.units,
            "hopf_omega_per_tau": self.hopf_omega,
            "hopf_omega_per_tau_units": "1/tau",
            "hopf_period": (2 * math.pi / self.hopf_omega) * tau_hopf,
            "hopf_period_units": tu,
            "lyapunov_coefficient": self.lyapunov_coefficient,
            "lyapunov_coefficient_units": "1/tau",
            "lyapunov_coefficient_comment": (
                "first Lyapunov coefficient l1 [1/tau] for the critical eigenvector q normalised to unit Euclidean "
                "norm over the 2N+1 shape components: its size scales like 1/N (N l1 converges); its sign decides "
                "the bifurcation"),
            "lyapunov_amplitude2_slope": self.amplitude2_slope,
            "lyapunov_amplitude2_slope_units": "1" if self.axis.units == "1" else f"1/({self.axis.units})",
            "lyapunov_amplitude2_slope_comment": (
                f"d(amplitude^2)/d({name}){'' if self.axis.units == '1' else f' [1/({self.axis.units})]'} at the "
                "Hopf point from the normal form, for "
                "the RMS amplitude (the amplitude variable's definition)"),
            "bifurcation": "supercritical" if self.lyapunov_coefficient < 0 else "subcritical",
            "multiplier_crossings": "; ".join(f"{name}={v:.6g} ({kind})" for v, kind in crossings) if crossings else "none",
            "multiplier_crossings_comment": (
                "where the largest non-trivial Floquet multiplier crosses the unit circle (interpolated) and how: fold "
                "(real, +1, the branch turns back), branch point (real, +1, another branch meets this one), period "
                "doubling (real, -1), torus (a complex pair)"),
            "n_segments": self.n_segments,
            "steps_per_period_max": self.steps,
            "steps_per_period_max_units": "1",
            "n_inaccurate_orbits": int(np.count_nonzero(ds["trivial_multiplier_error"].values > ACCURACY_GAUGE)),
            "n_inaccurate_orbits_comment": (
                f"orbits whose trivial Floquet multiplier is off 1 by more than {ACCURACY_GAUGE:g} (see "
                "trivial_multiplier_error): the time discretisation limits their accuracy; more steps per "
                "period (steps=) checks them"),
            "message": self.message,
        })
        return cf_dataset(ds)

    def ends_at(self, value: float) -> bool:
        """Whether the branch's last orbit is at ``value`` of its parameter (it reached its
        ``to``; a branch stopped short ends elsewhere, and its ``message`` says why)."""
        return abs(float(self.values[-1]) - value) <= 1e-12 * max(1.0, abs(value))

    def multiplier_crossings(self) -> list[float]:
        """Parameter values (linearly interpolated) where the largest non-trivial multiplier
        crosses the unit circle along the branch."""
        return [v for v, _ in self.stability_changes()]

    def stability_changes(self) -> list[tuple[float, str]]:
        """Where the largest non-trivial multiplier crosses the unit circle (parameter value,
        linearly interpolated) and how, from the multiplier outside the circle on the unstable
        side (:func:`crossing_kind`): "fold" (real, through +1, where the branch turns back in
        the parameter), "branch point" (real, through +1, the branch going on: another branch
        of strokes meets it there, as one that breaks a symmetry), "period doubling" (real,
        through -1) or "torus" (a complex pair: Neimark-Sacker, a second frequency)."""
        m = np.array([o.max_multiplier for o in self.orbits]) - 1.0
        v = np.asarray(self.values, float)
        out = []
        for i in range(len(m) - 1):
            if m[i] * m[i + 1] < 0:
                f = m[i] / (m[i] - m[i + 1])
                at = float(v[i] + f * (v[i + 1] - v[i]))
                out.append((at, crossing_kind(self.orbits[i if m[i] > 0 else i + 1], v, i)))
        return out

    def save(self, path) -> None:
        """Write the branch to NetCDF atomically (temporary name, then rename)."""
        from .._paths import check_output_file, write_netcdf

        path = check_output_file(path, (".nc",), kind=BRANCH_TITLE)
        write_netcdf(self.to_dataset(), path)


def _systems(axis: Axis, value: float, n: int) -> ShapeSystem:
    return ShapeSystem.of(axis.at(value), n)


def branch_side(nf) -> int:
    """+1 if the stable strokes lie above the Hopf point, -1 below: a supercritical branch's
    side (``nf.direction``); a subcritical branch leaves towards ``nf.direction`` as unstable
    orbits and folds back to the other side, where the continuation ends."""
    return nf.direction if nf.supercritical else -nf.direction


def unreachable(nf, hopf_value: float, to: float, parameter: str, mirror: bool = False) -> str:
    """Why the branch from the Hopf point cannot end at ``to`` ("" if it may). A supercritical
    branch exists on one side only; a subcritical one on both (from its fold, unknown before
    the branch is followed, to beyond the Hopf point: bistable between them). ``mirror``: the
    parameter changes sign with the field, so a ``to`` of the other sign may lie on the mirror
    branch (the field reversed), which is said."""
    side = branch_side(nf)
    if nf.supercritical and (to - hopf_value) * side <= 0:
        why = (f"the stroke branch exists for {parameter} {'above' if side > 0 else 'below'} the Hopf point "
               f"{hopf_value:.6g} (supercritical)")
        if mirror and to * hopf_value < 0:
            why += (f"; {parameter}={to:g} lies on the mirror branch from {-hopf_value:.6g} (the field reversed): "
                    "follow it from a base value of that sign")
        return why
    return ""


def look_beyond_limit(axis: Axis, hopf: float, to: float, look_beyond: float, side: int) -> float:
    """How far past ``to`` the branch is followed, towards ``side`` (+1 up, -1 down):
    ``look_beyond`` times the range from the Hopf point; for a parameter that is positive only,
    downwards no further than half of ``to`` (the reach below a small ``to`` in B or tau went to 0
    or below, where eta_perp ~ 1 / (B tau) diverges: from 1e-13 to 5e-15 the branch was followed
    to B = 7e-19, 10 times the cost, all of it dropped). Half, not less: at twice the paper's
    field an S-shaped branch in B folds at 0.75 and 1.28 times the paper's B, 0.6 of a ``to`` of
    1.24 times it (a fifth of the range on a log scale, 0.78, missed that fold)."""
    limit = to + side * look_beyond * abs(to - hopf)
    if axis.positive and side < 0 and to > 0:
        limit = max(limit, 0.5 * to)
    return limit


@one_blas_thread
def continue_orbits(params, parameter: str, to: float, *, n_points: int = 100,
                    n_segments: int = defaults.SWEEP_N_SEGMENTS, steps: int | None = None, tol: float = 1e-10,
                    max_newton: int = 8, progress: bool = False, max_points: int | None = None,
                    look_beyond: float = LOOK_BEYOND) -> Branch:
    """Continue the stroke from the Hopf point along ``parameter`` up to ``to``, with at least
    ``n_points`` orbits (more where the branch bends). The default resolution is the sweeps'
    (``flutterswim.defaults.SWEEP_N_SEGMENTS``, with its stated accuracy). ``tol``: closing
    residual max|Phi(u) - u| relative to 1 + max|u| (see :func:`_scaled`).

    ``look_beyond``: past ``to`` the branch is followed for this fraction of its range more
    (for a parameter that is positive only, downwards to half of ``to`` at most: :func:`look_beyond_limit`),
    for a fold that turns it back into the range (an S-shaped branch: strokes that coexist
    there). When it turns back it is followed until it leaves the range again (or ends), and
    the orbits beyond ``to`` stay in the branch; otherwise they are dropped and the branch ends
    at ``to``. 0: stop at ``to``.

    ``max_points``: at most this many orbits in all, the first one included (default
    ``10 n_points + 50``); a corrector step that fails and is retried shorter adds none, and so
    does not count.

    ``steps``: Radau steps per period. None (default): BRANCH_STEPS to start with, and each
    orbit's period and advance are screened against twice its steps (as for an orbit from
    scratch, to :data:`BRANCH_STEP_TOLERANCE`); where the screen fails the
    steps double (up to MAX_STEPS) and the orbit is solved again; where it passes with room
    (below 1/64 of the tolerance) the next orbit takes half (not below BRANCH_STEPS).
    The MAX_SKIPPED orbits after one that passed below ROOM_FRACTION of the tolerance are not
    screened (their ``step_error`` NaN). Near the kappa_E fold 32 steps put the advance 2.6e-3 off. Each
    orbit's ``step_error`` holds the screen's estimate and ``steps`` its own count. An integer:
    that many, unchecked."""
    t_start = time.perf_counter()
    axis = Axis(params, parameter)
    to = finite("to", to)
    n_points = positive_int("n_points", n_points, minimum=2)
    if n_points > MAX_POINTS:
        raise ParameterError(f"n_points={n_points} is too many; at most {MAX_POINTS} orbits along a branch")
    n_segments = segments_checked(n_segments)
    check = steps is None
    steps = positive_int("steps", BRANCH_STEPS if steps is None else steps, minimum=8, maximum=MAX_STEPS)
    tol = positive("tol", tol)
    max_newton = positive_int("max_newton", max_newton)
    max_points = 10 * n_points + 50 if max_points is None else positive_int("max_points", max_points)
    # (1e9 was taken: a branch followed a billion ranges on)
    look_beyond = within("look_beyond", look_beyond, 0.0, MAX_LOOK_BEYOND, f"times the range; default {LOOK_BEYOND:g}")
    base = axis.value()
    lo, hi = sorted((base, to))
    span = hi - lo
    hopf = hopf_point(params, parameter, n_segments=n_segments,
                      bracket=None if span == 0 else hopf_bracket(axis, n_segments, base, to))
    nf = normal_form(hopf)
    side = branch_side(nf)
    why = unreachable(nf, hopf.value, to, parameter, mirror=not axis.positive)
    if why:
        raise ParameterError(f"to={to:g}: {why}")
    first_leg = not nf.supercritical  # (a subcritical branch first runs to its fold, then turns back)
    length_p = abs(to - hopf.value)
    # the shape moves along the orbit as well as in amplitude: a few times the amplitude range
    length_u = 3.0 * math.sqrt(nf.amplitude2_slope * length_p)
    # first orbit a small distance into the branch: its amplitude along the Hopf eigenvector
    # from the normal form at 0.2 % (or 1 % of the range) past the Hopf point, capped where the
    # first Lyapunov coefficient nearly vanishes (a degenerate Hopf point: the amplitude law
    # there is no longer a square root); solved with the amplitude fixed and the parameter free
    d1 = side * min(0.01 * length_p, 0.002 * abs(hopf.value) if hopf.value != 0 else 0.01 * length_p)
    amp = min(math.sqrt(nf.amplitude2_slope * abs(d1)), START_AMPLITUDE_CAP)
    d1 = side * amp * amp / nf.amplitude2_slope
    while True:
        sysm, u, T, fl, res, it, p1 = _amplitude_start(axis, n_segments, steps, hopf, amp, hopf.value + d1, tol,
                                                       2 * max_newton)
        err, finer, _, prev_ratio = _screened(check, sysm, u, T, steps, fl)
        skipped = 0
        if not finer:
            break
        steps *= 2
    orbits: list[PeriodicOrbit] = []
    values: list[float] = [p1]
    orbits.append(replace(orbit_from_flow(axis.at(p1), sysm, fl, res, it, steps), step_error=err))
    X = [np.concatenate((u, [T, values[-1]]))]
    last_flow = fl  # (only the last is a warm start: each holds its step matrices, MBs)
    w = _weights(u.size, length_u, length_p)
    # the scale of the steps: the range from the Hopf point to ``to``, or as far from ``to`` as
    # the branch now is, updated when that changes by half or more (a nearly degenerate Hopf
    # point with ``to`` just past it: the branch first runs the other way to a fold 12 ranges
    # off and back, which steps of a range's 1/n_points could not cover in max_points orbits;
    # settle then took the last orbit, at another chi). Within 1.5 ranges of ``to``, as on every
    # ordinary branch, it is the range.
    reach = length_p
    ds = 0.7 / n_points
    ds_max = 3.0 / n_points
    bar = _bar(progress, length_p)
    message = f"reached {parameter}={to:g}"
    # past ``to`` (look_beyond): the orbits up to ``to``, the outer limit, whether it turned back
    target, n_at_to, turned = to, None, False
    limit = look_beyond_limit(axis, hopf.value, to, look_beyond, side)
    try:
        while True:
            if len(orbits) >= max_points:
                if n_at_to is None:
                    message = f"stopped after max_points={max_points} orbits before {parameter}={to:g}"
                elif turned:
                    message += f" (stopped after max_points={max_points} orbits at {parameter}={short_of(values[-1], to)})"
                break
            xk = X[-1]
            if len(X) == 1:
                # along the amplitude: du/da = (u - u_s)/a, dp/da = 2 a / slope (square-root law)
                tangent = np.zeros_like(xk)
                tangent[:-2] = (u - sysm.straight()) / amp
                tangent[-1] = side * 2 * amp / nf.amplitude2_slope
            else:
                tangent = X[-1] - X[-2]
            tangent = tangent / math.sqrt(np.sum((tangent * w) ** 2))
            # at most 1/n_points of the parameter range per step, so that there are n_points or more
            step_ds = min(ds, reach / (n_points * max(abs(tangent[-1]), 1e-300)))
            if first_leg and len(X) > 1 and tangent[-1] * side > 0:  # the subcritical branch has folded
                first_leg = False
                fold = min(values, key=lambda v: v * side)
                if (to - fold) * side < 0:
                    message = (f"no stroke at {parameter}={to:g}: the branch leaves the Hopf point {parameter}="
                               f"{hopf.value:.6g} as unstable orbits (subcritical) and folds back at {parameter}="
                               f"{fold:.6g} before reaching it")
                    break
            finishing = (not first_leg and (xk[-1] + step_ds * tangent[-1] - target) * side >= 0
                         and tangent[-1] * side > 0)
            try:
                if finishing:
                    xn, fl, res, it = _newton_natural(axis, n_segments, steps, xk, last_flow, target, tol, max_newton)
                else:
                    xn, fl, res, it = _newton_arclength(axis, n_segments, steps, xk, last_flow, tangent, w,
                                                        step_ds, tol, max_newton)
            except (OrbitNotFound, StepFailure, np.linalg.LinAlgError, ParameterError) as exc:
                # (ParameterError: the corrector left the parameter's admissible range)
                ds *= 0.5
                if ds < 1e-4 / n_points:
                    if n_at_to is None or turned:
                        message = f"continuation stopped at {parameter}={short_of(xk[-1], to)}: {exc}"
                    break
                continue
            pval = float(xn[-1])
            sysn = _systems(axis, pval, n_segments)
            m = xn.size - 2
            # up to MAX_SKIPPED orbits after one that passed with room are not screened (prev_ratio
            # NaN: the steps changed, screen)
            screen = check and not (prev_ratio < ROOM_FRACTION and skipped < MAX_SKIPPED)
            err, finer, coarser, ratio = _screened(screen, sysn, xn[:m], float(xn[m]), steps, fl)
            skipped = 0 if screen else skipped + 1
            prev_ratio = ratio if screen else prev_ratio
            if finer:  # the same step again, solved with twice the steps (no warm start at the old ones)
                steps *= 2
                last_flow = None
                prev_ratio = math.nan
                continue
            orbits.append(replace(orbit_from_flow(axis.at(pval), sysn, fl, res, it, steps), step_error=err))
            values.append(pval)
            X.append(xn)
            last_flow = fl
            far = max(length_p, abs(pval - to))
            if far > 1.5 * reach or far < reach / 1.5:  # (out and back: the steps grow, then shrink again)
                reach = far
                w = _weights(u.size, 3.0 * math.sqrt(nf.amplitude2_slope * reach), reach)
            if coarser:  # half the steps from the next orbit on (its warm start is at these)
                steps //= 2
                last_flow = None
                prev_ratio = math.nan
            if bar is not None and n_at_to is None:
                # how far into the range the branch has come (a branch that runs back past a fold
                # summed its steps past the total: tqdm's "clamping frac to range [0, 1]")
                done = min(bar.total, max(0.0, (values[-1] - hopf.value) * side))
                if done > bar.n:
                    bar.update(done - bar.n)
            if n_at_to is not None and not turned and (values[-1] - to) * side < 0:
                # a fold beyond ``to`` has turned the branch back into the range: follow it until it
                # leaves the range again
                turned, target = True, to
                fold = max(values[n_at_to:], key=lambda v: v * side)
                message = (f"reached {parameter}={to:g}; the branch folds back at {parameter}={fold:.6g} "
                           "beyond it and was followed until it leaves the range again")
            if turned and (values[-1] - hopf.value) * side <= 0:
                message += f" (it returned to the Hopf point's side at {parameter}={values[-1]:.6g})"
                break
            if finishing:
                if n_at_to is None and look_beyond > 0:
                    n_at_to, target = len(orbits), limit
                    continue
                break
            ds = min(ds_max, max(ds, step_ds) * (1.5 if it <= 4 else 0.7 if it >= 7 else 1.0))
    finally:  # (closed before Ctrl-C's message, which it would share a line with)
        if bar is not None:
            bar.close()
    if n_at_to is not None and not turned:  # no fold back into the range: the branch ends at ``to``
        del orbits[n_at_to:], values[n_at_to:]
    _warn_inaccurate(parameter, values, orbits)
    return Branch(axis, np.array(values), orbits, hopf.value, hopf.omega, nf.lyapunov_coefficient,
                  nf.amplitude2_slope_rms, n_segments, max(o.steps for o in orbits), time.perf_counter() - t_start, message)


#: a non-trivial multiplier counts as real when its imaginary part is below this fraction of
#: its modulus (a real monodromy matrix's real eigenvalues come out with none; a complex pair
#: leaving the circle near +1 turns slowly, at a torus crossing of the paper's model 1e-2 rad or more)
REAL_MULTIPLIER = 1e-6


def leading_multiplier(orbit) -> complex:
    """The largest non-trivial Floquet multiplier of ``orbit`` (the trivial one, the orbit's
    own phase, is the one nearest 1)."""
    mu = np.asarray(orbit.multipliers)
    mu = np.delete(mu, int(np.argmin(np.abs(mu - 1.0))))
    return complex(mu[int(np.argmax(np.abs(mu)))])


def multiplier_kind(orbit) -> str:
    """What the largest non-trivial multiplier of ``orbit`` is: "torus" (a complex pair),
    "period doubling" (real, negative) or "real" (real, positive)."""
    lead = leading_multiplier(orbit)
    if abs(lead.imag) > REAL_MULTIPLIER * abs(lead):
        return "torus"
    return "period doubling" if lead.real < 0 else "real"


def crossing_kind(orbit, values: np.ndarray, i: int) -> str:
    """How the stability changes between orbits i and i + 1 of a branch at ``values``, from
    ``orbit`` (the one of the two with a non-trivial multiplier outside the unit circle): its
    largest non-trivial multiplier real and positive, "fold" if the parameter turns back
    within two orbits of the crossing (its steps change sign), else "branch point"; real and
    negative, "period doubling"; complex, "torus"."""
    kind = multiplier_kind(orbit)
    if kind != "real":
        return kind
    d = np.diff(values[max(i - 2, 0):i + 4])
    return "fold" if np.any(d[:-1] * d[1:] < 0) else "branch point"


def _step_range(orbits) -> str:
    steps = sorted({o.steps for o in orbits})
    return f"{steps[0]}" if len(steps) <= 1 else f"{steps[0]}-{steps[-1]}"


#: The advance's step error along a branch is relative to max(advance, this) (in l): near the
#: Hopf point the advance vanishes (a branch's reaches 0.15 l); 32 steps there are 2e-7 l off,
#: 2e-4 of 1e-3 l (an orbit from scratch's floor), 2e-5 of this
ADVANCE_FLOOR = 1e-2
#: An orbit whose screen passed below this fraction of the tolerance lets the next MAX_SKIPPED
#: go unscreened (at the same steps): along a few steps of the branch the error changes little
ROOM_FRACTION = 1 / 8
MAX_SKIPPED = 2


def _screened(check: bool, system: ShapeSystem, u: np.ndarray, T: float, steps: int,
              fl) -> tuple[float, bool, bool, float]:
    """(the step screen's estimate or NaN, whether to solve again with twice the steps, whether
    the next orbit may take half, the estimate as a fraction of the tolerance or NaN). Half:
    the estimate below 1/64 of the tolerance, where halving (order 5: about 32 times the
    error) still passes with room."""
    if not check or fl.monodromy is None:
        return math.nan, False, False, math.nan
    adv = float(np.hypot(*(fl.y[-1, :2] - fl.y[0, :2])))
    screened = step_screen(system, u, T, steps, fl.monodromy, adv, advance_floor=ADVANCE_FLOOR)
    if screened is None:
        return math.nan, False, False, math.nan
    ratio = max(screened[0] / BRANCH_STEP_TOLERANCE[0], screened[1] / BRANCH_STEP_TOLERANCE[1])
    finer = not screen_passes(screened, BRANCH_STEP_TOLERANCE) and 2 * steps <= MAX_STEPS
    return max(screened), finer, steps > BRANCH_STEPS and ratio < 1 / 64, ratio


def short_of(value: float, end: float) -> str:
    """``value`` with 6 significant digits, or as many more as tell it from ``end`` (printed as
    ``{end:g}``): a branch stopped at 0.69999997 did not stop "at 0.7", short of 0.7."""
    for digits in range(6, 18):
        text = f"{value:.{digits}g}"
        if value == end or text != f"{end:.{digits}g}":
            return text
    return repr(float(value))


def _warn_inaccurate(parameter, values, orbits) -> None:
    """Warn (UserWarning) if some orbits' trivial multiplier is off 1 by more than ACCURACY_GAUGE."""
    err = np.array([o.trivial_multiplier_error for o in orbits])
    bad = np.nonzero(err > ACCURACY_GAUGE)[0]
    if bad.size:
        v = np.asarray(values)[bad]
        steps = _step_range([orbits[i] for i in bad])  # theirs, not the branch's largest
        warnings.warn(f"{bad.size} of {err.size} orbits ({parameter} {v.min():.6g} to {v.max():.6g}) have the trivial "
                      f"Floquet multiplier off 1 by up to {err.max():.2g} (> {ACCURACY_GAUGE:g}): {steps} steps per "
                      "period limit their accuracy there; continue with more (steps=) to check them",
                      UserWarning, stacklevel=4)  # (the caller of continue_orbits)


def _amplitude_start(axis, n, steps, hopf, amp, p_guess, tol, max_newton):
    """The orbit of amplitude ``amp`` along the Hopf eigenvector q: Newton on (u, T, p) with
    the phase condition (u - u_s).q_i = 0 and the amplitude condition (u - u_s).q_r = amp |q_r|^2
    (q_r, q_i: real and imaginary parts of q, q_i orthogonalised). Well posed however flat the
    amplitude law is at the Hopf point."""
    qr = hopf.q.real.copy()
    qi = hopf.q.imag - (hopf.q.imag @ qr) / (qr @ qr) * qr
    qi /= np.linalg.norm(qi)
    us = _systems(axis, hopf.value, n).straight()
    m = us.size
    rows = np.zeros((2, m + 2))
    rows[0, :m], rows[1, :m] = qi, qr

    def conditions(x):
        d = x[:m] - us
        return np.array([qi @ d, qr @ d - amp * (qr @ qr)]), rows

    x0 = np.concatenate((us + amp * qr, [2 * math.pi / hopf.omega, p_guess]))
    x, sysm, final, res, it = _newton_bordered(axis, n, steps, x0, None, conditions, 1e-10 * (1.0 + amp), tol,
                                               max_newton, "the start from the Hopf point")
    return sysm, x[:m], x[m], final, res, it, float(x[-1])


def _newton_bordered(axis, n, steps, x, warm, conditions, cond_tol, tol, max_newton, what):
    """Newton on x = (u, T, p) for Phi(u, T, p) = u and two scalar conditions
    ``conditions(x) -> (values (2,), their gradients (2, m + 2))``; dPhi/dp by a difference of
    flows, formed at the first iteration and kept (it changes little over a corrector).
    Returns (x, system, exact final flow, residual, iterations)."""
    m = x.size - 2
    fl, dphi_dp, res = warm, None, math.inf
    for it in range(1, max_newton + 1):
        u, T, p = x[:m], x[m], x[-1]
        sysm, fl = _closing(axis, n, steps, u, T, p, fl, True, derivative_tol=1e-6)
        r = fl.y[-1, 2:] - u
        res = float(np.max(np.abs(r)))
        c, rows = conditions(x)
        if res < _scaled(tol, u) and np.max(np.abs(c)) < cond_tol:
            _, final = _closing(axis, n, steps, u, T, p, fl, True)
            return x, sysm, final, float(np.max(np.abs(final.y[-1, 2:] - u))), it
        if dphi_dp is None:
            dp = 1e-6 * abs(p) if p != 0 else 1e-6  # relative: physical parameters may be ~1e-14
            _, fl_p = _closing(axis, n, steps, u, T, p + dp, fl, False)
            dphi_dp = (fl_p.y[-1, 2:] - fl.y[-1, 2:]) / dp
        a = np.zeros((m + 2, m + 2))
        a[:m, :m] = fl.monodromy - np.eye(m)
        a[:m, m] = fl.f[-1, 2:]
        a[:m, m + 1] = dphi_dp
        a[m:] = rows
        x = x + np.linalg.solve(a, -np.concatenate((r, c)))
        if not (np.all(np.isfinite(x)) and x[m] > 0):
            raise OrbitNotFound(f"{what}: Newton left the admissible region at iteration {it}")
    raise OrbitNotFound(f"{what}: no convergence in {max_newton} iterations (residual {res:.3g})")


def _scaled(tol: float, u: np.ndarray) -> float:
    """The closing tolerance relative to the state's scale: the residual Phi(u) - u is a
    difference of states of size max|u| (curvatures kappa l reach ~20 on the branch), and the
    flow solves its stage equations to 1e-13 (1 + max|u|) per step (shooting.flow), errors the
    stiff steps amplify (large eta_perp, few segments) to ~1e-9 at max|u| ~ 17: an absolute
    1e-10 is below that floor, so Newton wanders there (eta_perp ~ 163, N = 8, 16 steps)."""
    return tol * (1.0 + float(np.max(np.abs(u))))


def _weights(m: int, length_u: float, length_p: float) -> np.ndarray:
    w = np.empty(m + 2)
    w[:m] = 1.0 / max(length_u, 1e-12)
    w[m] = 0.0  # the period does not count in the arclength
    w[m + 1] = 1.0 / length_p
    return w


def _closing(axis, n, steps, u, T, p, warm, variational, derivative_tol=1e-10):
    sysm = _systems(axis, p, n)
    fl = flow(sysm, u, T, steps, variational=variational, warm=warm, derivative_tol=derivative_tol)
    return sysm, fl


def _newton_arclength(axis, n, steps, xk, warm, tangent, w, ds, tol, max_newton):
    """Corrector: Newton on (u, T, p) with the phase condition at the previous orbit and the
    pseudo-arclength condition (weights ``w``) at distance ``ds`` along ``tangent``."""
    m = xk.size - 2
    normal = _systems(axis, xk[-1], n).f(xk[:m])
    normal /= np.linalg.norm(normal)
    rows = np.zeros((2, m + 2))
    rows[0, :m], rows[1] = normal, w * w * tangent

    def conditions(x):
        return np.array([normal @ (x[:m] - xk[:m]), float(np.sum(w * w * tangent * (x - xk))) - ds]), rows

    x, _, final, res, it = _newton_bordered(axis, n, steps, xk + ds * tangent, warm, conditions, 1e-8, tol,
                                            max_newton, "corrector")
    return x, final, res, it


def _newton_natural(axis, n, steps, xk, warm, p, tol, max_newton):
    from .periodic import solve_orbit

    m = xk.size - 2
    sysm = _systems(axis, p, n)
    u, T, fl, res, it = solve_orbit(sysm, xk[:m], xk[m], steps=steps, tol=_scaled(tol, xk[:m]),
                                    max_newton=max_newton, u_ref=xk[:m])
    return np.concatenate((u, [T, p])), fl, res, it


def _bar(enabled: bool, total: float):
    if not enabled:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=round(total, 6), desc="branch", unit=" (parameter)", leave=False,
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}")
