"""Eigenmodes r(s) from the kernel of the boundary matrix, bifurcation curves, animation.

R(s) = sum_i c_i exp(lambda_i (s - s_i)) with s_i = 1 if Re lambda_i > 0 else 0 (a rescaling of
the paper's basis that keeps the 4x4 boundary matrix well conditioned); c spans its kernel
(smallest singular vector). kappa(s) = -chi/(1+omega) R'(s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import ParameterError, finite, positive, positive_int
from .characteristic import quartic_roots
from .leading import leading_eigenvalue, same_root
from .newton import follow_root

__all__ = ["Eigenmode", "eigenmodes", "mode_shape", "Bifurcation", "bifurcation", "animate_mode"]


@dataclass(frozen=True)
class Eigenmode:
    """omega: eigenvalue [1/tau]; s (n,); r, kappa (n,) complex, normalised so that r = 1 where
    |r| is largest; rank: 1 for the leading mode, 2 for the second; residual: smallest singular
    value / largest of the boundary matrix (0 for an exact eigenvalue)."""

    omega: complex
    s: np.ndarray
    r: np.ndarray
    kappa: np.ndarray
    rank: int
    residual: float


def mode_shape(omega: complex, chi: float, eta_perp: float, *, n_points: int = 201, rank: int = 1) -> Eigenmode:
    """Mode shape for a given eigenvalue omega (kernel of the boundary-condition matrix)."""
    chi = finite("chi", chi)
    eta_perp = positive("eta_perp", eta_perp)
    n_points = positive_int("n_points", n_points, minimum=2)
    lam = quartic_roots(omega, chi, eta_perp)
    c = chi / (omega + 1.0)
    shift = np.where(lam.real > 0, 1.0, 0.0)
    a = lam * (lam + c)
    e0, e1 = np.exp(-lam * shift), np.exp(lam * (1.0 - shift))
    Bm = np.array([a * e0, lam * a * e0, a * e1, lam * a * e1])
    colscale = np.maximum(np.abs(Bm).max(axis=0), 1e-300)
    _, sv, vh = np.linalg.svd(Bm / colscale)
    coef = vh[-1].conj() / colscale
    s = np.linspace(0.0, 1.0, n_points)
    E = np.exp(lam[None, :] * (s[:, None] - shift[None, :]))
    r = E @ coef
    dr = E @ (coef * lam)
    k = int(np.argmax(np.abs(r)))
    norm = r[k]
    return Eigenmode(complex(omega), s, r / norm, -c * dr / norm, rank, float(sv[-1] / sv[0]))


def eigenmodes(chi: float, eta_perp: float, *, n_points: int = 201) -> tuple[Eigenmode, Eigenmode]:
    """First and second eigenmodes (largest and second largest Re omega, neutral modes excluded)."""
    le = leading_eigenvalue(chi, eta_perp)
    if chi == 0.0:
        raise ParameterError("chi=0: the leading eigenvalue -1 is a pure curvature mode; use chi != 0")
    return (mode_shape(le.omega, chi, eta_perp, n_points=n_points, rank=1),
            mode_shape(le.second, chi, eta_perp, n_points=n_points, rank=2))


@dataclass(frozen=True)
class Bifurcation:
    """Leading eigenvalue along one parameter: parameter ('chi' or 'eta_perp'), values (n,),
    omega (n,) complex [1/tau], fixed: the value of the other parameter."""

    parameter: str
    values: np.ndarray
    omega: np.ndarray
    fixed: float


#: the followed root is compared with the leading eigenvalue from scratch at every CHECK_STRIDE-th
#: value, the last, and wherever it moves by more than CHECK_JUMP (relative) from one value to the next
CHECK_STRIDE = 50
CHECK_JUMP = 0.05


def bifurcation(*, parameter: str, values, fixed: float, max_step: float = 0.1) -> Bifurcation:
    """Re/Im of omega_max vs chi (fixed eta_perp) or vs eta_perp (fixed chi), by root following
    from the leading eigenvalue at the largest value (steps refined to <= max_step).

    The followed root is checked against :func:`leading_eigenvalue` (every CHECK_STRIDE-th
    value, the last, and wherever it jumps). Where another pair leads (beyond the paper's
    region: at eta_perp = 1000 and chi ~ 12 the root followed from chi = 130 is the second),
    the values since the last good check are taken from scratch and the following restarts
    there; a lead that changes hands and back between two checks is not seen."""
    from .stability_map import _refine

    v = np.atleast_1d(np.asarray(values, dtype=float))
    if v.ndim != 1 or np.any(np.diff(v) <= 0) or not np.all(np.isfinite(v)):
        raise ParameterError("values must be a finite, strictly increasing 1-D array")
    fixed = finite("fixed", fixed)
    if parameter == "chi":
        if fixed <= 0:
            raise ParameterError(f"fixed eta_perp={fixed!r} must be > 0")
        if v[0] < 0 < v[-1] or np.any(v == 0):
            raise ParameterError("chi values must not contain or straddle 0 (use chi > 0; symmetric)")
    elif parameter == "eta_perp":
        if v[0] <= 0:
            raise ParameterError(f"eta_perp values must be > 0, got {v[0]!r}")
        if fixed == 0:
            raise ParameterError("fixed chi must be != 0")
    else:
        raise ParameterError(f"parameter={parameter!r}; choose 'chi' or 'eta_perp'")
    order = np.argsort(-np.abs(v))
    path, idx = _refine(v[order], max_step)
    if parameter == "chi":
        def leading(x):
            return leading_eigenvalue(float(x), fixed, n=48).omega

        def follow(w0, p):
            return follow_root(w0, p, fixed).omega
    else:
        def leading(x):
            return leading_eigenvalue(fixed, float(x), n=48).omega

        def follow(w0, p):
            return follow_root(w0, fixed, p).omega
    om = np.empty(v.size, dtype=complex)
    om[order] = _follow_checked(path, idx, leading, follow)
    return Bifurcation(parameter, v, om, fixed)


def _follow_checked(path: np.ndarray, idx: np.ndarray, leading, follow) -> np.ndarray:
    """The leading eigenvalue at path[idx] (idx increasing): ``follow(w0, path[k:])`` (the
    root through w0 along the path) from ``leading(path[0])``, checked against ``leading`` at
    every CHECK_STRIDE-th value, the last and wherever it jumps; from a wrong check on, the
    values since the last good check come from ``leading`` and the following restarts."""
    m = idx.size
    om = np.full(m, complex(np.nan, np.nan))
    q0, good = 0, 0
    om[0] = leading(path[idx[0]])
    while q0 < m:
        start = idx[q0]
        om[q0:] = follow(om[q0], path[start:])[idx[q0:] - start]
        wrong = None
        for q in range(q0 + 1, m):
            jump = not (abs(om[q] - om[q - 1]) <= CHECK_JUMP * max(1.0, abs(om[q - 1])))
            if (q - q0) % CHECK_STRIDE == 0 or q == m - 1 or jump:
                ref = leading(path[idx[q]])
                if not same_root(om[q], ref):
                    wrong = q
                    break
                good = q
        if wrong is None:
            break
        for q in range(good + 1, wrong + 1):
            om[q] = leading(path[idx[q]])
        q0 = good = wrong
        if q0 == m - 1:
            break
    return om


def animate_mode(mode: Eigenmode, path, *, frames: int = 40, amplitude: float = 0.15, fps: int = 20) -> None:
    """GIF of the linear travelling wave r(s, t) = amplitude Re[r(s) e^{i beta t}] over one period
    (growth removed), beta = Im omega; needs matplotlib (Agg) and pillow."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    from ..plotting._common import new_figure

    beta = mode.omega.imag if mode.omega.imag != 0 else 1.0
    t = np.linspace(0.0, 2 * np.pi / abs(beta), frames, endpoint=False)
    fig = new_figure((4, 2.4), dpi=100)
    ax = fig.subplots()
    (line,) = ax.plot(mode.s, amplitude * mode.r.real, lw=2)
    ax.set_xlim(0, 1)
    ax.set_ylim(-1.2 * amplitude, 1.2 * amplitude)
    ax.set_aspect("equal")
    ax.set_xlabel("s / l")
    ax.set_ylabel("r / l (scaled)")
    ax.set_title(f"mode {mode.rank}: omega = {mode.omega.real:.3f} + {mode.omega.imag:.3f}i (1/tau); "
                 f"amplitude {amplitude:g}", fontsize=8)

    def update(k):
        line.set_ydata(amplitude * (mode.r * np.exp(1j * beta * t[k])).real)
        return (line,)

    anim = FuncAnimation(fig, update, frames=frames, blit=True)
    anim.save(str(path), writer=PillowWriter(fps=fps))
