"""Fixed-step flow map of the shape dynamics and its exact derivative (the monodromy).

With a fixed number of steps M per period, the discrete flow map Phi(u0, T) is a smooth
function of (u0, T), so Newton's method on Phi(u0, T) = u0 converges quadratically to the
fixed point of the discrete map. The steps are those of the 3-stage Radau IIA collocation
method (order 5, L-stable and stiffly accurate, so the stiff bending modes are damped as
in the ODE, not reflected as with Gauss collocation), with stage equations solved by a
simplified Newton iteration whose step matrix comes from the exact Jacobians of the
simulator's rhs (kept from a warm start while it converges fast, re-formed when it does not;
its linear algebra, with the kappa unknowns eliminated, is in :mod:`.radau`).

Stage equations, Z_i = Y_i - u_n:  Z_i = h sum_j A_ij f(u_n + Z_j).
The derivative of the step follows from the implicit function theorem,
  P dZ/du_n = h [sum_j A_ij J_j]_i,   P_ij = delta_ij I - h A_ij J_j,  J_j = f'(Y_j),
and du_{n+1}/du_n = I + dZ_3/du_n (the last stage is the step's end). The product over the
M steps is the exact derivative of the discrete map: its trivial Floquet multiplier equals
1 up to the time-discretisation error O(h^5). The position r(0) follows by the same
quadrature, r_{n+1} = r_n + h sum_j b_j U0(Y_j).

The derivative of the end state with respect to the dimensionless groups g = (eta_par,
eta_perp, chi) follows in the same pass (``sensitivity=True``): with S_g = du_n/dg,
  P dZ/dg = h [sum_j A_ij (J_j S_g + f_g(Y_j))]_i,
one more right-hand side per group, f_g from the model
(:meth:`flutterswim.filament.Filament.group_derivatives`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import radau
from .system import ShapeSystem

__all__ = ["Flow", "flow", "RADAU_A", "RADAU_C"]

_S6 = math.sqrt(6.0)
RADAU_C = np.array([(4.0 - _S6) / 10.0, (4.0 + _S6) / 10.0, 1.0])
RADAU_A = np.array([
    [(88.0 - 7.0 * _S6) / 360.0, (296.0 - 169.0 * _S6) / 1800.0, (-2.0 + 3.0 * _S6) / 225.0],
    [(296.0 + 169.0 * _S6) / 1800.0, (88.0 + 7.0 * _S6) / 360.0, (-2.0 - 3.0 * _S6) / 225.0],
    [(16.0 - _S6) / 36.0, (16.0 + _S6) / 36.0, 1.0 / 9.0],
])
RADAU_B = RADAU_A[2]
ORDER = 5


@dataclass(frozen=True)
class Flow:
    """States at the M+1 step times (M+1, 2N+3) (position and shape), the full rhs there,
    the converged stage increments (M, 3, 2N+1) (a warm start for the next call), and the
    monodromy of the shape part (2N+1, 2N+1) or None. ``matrices``: per step, the stage
    Jacobians, the LU of the step matrix and the stage points where they were formed (reused
    by the next call that starts from this flow, as a simplified Newton iteration)."""

    t: np.ndarray
    y: np.ndarray
    f: np.ndarray
    stages: np.ndarray
    monodromy: np.ndarray | None
    matrices: tuple = field(default=(), repr=False, compare=False)
    matrix_key: tuple = field(default=(), repr=False, compare=False)  # (h, N, groups, phi) they were formed for
    #: d(end shape)/d(eta_par, eta_perp, chi) at fixed start and period, (2N+1, 3), or None
    sensitivity: np.ndarray | None = field(default=None, repr=False, compare=False)
    groups: tuple = field(default=(), repr=False, compare=False)  # (eta_par, eta_perp, chi, phi) of the system


class StepMatrices(list):
    """Per step (stage Jacobians, factors of :func:`radau.factor`, stage points they were
    formed at); :meth:`stacked` gives the factors as arrays over the steps (made once) for
    the compiled pass; :meth:`without_jacobians` keeps only what a stage iteration needs."""

    def without_jacobians(self) -> "StepMatrices":
        """The same factors without the stage Jacobians (a derivative re-forms them): for a
        warm start kept on an orbit, about half the memory."""
        return StepMatrices((None, f, y) for _, f, y in self)

    _stacked: tuple | None = None

    def stacked(self) -> tuple:
        if self._stacked is None:
            self._stacked = tuple(np.stack([f[1][k] for f in self]) for k in range(3))
            for i, (jac, _, y_lu) in enumerate(self):  # per step, views of the stacks (no second copy)
                self[i] = (jac, tuple(a[i] for a in self._stacked), y_lu)
        return self._stacked


class StepFailure(FloatingPointError):
    """A Radau step's stage equations did not converge."""


