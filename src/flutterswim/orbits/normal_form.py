"""The Hopf normal form: the first Lyapunov coefficient from the discrete model.

Kuznetsov, Elements of Applied Bifurcation Theory, eq. (3.20) and section 5.4 (projection
formula for n-dimensional systems): with A q = i w q, A^T p = -i w p, <p, q> = conj(p).q = 1,

  c1 = 1/2 <p, C(q,q,conj q)> - <p, B(q, A^-1 B(q, conj q))> + 1/2 <p, B(conj q, (2iw - A)^-1 B(q,q))>,
  l1 = Re(c1) / w,

where B and C are the second and third derivatives of the simulator's rhs at the straight
state. They are evaluated here by central differences of the rhs along real directions
(with polarisation for mixed and complex arguments) and Richardson extrapolation in the
step: a clearly defined numerical reduction, exact up to O(eps^4).

A is singular here: the straight state lies on the family of bent equilibria. The kernel is
odd under the mirror theta -> -theta, kappa -> -kappa, while B(q, conj q) is even, so
A^-1 B(q, conj q) is taken as the least-squares solution; its kernel part would drop out of
<p, B(q, .)> by the same symmetry.

Near the Hopf point the stroke's complex amplitude z (x = x0 + z q + c.c.) obeys
dz/dt = (i w + g' d) z + c1 |z|^2 z, with g' = d Re(lambda)/d(parameter) and d the distance
to the Hopf point: the branch has |z|^2 = -g' d / Re(c1), so 2 |first Fourier coefficient
of the shape| = 2|z| (q of unit norm) obeys (2|z|)^2 = -4 g' d / Re(c1). The orbit's
``amplitude`` is that over sqrt(2N + 1) (the RMS over the 2N + 1 shape components, which does
not grow with N): amplitude^2 = -4 g' d / (Re(c1) (2N + 1)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import ParameterError
from .linear import HopfPoint
from .system import ShapeSystem

__all__ = ["NormalForm", "normal_form"]


@dataclass(frozen=True)
class NormalForm:
    """c1 and l1 = Re(c1)/omega; ``amplitude2_slope`` = d((2|z|)^2)/d(parameter) on the
    branch, for the amplitude 2|z| along the unit eigenvector q (it scales like N, as c1's
    1/N); ``amplitude2_slope_rms`` = amplitude2_slope / (2N + 1), the slope of the orbits'
    ``amplitude``^2 (:attr:`PeriodicOrbit.amplitude`, whose scale is independent of N; the slope converges with N at order 2, 23.7, 20.9, 20.1 at N = 24, 48, 96 for Groups(70, 120, chi)); ``supercritical`` if l1 < 0: the branch exists on the side where the straight state is unstable, and its small orbits are stable within the plane of the Hopf pair. That alone does not make them stable: the straight state also has a neutral real mode (the family of bent equilibria, eigenvalue 0), whose Floquet multiplier, 1 at the Hopf point, moves with the amplitude either way. Where eta_perp < eta_par (eta_par = 41.5, chi = 70.7) it rises above 1 (1.06 on the first orbit, up to 2.9) although l1 < 0; the orbits' multipliers (:attr:`PeriodicOrbit.stable`) decide.
    c1 and l1 are for q of unit Euclidean norm over the 2N + 1 shape components, so they scale
    like 1/N (N l1 converges: -6.05e-5, -3.24e-5, -1.66e-5 at N = 24, 48, 96 at the paper's
    point); their sign is the model's, and the amplitude law does not depend on it."""

    c1: complex
    lyapunov_coefficient: float
    amplitude2_slope: float
    supercritical: bool
    direction: int  # +1: the branch exists for parameter values above the Hopf point
    amplitude2_slope_rms: float


def _b(f, v: np.ndarray, eps: float) -> np.ndarray:
    """B(v, v) by central differences, Richardson-extrapolated (f(0) = 0)."""
    def d2(e):
        return (f(e * v) + f(-e * v)) / (e * e)
    return (4 * d2(eps / 2) - d2(eps)) / 3


def _c(f, v: np.ndarray, eps: float) -> np.ndarray:
    """C(v, v, v) by central differences, Richardson-extrapolated."""
    def d3(e):
        return (f(2 * e * v) - 2 * f(e * v) + 2 * f(-e * v) - f(-2 * e * v)) / (2 * e**3)
    return (4 * d3(eps / 2) - d3(eps)) / 3


def _bilinear(f, x: np.ndarray, y: np.ndarray, eps: float) -> np.ndarray:
    """B(x, y) for real x, y by polarisation."""
    return (_b(f, x + y, eps) - _b(f, x - y, eps)) / 4


def _bc(f, x: np.ndarray, y: np.ndarray, eps: float) -> np.ndarray:
    """B(x, y) for complex x, y (bilinear, not sesquilinear)."""
    xr, xi, yr, yi = x.real, x.imag, y.real, y.imag
    return (_bilinear(f, xr, yr, eps) - _bilinear(f, xi, yi, eps)
            + 1j * (_bilinear(f, xr, yi, eps) + _bilinear(f, xi, yr, eps)))


def normal_form(hopf: HopfPoint, *, eps_b: float = 1e-3, eps_c: float = 1e-2) -> NormalForm:
    """First Lyapunov coefficient at ``hopf`` (see the module docstring)."""
    if not isinstance(hopf, HopfPoint):
        raise ParameterError(f"hopf={hopf!r} must be a HopfPoint (from flutterswim.orbits.hopf_point)")
    sysm = ShapeSystem.of(hopf.params, hopf.n_segments)
    x0 = sysm.straight()
    f0 = sysm.f(x0)

    def f(v):
        return sysm.f(x0 + v) - f0

    q, p, a, w = hopf.q, hopf.p, hopf.jacobian, hopf.omega
    qr, qi = q.real, q.imag
    b_qqbar = _b(f, qr, eps_b) + _b(f, qi, eps_b)
    b_qq = _bc(f, q, q, eps_b)
    # C(q, q, conj q) = C(qr,qr,qr) + C(qr,qi,qi) + i (C(qr,qr,qi) + C(qi,qi,qi))
    c_r, c_i = _c(f, qr, eps_c), _c(f, qi, eps_c)
    c_p, c_m = _c(f, qr + qi, eps_c), _c(f, qr - qi, eps_c)
    c_aab = (c_p - c_m - 2 * c_i) / 6  # C(qr, qr, qi)
    c_abb = (c_p + c_m - 2 * c_r) / 6  # C(qr, qi, qi)
    c_qqq = c_r + c_abb + 1j * (c_aab + c_i)
    h11 = np.linalg.lstsq(a, b_qqbar, rcond=None)[0]
    h20 = np.linalg.solve(2j * w * np.eye(a.shape[0]) - a, b_qq)
    c1 = (0.5 * np.vdot(p, c_qqq) - np.vdot(p, _bc(f, q, h11.astype(complex), eps_b))
          + 0.5 * np.vdot(p, _bc(f, np.conj(q), h20, eps_b)))
    l1 = float(c1.real / w)
    slope = float(-4 * hopf.growth_slope / c1.real)
    direction = 1 if slope > 0 else -1
    return NormalForm(complex(c1), l1, abs(slope), l1 < 0, direction, abs(slope) / q.size)
