"""Discrete filament: geometry, resistive-force drag and the mobility problem.

Dimensionless throughout (length by l, time by tau, forces by B/l^2).

The filament is cut into N straight segments of length h = 1/N with tangent angles
theta_i (i = 0..N-1, at the segment midpoints s_i = (i + 1/2) h). Joints j = 0..N sit
at s_j = j h, X_0 = r(0). The spontaneous curvature kappa_j lives at the joints.

State vector y = [x0, y0, theta_0..theta_{N-1}, kappa_0..kappa_N], size 2N + 3.

Mobility problem (no inertia), :mod:`flutterswim.mobility`: unknowns
z = [U0x, U0y, omega_0..omega_{N-1}] with omega = theta_t; drag law :mod:`flutterswim.drag`
at the joints (joint tangent angle interpolated from its segments), integrated by the
trapezoidal rule. (Sampling the drag at segment midpoints instead leaves a zig-zag null
mode.) G z = b balances drag against the bending moment M_j = theta_s(s_j) - kappa_j (eq. MOD:eq:bending_moment_constitutive)
and M_0 = M_N = 0 (free ends). theta_s and the joint angles use 4th-order staggered stencils
inside and 2-point stencils next to the ends (:func:`_joint_difference`, :func:`_joint_average`).
Activity (:mod:`flutterswim.activity`, eq. MOD:eq:nondim_EVO with the field direction phi
and strength sigma): kappa_t = -kappa - chi sigma sin(theta_node - phi).
The scheme is second order in h.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import mobility

__all__ = ["Filament", "centreline"]


@dataclass(frozen=True)
class Filament:
    """Set-up of the discrete filament: resolution, drag groups and cached masks."""

    n: int
    eta_par: float
    eta_perp: float
    chi: float
    compiled: bool = True
    _weights: np.ndarray = field(init=False, repr=False, compare=False)
    _avg: np.ndarray = field(init=False, repr=False, compare=False)
    _diff: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        n = self.n
        weights = np.full(n + 1, 1.0 / n)
        weights[[0, -1]] *= 0.5
        object.__setattr__(self, "_weights", weights)
        object.__setattr__(self, "_avg", _joint_average(n))
        object.__setattr__(self, "_diff", _joint_difference(n))

    @property
    def h(self) -> float:
        return 1.0 / self.n

    @property
    def size(self) -> int:
        return 2 * self.n + 3

    @property
    def s_mid(self) -> np.ndarray:
        return (np.arange(self.n) + 0.5) / self.n

    @property
    def s_nodes(self) -> np.ndarray:
        return np.arange(self.n + 1) / self.n

    # --- physics (kernels in mobility, drag and activity) ------------------------------
    def node_theta(self, theta: np.ndarray, kappa: np.ndarray | None = None) -> np.ndarray:
        """Tangent angle at the joints (N+1,), interpolated from the segments
        (:func:`_joint_average`); the end segments' angles at the free ends.

        (Extrapolating the ends with theta_s = kappa, theta_0 - h kappa_0 / 2, feeds kappa_0
        back into its own activity law with gain chi h / 2 and, for chi h > 2, creates a
        spurious unstable mode, so it is not done.)"""
        return self._avg @ theta

    @property
    def _k(self):
        """The mobility kernels: compiled when numba is installed and ``compiled`` is set."""
        if self.compiled:
            return mobility.kernels()
        return mobility

    def _args(self, theta: np.ndarray) -> tuple:
        return (theta, self._avg @ theta, self._weights, self.eta_par, self.eta_perp, self.h)

    def matrix(self, theta: np.ndarray, kappa: np.ndarray | None = None) -> np.ndarray:
        """The mobility matrix G (N+2, N+2) (:func:`flutterswim.mobility.assemble`)."""
        return self._k.assemble(*self._args(theta))

    def moment(self, theta: np.ndarray, kappa: np.ndarray) -> np.ndarray:
        """Bending moment at interior joints, M_j = theta_s(s_j) - kappa_j, (N-1,)."""
        return self._diff @ theta - kappa[1:-1]

    def _load(self, theta: np.ndarray, kappa: np.ndarray) -> np.ndarray:
        b = np.zeros(self.n + 2)
        b[2 : self.n + 1] = -self.moment(theta, kappa)
        return b

    def velocities(self, y: np.ndarray) -> np.ndarray:
        """Solve the mobility problem: z = [U0x, U0y, omega] (N+2,)."""
        n = self.n
        theta, kappa = y[2 : n + 2], y[n + 2 :]
        return self._k.solve(*self._args(theta), self._load(theta, kappa))

    def rhs(self, y: np.ndarray, phi: float, sigma: float) -> np.ndarray:
        """Time derivative of the state y (2N+3,) for field direction phi and strength sigma."""
        from . import rosw

        k = rosw.kernels() if self.compiled else rosw
        y = np.ascontiguousarray(y, dtype=float)
        return k.rhs(y, *self.rhs_args(phi, sigma), np.empty_like(y))

    def rhs_args(self, phi: float, sigma: float) -> tuple:
        """The arguments after the state of the rhs kernel :func:`flutterswim.rosw.rhs`
        (for compiled loops that call it)."""
        return (self._avg, self._diff, self._weights, self.eta_par, self.eta_perp, self.chi * sigma, float(phi))

    def jacobian(self, y: np.ndarray, phi: float, sigma: float, *, exact: bool = False) -> np.ndarray:
        """Jacobian of :meth:`rhs`. By default it leaves out the change of G with theta
        (a non-stiff term that W-methods may drop); ``exact=True`` adds it,
        -G^-1 d(G z)/d theta (:func:`flutterswim.mobility.apply_theta_derivative`)."""
        from . import rosw

        k = rosw.kernels() if self.compiled else rosw
        y = np.ascontiguousarray(y, dtype=float)
        return k.jacobian(y, *self.rhs_args(phi, sigma), bool(exact), np.empty((self.size, self.size)))

    def group_derivatives(self, y: np.ndarray, phi: float, sigma: float) -> np.ndarray:
        """Derivatives of :meth:`rhs` with respect to the groups (eta_par, eta_perp, chi),
        (2N+3, 3) (:func:`flutterswim.rosw.group_derivatives`)."""
        from . import rosw

        k = rosw.kernels() if self.compiled else rosw
        y = np.ascontiguousarray(y, dtype=float)
        return k.group_derivatives(y, *self.group_args(phi, sigma), np.empty((self.size, 3)))

    def group_args(self, phi: float, sigma: float) -> tuple:
        """The arguments after the state of :func:`flutterswim.rosw.group_derivatives`."""
        return (self._avg, self._diff, self._weights, self.eta_par, self.eta_perp, float(sigma), float(phi))

    def joint_drag(self, y: np.ndarray, z: np.ndarray | None = None):
        """Weighted drag (wfx, wfy) at the joints and joint positions relative to r(0)."""
        n = self.n
        theta = y[2 : n + 2]
        if z is None:
            z = self.velocities(y)
        return self._k.joint_drag(*self._args(theta), z)

    def forces(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Internal force components A, V and bending moment M at the joints, each (N+1,)."""
        n = self.n
        theta, kappa = y[2 : n + 2], y[n + 2 :]
        wfx, wfy, _, _ = self.joint_drag(y)
        # C(s_j) = -(drag on [0, s_j]); joint j carries half its trapezoid cell on each side.
        right = np.r_[1.0, np.full(n - 1, 0.5), 0.0]  # share of w_j to the right of s_j
        cx = -(np.cumsum(wfx) - right * wfx)
        cy = -(np.cumsum(wfy) - right * wfy)
        tn = self.node_theta(theta)
        a = cx * np.cos(tn) + cy * np.sin(tn)
        v = -cx * np.sin(tn) + cy * np.cos(tn)
        return a, v, np.concatenate(([0.0], self.moment(theta, kappa), [0.0]))

    def drag_totals(self, y: np.ndarray) -> tuple[float, float, float]:
        """Total drag force (x, y) and torque about r(0) on the filament at state y."""
        wfx, wfy, xj, yj = self.joint_drag(y)
        return float(wfx.sum()), float(wfy.sum()), float(np.sum(xj * wfy - yj * wfx))


