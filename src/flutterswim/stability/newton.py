"""Newton iteration on the reduced characteristic function, and root following.

Solves g(omega; chi, eta_perp) = 0 (see :mod:`.characteristic`), whose zeros are the
eigenvalues omega of the linearised problem other than the neutral omega = 0 pair.
Backends: ``"numba"`` (compiled scalar kernels, parallel over points) and ``"numpy"``
(batched: companion-matrix roots by np.linalg.eigvals, one array operation per iteration).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import ParameterError, positive, positive_int
from . import _kernels
from .characteristic import reduced_char

__all__ = ["RootResult", "PathResult", "newton_root", "follow_root", "resolve_backend"]


def resolve_backend(backend: str) -> str:
    """Map ``"auto"`` to ``"numba"`` if numba is importable, else ``"numpy"``; check the name."""
    if backend == "auto":
        return "numba" if _kernels.HAVE_NUMBA else "numpy"
    if backend not in ("numba", "numpy"):
        raise ParameterError(f"backend={backend!r} is unknown; choose 'auto', 'numba' or 'numpy'")
    if backend == "numba" and not _kernels.HAVE_NUMBA:
        raise ParameterError("backend='numba' requested but numba is not installed; use 'numpy'")
    return backend


@dataclass(frozen=True)
class RootResult:
    """Newton result. omega: roots (broadcast shape of the inputs), complex, units 1/tau;
    iterations: Newton steps taken (-1 where not converged); converged: bool array."""

    omega: np.ndarray
    iterations: np.ndarray

    @property
    def converged(self) -> np.ndarray:
        return self.iterations >= 0


@dataclass(frozen=True)
class PathResult:
    """Root followed along a parameter path. omega, chi, eta_perp, iterations: shape (n,).
    Roots are reported with Im >= 0 (the conjugate is also a root)."""

    omega: np.ndarray
    chi: np.ndarray
    eta_perp: np.ndarray
    iterations: np.ndarray

    @property
    def converged(self) -> np.ndarray:
        return self.iterations >= 0


def _check_eta(eta: np.ndarray) -> None:
    if not np.all(np.isfinite(eta)) or np.any(eta <= 0):
        bad = eta[~(np.isfinite(eta) & (eta > 0))].ravel()[0]
        raise ParameterError(f"eta_perp={bad!r} must be finite and > 0 (eta_perp = 0 has no drag)")


def _newton_numpy(w0, chi, eta, tol, maxit):
    """Batched Newton (all points at once, converged points frozen)."""
    w = np.array(w0, dtype=complex).ravel()
    chi = np.asarray(chi, dtype=float).ravel()
    eta = np.asarray(eta, dtype=float).ravel()
    it = np.full(w.shape, -1, dtype=np.int64)
    active = np.isfinite(w) & (w != -1.0)
    for k in range(maxit):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        with np.errstate(all="ignore"):
            g, dg, _ = reduced_char(w[idx], chi[idx], eta[idx], derivative=True, scaled=True)
            step = -g / dg
            lim = 0.5 * np.abs(w[idx] + 1.0)
            big = np.abs(step) > lim
            step[big] *= lim[big] / np.abs(step[big])
        bad = ~np.isfinite(step)
        w[idx] = w[idx] + np.where(bad, 0.0, step)
        done = ~bad & (np.abs(step) <= tol * np.maximum(np.abs(w[idx]), 1.0))
        it[idx[done]] = k + 1
        active[idx[done | bad]] = False
    return w, it


def newton_root(guess, chi, eta_perp, *, tol: float = 1e-12, maxit: int = 50, backend: str = "auto") -> RootResult:
    """Newton on g(omega; chi, eta_perp) = 0 from ``guess``; inputs broadcast, vectorised.

    Stops when |step| <= tol max(|omega|, 1). ``omega`` in units of 1/tau.
    """
    backend = resolve_backend(backend)
    tol = positive("tol", tol)
    maxit = positive_int("maxit", maxit)
    w0, ch, et = np.broadcast_arrays(np.asarray(guess, dtype=complex), np.asarray(chi, dtype=float),
                                     np.asarray(eta_perp, dtype=float))
    _check_eta(et)
    shape = w0.shape
    if backend == "numba":
        w0f = np.ascontiguousarray(w0.ravel())
        out = np.empty_like(w0f)
        it = np.empty(w0f.shape, dtype=np.int64)
        kern = _kernels._newton_serial if w0f.size < 512 else _kernels._newton_batch
        kern(w0f, np.ascontiguousarray(ch.ravel()), np.ascontiguousarray(et.ravel()), tol, maxit, out, it)
    else:
        out, it = _newton_numpy(w0, ch, et, tol, maxit)
    return RootResult(out.reshape(shape), it.reshape(shape))


def _follow_numpy(etas, chis, w0, tol, maxit):
    n = etas.size
    out = np.empty(n, dtype=complex)
    its = np.empty(n, dtype=np.int64)
    w1 = w2 = complex(w0)
    for k in range(n):
        guess = w1
        if k >= 2:
            dp1 = abs(etas[k] - etas[k - 1]) + abs(chis[k] - chis[k - 1])
            dp0 = abs(etas[k - 1] - etas[k - 2]) + abs(chis[k - 1] - chis[k - 2])
            if dp0 > 0:
                guess = w1 + (w1 - w2) * dp1 / dp0
        w, it = _newton_numpy([guess], [chis[k]], [etas[k]], tol, maxit)
        w, it = complex(w[0]), int(it[0])
        if it < 0:
            out[k], its[k] = np.nan, -1
            continue
        w = complex(w.real, abs(w.imag))
        out[k], its[k] = w, it
        w2 = w1 if k > 0 else w
        w1 = w
    return out, its


def follow_root(omega0: complex, chi, eta_perp, *, tol: float = 1e-12, maxit: int = 50,
                backend: str = "auto") -> PathResult:
    """Follow the root through omega0 along the path (chi[k], eta_perp[k]) (paper's algorithm).

    omega0 must be (close to) a root at the first path point. Each point is solved by Newton
    from a linear extrapolation of the two previous roots; on failure the step is split into
    16 substeps. Path arrays broadcast to shape (n,).
    """
    backend = resolve_backend(backend)
    ch, et = np.broadcast_arrays(np.atleast_1d(np.asarray(chi, dtype=float)),
                                 np.atleast_1d(np.asarray(eta_perp, dtype=float)))
    if ch.ndim != 1:
        raise ParameterError(f"chi and eta_perp must broadcast to a 1-D path, got shape {ch.shape}")
    _check_eta(et)
    ch = np.ascontiguousarray(ch)
    et = np.ascontiguousarray(et)
    if backend == "numba":
        out = np.empty(ch.size, dtype=complex)
        its = np.empty(ch.size, dtype=np.int64)
        _kernels._follow(et, ch, complex(omega0), float(tol), int(maxit), out, its)
    else:
        out, its = _follow_numpy(et, ch, omega0, tol, maxit)
    return PathResult(out, ch.copy(), et.copy(), its)
