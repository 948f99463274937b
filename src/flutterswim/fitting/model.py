"""The descriptor model of the fit: (B, tau, kappa_E) -> period, advance, lateral excursion,
from the stroke's periodic orbit (smooth in the parameters, unlike time-stepping estimates).

With the geometry (l, a, b) and the viscosity fixed, the dimensionless stroke depends only on
eta_perp = mu_perp l^4 / (B tau) and chi = kappa_E l (eta_par / eta_perp is fixed by b/l);
tau only scales the period. So the fit works in the identifiable coordinates
x = (log eta_perp, log chi, log tau) and maps back:
B = mu_perp l^4 / (eta_perp tau), kappa_E = chi / l.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import ParameterError
from ..params import Groups, Parameters

__all__ = ["DescriptorModel", "to_physical", "to_identifiable", "LOG_MAP", "NotSwimming"]

#: d(log B, log tau, log kappa_E) / d(log eta_perp, log chi, log tau)
LOG_MAP = np.array([[-1.0, 0.0, -1.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])


class NotSwimming(RuntimeError):
    """No stable stroke at these parameters (the straight state is stable, or Newton failed)."""


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
    direction). Orbits are cached and each new one starts from the nearest cached one."""

    base: Parameters
    tip: str = "trailing"
    n_segments: int = 24
    steps: int = 24
    n_evaluations: int = 0
    executor: object = field(default=None, repr=False, compare=False)  # for parallel differences
    _cache: list = field(default_factory=list, repr=False)
    _memo: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.base, Parameters):
            raise ParameterError(f"base={self.base!r} must be flutterswim.Parameters (geometry and viscosity)")
        if self.tip not in ("trailing", "leading"):
            raise ParameterError(f"tip={self.tip!r} must be 'trailing' or 'leading'")

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
        self.n_evaluations += 1
        out = solve_point((self.groups(eta_perp, chi), self._nearest(key), self.n_segments, self.steps))
        if isinstance(out, str):
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

    def prefetch(self, xs, executor) -> None:
        """Compute the orbits at identifiable points ``xs`` (k, 3) not yet known, in parallel
        on ``executor`` (a sweep backend's executor: ``imap(fn, ((key, item), ...))``), each
        from its nearest known neighbour; afterwards calls at these points are cache hits."""
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
        if len(todo) < 2:
            return  # nothing to share out: the serial path computes it
        for (eta_perp, chi), out in executor.imap(solve_point, list(todo.items())):
            self.n_evaluations += 1
            if isinstance(out, str) or not hasattr(out, "theta"):  # NotSwimming reason or WorkerLost
                continue  # the serial call will recompute it and raise
            self._remember(np.array([math.log(eta_perp), math.log(chi)]), out)

    def dimensionless(self, eta_perp: float, chi: float) -> np.ndarray:
        """(period / tau, advance / l, lateral / l), memoised on (eta_perp, chi)."""
        key = (float(eta_perp), float(chi))
        if key not in self._memo:
            o = self.orbit(eta_perp, chi)
            lat = o.lateral_trailing if self.tip == "trailing" else o.lateral_leading
            self._memo[key] = np.array([o.period, o.advance, lat])
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
