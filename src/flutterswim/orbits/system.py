"""The shape dynamics of the filament in a steady field: the system whose periodic orbits
are strokes.

The simulator's state is y = [x0, y0, theta (N), kappa (N+1)]. Its right-hand side does not
depend on the position r(0) = (x0, y0) (translation symmetry), so the shape u = (theta, kappa)
(size 2N+1) evolves on its own; r(0) follows by quadrature. Everything here comes from the
simulator's :class:`flutterswim.filament.Filament`: the same rhs and its exact Jacobian.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..filament import Filament
from ..params import Groups, Parameters

__all__ = ["ShapeSystem"]


@dataclass(frozen=True)
class ShapeSystem:
    """Autonomous shape dynamics at field direction ``phi`` (radians), unit strength."""

    filament: Filament
    phi: float = 0.0

    @classmethod
    def of(cls, params: Parameters | Groups, n_segments: int, phi: float = 0.0) -> "ShapeSystem":
        g = params.groups if isinstance(params, Parameters) else params
        return cls(Filament(n_segments, g.eta_par, g.eta_perp, g.chi), phi)

    @property
    def n(self) -> int:
        return self.filament.n

    @property
    def size(self) -> int:
        """Dimension of the shape space, 2N + 1."""
        return 2 * self.n + 1

    def full(self, u: np.ndarray, r0=(0.0, 0.0)) -> np.ndarray:
        return np.concatenate((np.asarray(r0, float), u))

    def rhs_full(self, y: np.ndarray) -> np.ndarray:
        """Simulator rhs of the full state y (2N+3,)."""
        return self.filament.rhs(y, self.phi, 1.0)

    def jac_full(self, y: np.ndarray) -> np.ndarray:
        """Exact Jacobian of :meth:`rhs_full` (2N+3, 2N+3)."""
        return self.filament.jacobian(y, self.phi, 1.0, exact=True)

    def f(self, u: np.ndarray) -> np.ndarray:
        """Shape rhs u_t = f(u), (2N+1,)."""
        return self.rhs_full(self.full(u))[2:]

    def jac(self, u: np.ndarray) -> np.ndarray:
        """Exact Jacobian df/du (2N+1, 2N+1)."""
        return self.jac_full(self.full(u))[2:, 2:]

    def at_points(self, points: np.ndarray, what: str) -> np.ndarray:
        """The exact Jacobians (``what="jacobian"``: (k, 2N+1, 2N+1)) or the group derivatives
        (``"groups"``: (k, 2N+1, 3)) at k shapes ``points`` (k, 2N+1): the simulator's kernels
        (:mod:`flutterswim.rosw`) called directly, for the Radau steps' stages."""
        from .. import rosw

        fil = self.filament
        k = rosw.kernels() if fil.compiled else rosw
        size = points.shape[1] + 2
        y = np.zeros(size)
        if what == "jacobian":
            out = np.empty((points.shape[0], size, size))
            args = (*fil.rhs_args(self.phi, 1.0), True)
            kernel = k.jacobian
        else:
            out = np.empty((points.shape[0], size, 3))
            args = fil.group_args(self.phi, 1.0)
            kernel = k.group_derivatives
        for i in range(points.shape[0]):
            y[2:] = points[i]
            kernel(y, *args, out[i])
        return out[:, 2:, 2:] if what == "jacobian" else out[:, 2:]

    def straight(self) -> np.ndarray:
        """The straight state aligned with the field: an equilibrium."""
        u = np.zeros(self.size)
        u[: self.n] = self.phi
        return u