def flow(system: ShapeSystem, u0: np.ndarray, period: float, steps: int, *,
         variational: bool = False, warm: Flow | None = None, r0=(0.0, 0.0),
         stage_tol: float = 1e-13, max_iter: int = 12, derivative_tol: float = 1e-10,
         sensitivity: bool = False, keep_matrices: bool = False) -> Flow:
    """Integrate the shape from u0 over ``period`` in ``steps`` equal Radau IIA steps.

    Stage equations by a simplified Newton iteration: the step matrix P of the warm flow
    (formed at its stages) when there is one, else P formed at the explicit predictor; a
    fresh P at the current iterate when the iteration stalls. With ``variational``, the
    step's derivative uses P and the stage Jacobians at the converged stages: they are
    formed again there unless the stage points differ by less than ``derivative_tol``
    (relative) from where they were formed, so the derivative is exact to that size (Newton
    shooting needs it only to the size of its correction; the Floquet multipliers of the
    converged orbit need it exact: the default). With ``sensitivity`` (and ``variational``),
    also the end shape's derivative with respect to the groups (module docstring). With
    ``keep_matrices``, the derivative's exact step matrices are solved by LU and not kept:
    the flow keeps the (warm) matrices its stages converged with, re-formed only where that
    iteration was slow (they serve the next warm start as well; no inversions)."""
    a = RADAU_A
    h = period / steps
    u = np.array(u0, float)
    m = u.size
    r = np.array(r0, float)
    ys = np.empty((steps + 1, m + 2))
    fs = np.empty((steps + 1, m + 2))
    zs = np.empty((steps, 3, m))
    mats = []
    ys[0, :2], ys[0, 2:] = r, u
    fs[0] = system.rhs_full(ys[0])
    smat = np.eye(m) if variational else None
    fil = system.filament
    groups = (fil.eta_par, fil.eta_perp, fil.chi)
    sens = variational and sensitivity
    if sens:
        smat = np.concatenate((smat, np.zeros((m, 3))), axis=1)  # [du/du0 | du/dg]
    have_warm = warm is not None and warm.stages.shape == zs.shape
    warm_mats = have_warm and len(warm.matrices) == steps
    key = (h, system.n, fil.eta_par, fil.eta_perp, fil.chi, system.phi)  # what the matrices depend on
    # matrices of another step size or system serve the stage iteration, and an approximate
    # derivative (Newton shooting), but never a derivative asked to be exact
    stale = warm_mats and warm.matrix_key != key and derivative_tol < 1e-8

    consts = radau.constants(h, a)
    kern = radau.kernels() if system.filament.compiled else radau

    def step_matrix(z):
        yst = u + z
        jac = system.at_points(yst, "jacobian")
        return jac, radau.factor(jac, system.n, consts, kern), yst  # P = I - h (A x I) diag(J_j), reduced

    kargs = system.filament.rhs_args(system.phi, 1.0)
    if have_warm and warm_mats and not variational:  # every step matrix given: the compiled pass
        zs[:] = warm.stages
        step, status = kern.chord_pass(u, zs, *warm.matrices.stacked(), *consts, *kargs, h, RADAU_B,
                                       stage_tol, max_iter, ys, fs)
        if step < 0:
            return Flow(np.linspace(0.0, period, steps + 1), ys, fs, zs, None, warm.matrices, warm.matrix_key,
                        None, groups + (system.phi,))
        # a step needs a fresh matrix (or failed): the general loop below redoes the pass
    state = np.empty(3)
    fz = np.empty((3, m + 2))
    for step in range(steps):
        if have_warm:
            z = warm.stages[step].copy()
        else:
            z = np.outer(RADAU_C * h, fs[step, 2:])  # explicit predictor
        scale = 1.0 + np.max(np.abs(u))
        jac, lu, y_lu = warm.matrices[step] if warm_mats else step_matrix(z)
        if stale:
            y_lu = np.full_like(y_lu, np.inf)  # formed for another h or system: re-form for the derivative
        state[:] = (0.0, np.inf, max_iter)
        while True:  # the stage iteration (compiled), with a fresh matrix when it is slow
            status = kern.stages(u, z, *consts, *lu, *kargs, stage_tol * scale, state, fz)
            if status != radau.SLOW:
                break
            jac, lu, y_lu = step_matrix(z)
        if status == radau.NOT_FINITE:
            raise StepFailure(f"non-finite stage values at step {step} of {steps}")
        if status == radau.NO_CONVERGENCE:
            raise StepFailure(f"stage equations did not converge at step {step} of {steps} (h={h:.3g})")
        if variational:
            fresh = jac is None or np.max(np.abs(u + z - y_lu)) > derivative_tol * scale
            if fresh and keep_matrices:
                jd = system.at_points(u + z, "jacobian")
            else:
                if fresh:
                    jac, lu, y_lu = step_matrix(z)
                jd = jac
            # P dZ/du = h [sum_j A_ij J_j]_i at the converged stages
            if sens:  # f_g at the stages: three more columns
                jac_g = np.concatenate((jd, system.at_points(u + z, "groups")), axis=2)
                rhs = (consts[0] @ jac_g.reshape(3, -1)).reshape(3 * m, m + 3)
            else:
                rhs = (consts[0] @ jd.reshape(3, -1)).reshape(3 * m, m)
            ok = (radau.exact_solve(jd, system.n, consts, rhs, kern) if fresh and keep_matrices
                  else kern.reduced_solve(*lu, *consts, rhs) == 0)
            if not ok:
                raise StepFailure(f"singular step matrix at step {step} of {steps}")
            dz = rhs[2 * m:]
            dzdu = dz[:, :m]
            smat = smat + dzdu @ smat
            if sens:
                smat[:, m:] += dz[:, m:]
        mats.append((jac, lu, y_lu))
        # (fz is from the last iterate, within stage_tol of z: no new evaluation)
        r = r + h * (RADAU_B @ fz[:, :2])
        u = u + z[2]
        zs[step] = z
        ys[step + 1, :2], ys[step + 1, 2:] = r, u
        fs[step + 1] = fz[2]
    mono, dg = (smat[:, :m], smat[:, m:]) if sens else (smat, None)
    return Flow(np.linspace(0.0, period, steps + 1), ys, fs, zs, mono, StepMatrices(mats), key, dg, groups + (system.phi,))
