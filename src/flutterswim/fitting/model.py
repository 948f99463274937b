"""The descriptor model of the fit: (B, tau, kappa_E) -> period, advance, lateral excursion,
from the stroke's periodic orbit (smooth in the parameters, unlike time-stepping estimates).

With the geometry (l, a, b) and the viscosity fixed, the dimensionless stroke depends only on
eta_perp = mu_perp l^4 / (B tau) and chi = kappa_E l (eta_par / eta_perp is fixed by b/l);
tau only scales the period. So the fit works in the identifiable coordinates
x = (log eta_perp, log chi, log tau) and maps back:
B = mu_perp l^4 / (eta_perp tau), kappa_E = chi / l.

The descriptors are those of the continuum filament: the orbit's descriptors converge at
order 2 in the segment count N, so by default they are extrapolated from N and 2N
(Richardson: D = D_2N + (D_2N - D_N) / 3). At the paper's point N = 24 alone puts the advance
1.8 % and the lateral 0.7 % above the continuum, which moves the fitted B, tau, kappa_E by
4-6 % (2-7 % elsewhere in the box); the extrapolation from 24 and 48 is within 0.04 % of it
(an extrapolation from 48 and 96 as the reference), and fits such data within 0.15 %.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from .._validate import MAX_SEGMENTS, ParameterError, positive_int
from ..params import Groups, Parameters

__all__ = ["DescriptorModel", "to_physical", "to_identifiable", "LOG_MAP", "NotSwimming", "Unresolved",
           "OutsideModel"]

#: d(log B, log tau, log kappa_E) / d(log eta_perp, log chi, log tau)
LOG_MAP = np.array([[-1.0, 0.0, -1.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])


#: largest relative change of a descriptor between N and 2N segments that extrapolation accepts
#: (the paper's box: at most 2 %; near onset or on another branch, tens of percent)
MAX_REFINEMENT_CHANGE = 0.10


#: the finest coarse level the fits refine to when a stroke is not resolved (its fine level 96)
MAX_COARSE_SEGMENTS = 48


class NotSwimming(RuntimeError):
    """No stable stroke at these parameters (the straight state is stable, or Newton failed)."""


class OutsideModel(NotSwimming):
    """The fit cannot proceed: the data are outside what the model can reproduce (no stable
    stroke at the start, or at every point the fit tries around its last one)."""


class Unresolved(NotSwimming):
    """The stroke changes by more than MAX_REFINEMENT_CHANGE from N to 2N segments, so no
    extrapolation is meaningful (near the onset of swimming, or N finds another stroke)."""


def to_identifiable(base: Parameters, B: float, tau: float, kappa_E: float) -> np.ndarray:
    """x = (log eta_perp, log chi, log tau) of physical (B [N m^2], tau [s], kappa_E [1/m])."""
    eta_perp = base.mu_perp * base.l ** 4 / (B * tau)
    return np.array([math.log(eta_perp), math.log(kappa_E * base.l), math.log(tau)])


def to_physical(base: Parameters, x: np.ndarray) -> tuple[float, float, float]:
    """(B [N m^2], tau [s], kappa_E [1/m]) of identifiable coordinates x."""
    eta_perp, chi, tau = np.exp(x)
    return float(base.mu_perp * base.l ** 4 / (eta_perp * tau)), float(tau), float(chi / base.l)


@dataclass
class DescriptorModel:
    """Descriptors of the stroke at fixed geometry and viscosity (``base``). ``tip``: which
    end's lateral peak-to-peak is compared (``"trailing"`` or ``"leading"``, by the swimming
    direction). Orbits are cached and each new one starts from the nearest cached one.

    ``extrapolate`` (default): descriptors extrapolated to the continuum from ``n_segments``
    and twice as many (Richardson, order 2); otherwise those of ``n_segments`` alone (for data
    made by a model of that resolution). :meth:`orbit` and :meth:`shape` are those of
    ``n_segments``."""

    base: Parameters
    tip: str = "trailing"
    n_segments: int = 24
    steps: int = 24
    extrapolate: bool = True
    n_evaluations: int = 0
    #: points refused as not resolved so far, and the last refusal's message
    n_unresolved: int = 0
    last_unresolved: str = ""
    last_change: float = 0.0  # the largest relative change from N to 2N of the last unresolved stroke
    executor: object = field(default=None, repr=False, compare=False)  # for parallel differences
    _cache: list = field(default_factory=list, repr=False)
    _memo: dict = field(default_factory=dict, repr=False)
    #: points without a stable stroke, with the reason (an optimiser that tries one again is
    #: told at once instead of waiting for the same failure)
    _failed: dict = field(default_factory=dict, repr=False)
    _fine: "DescriptorModel | None" = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.base, Parameters):
            raise ParameterError(f"base={self.base!r} must be flutterswim.Parameters (geometry and viscosity)")
        if self.tip not in ("trailing", "leading"):
            raise ParameterError(f"tip={self.tip!r} must be 'trailing' or 'leading'")
        if not isinstance(self.extrapolate, (bool, np.bool_)):
            raise ParameterError(f"extrapolate={self.extrapolate!r} must be True or False")
        # (extrapolating: the fine model has twice the segments, within MAX_SEGMENTS too)
        top = MAX_SEGMENTS // 2 if self.extrapolate and self._fine is None else MAX_SEGMENTS
        positive_int("n_segments", self.n_segments, 8, top,
                     "extrapolating from it and twice as many" if top < MAX_SEGMENTS else "")
        if self.extrapolate and self._fine is None:
            self._fine = DescriptorModel(self.base, tip=self.tip, n_segments=2 * int(self.n_segments),
                                         steps=self.steps, extrapolate=False)

    @property
    def evaluations(self) -> int:
        """Orbits computed so far (both resolutions when extrapolating)."""
        return self.n_evaluations + (self._fine.n_evaluations if self._fine is not None else 0)

    def finer(self) -> "DescriptorModel | None":
        """The same extrapolating model from twice the segments, or None (a single
        resolution, or already at MAX_COARSE_SEGMENTS)."""
        if self._fine is None or self.n_segments >= MAX_COARSE_SEGMENTS:
            return None
        return DescriptorModel(self.base, tip=self.tip, n_segments=2 * int(self.n_segments), steps=self.steps,
                               executor=self.executor)

    @property
    def resolution(self) -> str:
        """What the descriptors are, in words (for a fit's settings)."""
        if self._fine is None:
            return f"orbits of {self.n_segments} segments"
        return (f"extrapolated to the continuum from orbits of {self.n_segments} and {self._fine.n_segments} "
                "segments (Richardson, order 2)")

    @property
    def drag_ratio(self) -> float:
        return self.base.mu_par / self.base.mu_perp

    def groups(self, eta_perp: float, chi: float) -> Groups:
        return Groups(eta_perp * self.drag_ratio, eta_perp, chi)

    def orbit(self, eta_perp: float, chi: float):
        """The stroke at (eta_perp, chi) as a dimensionless PeriodicOrbit."""
        if not (eta_perp > 0 and chi > 0 and math.isfinite(eta_perp) and math.isfinite(chi)):
            raise NotSwimming(f"eta_perp={eta_perp!r}, chi={chi!r} are outside the model's range (both > 0)")
        key = np.array([math.log(eta_perp), math.log(abs(chi))])
        for k, o in self._cache:  # an exact repeat (the orbit depends on (eta_perp, chi) only)
            if np.array_equal(k, key):
                return o
        if (float(eta_perp), float(chi)) in self._failed:
            raise NotSwimming(self._failed[(float(eta_perp), float(chi))])
        self.n_evaluations += 1
        out = solve_point((self.groups(eta_perp, chi), self._nearest(key), self.n_segments, self.steps))
        if isinstance(out, str):
            self._failed[(float(eta_perp), float(chi))] = out
            raise NotSwimming(out)
        self._remember(key, out)
        return out

    def _nearest(self, key: np.ndarray):
        if not self._cache:
            return None
        d = [np.sum((k - key) ** 2) for k, _ in self._cache]
        return self._cache[int(np.argmin(d))][1]

    def _remember(self, key: np.ndarray, orb) -> None:
        self._cache.append((key, orb))
        if len(self._cache) > 64:
            self._cache.pop(0)
        if len(self._cache) > 8:  # warm starts (step matrices, MBs each) only on the newest
            k, o = self._cache[-9]
            self._cache[-9] = (k, o.compact())

    def _missing(self, xs) -> dict:
        """Work items for the identifiable points ``xs`` whose orbits are not yet known."""
        todo = {}
        for x in xs:
            eta_perp, chi, _ = np.exp(x)  # as __call__ does (np.exp and math.exp may differ by an ulp)
            if (float(eta_perp), float(chi)) in self._memo or not (math.isfinite(eta_perp) and math.isfinite(chi)):
                continue
            key = np.array([math.log(eta_perp), math.log(chi)])
            if any(np.array_equal(k, key) for k, _ in self._cache):
                continue
            todo[(float(eta_perp), float(chi))] = (self.groups(eta_perp, chi), self._nearest(key),
                                                   self.n_segments, self.steps)
        return todo

    def prefetch(self, xs, executor) -> None:
        """Compute the orbits at identifiable points ``xs`` (k, 3) not yet known (at both
        resolutions when extrapolating), in parallel on ``executor`` (a sweep backend's
        executor: ``imap(fn, ((key, item), ...))``), each from its nearest known neighbour;
        afterwards calls at these points are cache hits."""
        models = [self] if self._fine is None else [self, self._fine]
        todo = {(j, k): item for j, m in enumerate(models) for k, item in m._missing(xs).items()}
        if len(todo) < 2:
            return  # nothing to share out: the serial path computes it
        for (j, (eta_perp, chi)), out in executor.imap(solve_point, list(todo.items())):
            models[j].n_evaluations += 1
            if isinstance(out, str) or not hasattr(out, "theta"):  # NotSwimming reason or WorkerLost
                continue  # the serial call will recompute it and raise
            models[j]._remember(np.array([math.log(eta_perp), math.log(chi)]), out)

    def dimensionless(self, eta_perp: float, chi: float) -> np.ndarray:
        """(period / tau, advance / l, lateral / l), memoised on (eta_perp, chi)."""
        key = (float(eta_perp), float(chi))
        if key not in self._memo:
            o = self.orbit(eta_perp, chi)
            lat = o.lateral_trailing if self.tip == "trailing" else o.lateral_leading
            d = np.array([o.period, o.advance, lat])
            if self._fine is not None:
                f = self._fine.dimensionless(eta_perp, chi)
                change = np.max(np.abs(f / d - 1.0))
                if not change < MAX_REFINEMENT_CHANGE:
                    # not the same stroke resolved twice (another branch, or too close to onset
                    # for N segments): no extrapolation is meaningful
                    self.n_unresolved += 1
                    self.last_change = float(change)
                    self.last_unresolved = (
                        f"the stroke at eta_perp={eta_perp:.4g}, chi={chi:.4g} changes by {100 * change:.3g} % from "
                        f"{self.n_segments} to {self._fine.n_segments} segments (limit "
                        f"{100 * MAX_REFINEMENT_CHANGE:g} %): not resolved (more segments, --segments)")
                    raise Unresolved(self.last_unresolved)
                d = f + (f - d) / 3.0
            self._memo[key] = d
        return self._memo[key].copy()

    def shape(self, eta_perp: float, chi: float) -> np.ndarray:
        """Tangent angle over one cycle on the orbit's phase grid, (M, N) [rad]."""
        return self.orbit(eta_perp, chi).theta

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """Descriptors (period [s], advance [mm], lateral [mm]) at identifiable coordinates x."""
        eta_perp, chi, tau = np.exp(x)
        d = self.dimensionless(eta_perp, chi)
        return np.array([d[0] * tau, d[1] * self.base.l * 1e3, d[2] * self.base.l * 1e3])

    def jacobian(self, x: np.ndarray, y0: np.ndarray | None = None, *, step: float = 1e-5) -> np.ndarray:
        """d(descriptors) / dx (3, 3): central differences in log eta_perp and log chi (smooth
        orbit descriptors), exact in log tau (only the period scales with tau). With an
        ``executor`` set, the four difference orbits are computed in parallel on it."""
        if self.executor is not None:
            pts = [x] + [x + sgn * step * np.eye(3)[k] for k in (0, 1) for sgn in (1.0, -1.0)]
            self.prefetch(pts, self.executor)
        y0 = self(x) if y0 is None else y0
        jac = np.zeros((3, 3))
        for k in (0, 1):
            e = np.zeros(3)
            e[k] = step
            try:
                jac[:, k] = (self(x + e) - self(x - e)) / (2 * step)
            except NotSwimming:  # a neighbour without a stroke (edge of the region): one side
                try:
                    jac[:, k] = (self(x + e) - y0) / step
                except NotSwimming:
                    jac[:, k] = (y0 - self(x - e)) / step
        jac[0, 2] = y0[0]
        return jac


def solve_point(item):
    """Worker function (module level, so that backends can pickle it): the stable orbit at
    ``item = (groups, guess or None, n_segments, steps)``, or a string saying why there is none.
    A failure from a far neighbour is retried from scratch."""
    from ..orbits import OrbitNotFound, periodic_orbit

    groups, guess, n_segments, steps = item
    with warnings.catch_warnings():
        # (the fit's own steps, unchecked: its resolution is judged by N against 2N instead)
        warnings.filterwarnings("ignore", message="the orbit's trivial Floquet multiplier", category=UserWarning)
        try:
            orb = periodic_orbit(groups, guess, n_segments=n_segments, steps=steps)
        except OrbitNotFound as exc:
            if guess is None:
                return str(exc)
            try:
                orb = periodic_orbit(groups, n_segments=n_segments, steps=steps)
            except OrbitNotFound as exc2:
                return str(exc2)
    if not orb.stable:
        return f"the stroke at eta_perp={groups.eta_perp:.4g}, chi={groups.chi:.4g} is unstable"
    return orb
