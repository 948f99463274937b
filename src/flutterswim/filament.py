"""Discrete filament: geometry, resistive-force drag and the mobility problem.

Dimensionless throughout (length by l, time by tau, forces by B/l^2).

The filament is cut into N straight segments of length h = 1/N with tangent angles
theta_i (i = 0..N-1, at the segment midpoints s_i = (i + 1/2) h). Joints j = 0..N sit
at s_j = j h, X_0 = r(0). The spontaneous curvature kappa_j lives at the joints.

State vector y = [x0, y0, theta_0..theta_{N-1}, kappa_0..kappa_N], size 2N + 3.

Mobility problem (no inertia). Unknowns z = [U0x, U0y, omega_0..omega_{N-1}] with
omega = theta_t. Joint velocities V_j = U0 + sum_{k<j} h n_k omega_k, drag density
F_j = -(eta_par t_j t_j + eta_perp n_j n_j) V_j (eq. MOD:eq:d_RRFT) with the joint tangent
angle (mean of its segments), integrated by the trapezoidal rule, weights w_j.
(Sampling the drag at segment midpoints instead leaves a zig-zag null mode.)
Equations, G z = b:
  sum_j w_j F_j = 0                                         (2 rows)
  M_j + sum_{k<j} w_k (X_k - X_j) x F_k = 0,  j = 1..N-1    (moment balance at each cut)
  sum_k w_k (X_k - X_N) x F_k = 0                           (total torque)
with the bending moment M_j = theta_s(s_j) - kappa_j (eq. MOD:eq:bending_moment_constitutive)
and M_0 = M_N = 0 (free ends). theta_s and the joint angles use 4th-order staggered stencils
inside and 2-point stencils next to the ends (:func:`_joint_difference`, :func:`_joint_average`).
Activity (eq. MOD:eq:nondim_EVO with the field direction phi and strength sigma):
  kappa_t = -kappa - chi sigma sin(theta_node - phi).
The scheme is second order in h.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from . import _mobility_kernel as _kernel

__all__ = ["Filament", "centreline"]


@dataclass(frozen=True)
class Filament:
    """Set-up of the discrete filament: resolution, drag groups and cached masks."""

    n: int
    eta_par: float
    eta_perp: float
    chi: float
    compiled: bool = True
    _strict: np.ndarray = field(init=False, repr=False, compare=False)
    _weights: np.ndarray = field(init=False, repr=False, compare=False)
    _avg: np.ndarray = field(init=False, repr=False, compare=False)
    _diff: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        n = self.n
        object.__setattr__(self, "_strict", np.tril(np.ones((n + 1, n)), -1))
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

    # --- kernels ------------------------------------------------------------
    def node_theta(self, theta: np.ndarray, kappa: np.ndarray) -> np.ndarray:
        """Tangent angle at the joints (N+1,), interpolated from the segments
        (:func:`_joint_average`); the end segments' angles at the free ends.

        (Extrapolating the ends with theta_s = kappa, theta_0 - h kappa_0 / 2, feeds kappa_0
        back into its own activity law with gain chi h / 2 and, for chi h > 2, creates a
        spurious unstable mode, so it is not done.)"""
        return self._avg @ theta

    def mobility(self, theta: np.ndarray, kappa: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mobility matrix G (N+2, N+2) and the weighted drag maps Fx, Fy (N+1, N+2).

        ``Fx @ z`` is w_j F_j at each joint (trapezoidal weights w_j).
        """
        h, n = self.h, self.n
        c, s = np.cos(theta), np.sin(theta)
        tn = self.node_theta(theta, kappa)
        cn, sn = np.cos(tn), np.sin(tn)
        vx = np.zeros((n + 1, n + 2))
        vy = np.zeros((n + 1, n + 2))
        vx[:, 0] = 1.0
        vy[:, 1] = 1.0
        vx[:, 2:] = -h * self._strict * s
        vy[:, 2:] = h * self._strict * c
        dp, dn = self.eta_par, self.eta_perp
        w = self._weights
        rxx = w * (dp * cn * cn + dn * sn * sn)
        ryy = w * (dp * sn * sn + dn * cn * cn)
        rxy = w * ((dp - dn) * cn * sn)
        fx = -(rxx[:, None] * vx + rxy[:, None] * vy)
        fy = -(rxy[:, None] * vx + ryy[:, None] * vy)
        xj = np.concatenate(([0.0], h * np.cumsum(c)))
        yj = np.concatenate(([0.0], h * np.cumsum(s)))
        # Torque about X_j of the drag on joints k < j, by cumulative sums: O(N^2).
        sx = np.cumsum(fx, axis=0)[:-1]
        sy = np.cumsum(fy, axis=0)[:-1]
        p = np.cumsum(xj[:, None] * fy - yj[:, None] * fx, axis=0)[:-1]
        g = np.empty((n + 2, n + 2))
        g[0] = sx[-1] + fx[-1]
        g[1] = sy[-1] + fy[-1]
        g[2:] = p - xj[1:, None] * sy + yj[1:, None] * sx
        return g, fx, fy

    def matrix(self, theta: np.ndarray, kappa: np.ndarray) -> np.ndarray:
        """The mobility matrix G alone: compiled assembly when numba is available."""
        k = self._kernels
        if k:
            return k["assemble"](theta, self.node_theta(theta, kappa), self._weights,
                                 self.eta_par, self.eta_perp, self.h)
        return self.mobility(theta, kappa)[0]

    @property
    def _kernels(self) -> dict:
        return _kernel.kernels() if self.compiled else {}

    def moment(self, theta: np.ndarray, kappa: np.ndarray) -> np.ndarray:
        """Bending moment at interior joints, M_j = theta_s(s_j) - kappa_j, (N-1,)."""
        return self._diff @ theta - kappa[1:-1]

    def velocities(self, y: np.ndarray) -> np.ndarray:
        """Solve the mobility problem: z = [U0x, U0y, omega] (N+2,)."""
        n = self.n
        theta, kappa = y[2 : n + 2], y[n + 2 :]
        b = np.zeros(n + 2)
        b[2 : n + 1] = -self.moment(theta, kappa)
        k = self._kernels
        if k:
            return k["solve"](theta, self._avg @ theta, self._weights, self.eta_par, self.eta_perp,
                              self.h, b)
        return np.linalg.solve(self.matrix(theta, kappa), b)

    def rhs(self, y: np.ndarray, phi: float, sigma: float) -> np.ndarray:
        """Time derivative of the state y (2N+3,) for field direction phi and strength sigma."""
        n = self.n
        dy = np.empty_like(y)
        dy[: n + 2] = self.velocities(y)
        theta, kappa = y[2 : n + 2], y[n + 2 :]
        dy[n + 2 :] = -kappa - (self.chi * sigma) * np.sin(self.node_theta(theta, kappa) - phi)
        return dy

    def jacobian(self, y: np.ndarray, phi: float, sigma: float) -> np.ndarray:
        """Jacobian of rhs, exact except for the (non-stiff) change of G with theta."""
        n = self.n
        theta, kappa = y[2 : n + 2], y[n + 2 :]
        k = self._kernels
        if k:
            ginv = k["inverse"](theta, self._avg @ theta, self._weights, self.eta_par,
                                self.eta_perp, self.h)
        else:
            ginv = sla.inv(self.matrix(theta, kappa), check_finite=False)
        ginv_m = ginv[:, 2 : n + 1]  # dz/d(-M)
        jac = np.zeros((self.size, self.size))
        jac[: n + 2, 2 : n + 2] = -ginv_m @ self._diff
        jac[: n + 2, n + 3 : 2 * n + 2] = ginv_m
        cosv = np.cos(self.node_theta(theta, kappa) - phi) * (-self.chi * sigma)
        jac[n + 2 :, 2 : n + 2] = cosv[:, None] * self._avg
        k = np.arange(n + 2, 2 * n + 3)
        jac[k, k] = -1.0
        return jac

    def forces(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Internal force components A, V and bending moment M at the joints, each (N+1,)."""
        n = self.n
        theta, kappa = y[2 : n + 2], y[n + 2 :]
        g, fx, fy = self.mobility(theta, kappa)
        b = np.zeros(n + 2)
        mom = self.moment(theta, kappa)
        b[2 : n + 1] = -mom
        z = np.linalg.solve(g, b)
        # C(s_j) = -(drag on [0, s_j]); joint j carries half its trapezoid cell on each side.
        wfx, wfy = fx @ z, fy @ z
        right = np.r_[1.0, np.full(n - 1, 0.5), 0.0]  # share of w_j to the right of s_j
        cx = -(np.cumsum(wfx) - right * wfx)
        cy = -(np.cumsum(wfy) - right * wfy)
        tn = self.node_theta(theta, kappa)
        a = cx * np.cos(tn) + cy * np.sin(tn)
        v = -cx * np.sin(tn) + cy * np.cos(tn)
        return a, v, np.concatenate(([0.0], mom, [0.0]))

    def drag_totals(self, y: np.ndarray) -> tuple[float, float, float]:
        """Total drag force (x, y) and torque about r(0) on the filament at state y."""
        n = self.n
        theta, kappa = y[2 : n + 2], y[n + 2 :]
        g, fx, fy = self.mobility(theta, kappa)
        z = np.linalg.solve(g, np.r_[0.0, 0.0, -self.moment(theta, kappa), 0.0])
        fxs, fys = fx @ z, fy @ z
        xj, yj = centreline(np.zeros(2), theta)
        return float(fxs.sum()), float(fys.sum()), float(np.sum(xj * fys - yj * fxs))


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