def _joint_average(n: int) -> np.ndarray:
    """(N+1, N) map from segment angles to joint angles: 4th-order interpolation
    (-1, 9, 9, -1)/16 inside, the mean of the two neighbours next to the ends, and the end
    segment's angle at a free end."""
    avg = np.zeros((n + 1, n))
    avg[0, 0] = avg[n, n - 1] = 1.0
    for j in range(1, n):
        if 2 <= j <= n - 2:
            avg[j, j - 2 : j + 2] = np.array([-1.0, 9.0, 9.0, -1.0]) / 16.0
        else:
            avg[j, j - 1 : j + 1] = 0.5
    return avg


def _joint_difference(n: int) -> np.ndarray:
    """(N-1, N) map from segment angles to theta_s at the interior joints: the staggered
    4th-order stencil (1, -27, 27, -1)/(24 h) inside, (theta_j - theta_{j-1})/h next to the
    ends. Both operators leave the scheme second order overall (boundary stencils), with
    an error constant about ten times smaller than the plain two-point stencils."""
    diff = np.zeros((n - 1, n))
    for j in range(1, n):
        if 2 <= j <= n - 2:
            diff[j - 1, j - 2 : j + 2] = np.array([1.0, -27.0, 27.0, -1.0]) * (n / 24.0)
        else:
            diff[j - 1, j - 1 : j + 1] = (-n, n)
    return diff


def centreline(r0: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint coordinates x, y (..., N+1) from r(0) (..., 2) and theta (..., N)."""
    h = 1.0 / theta.shape[-1]
    zero = np.zeros(theta.shape[:-1] + (1,))
    x = r0[..., :1] + np.concatenate((zero, h * np.cumsum(np.cos(theta), axis=-1)), axis=-1)
    y = r0[..., 1:2] + np.concatenate((zero, h * np.cumsum(np.sin(theta), axis=-1)), axis=-1)
    return x, y
