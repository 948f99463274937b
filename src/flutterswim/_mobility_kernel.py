"""Compiled assembly and solution of the mobility problem (numba): the same maths as
:meth:`flutterswim.filament.Filament.mobility`, in O(N^2) loops without temporaries.

Used by the filament when numba is installed (extra ``fast``); the tests check that it
agrees with the numpy assembly. ``benchmarks/bench_simulate.py`` measures what it saves.
"""

from __future__ import annotations

import numpy as np

_KERNELS: dict[str, object] = {}
_assemble_nb = None  # the compiled _assemble, a global the compiled solvers call


def kernels() -> dict[str, object]:
    """The compiled kernels {"assemble", "solve", "inverse"}, compiled (or loaded from
    numba's cache) on first use; empty if numba is not installed. Importing numba costs
    tens of MB, so it is not done before a simulation needs it."""
    if not _KERNELS:
        try:
            from numba import njit
        except ImportError:  # pragma: no cover - the numpy path is used instead
            _KERNELS["missing"] = True
            return {}
        global _assemble_nb
        _assemble_nb = njit(cache=True)(_assemble)
        _KERNELS["assemble"] = _assemble_nb
        _KERNELS["solve"] = njit(cache=True)(_solve)
        _KERNELS["inverse"] = njit(cache=True)(_inverse)
    return {} if "missing" in _KERNELS else _KERNELS


def _solve(theta, tn, weights, eta_par, eta_perp, h, b):  # pragma: no cover - compiled
    return np.linalg.solve(_assemble_nb(theta, tn, weights, eta_par, eta_perp, h), b)


def _inverse(theta, tn, weights, eta_par, eta_perp, h):  # pragma: no cover - compiled
    return np.linalg.inv(_assemble_nb(theta, tn, weights, eta_par, eta_perp, h))


def _assemble(theta, tn, weights, eta_par, eta_perp, h):  # pragma: no cover - compiled
    n = theta.size
    m = n + 2
    c = np.cos(theta)
    s = np.sin(theta)
    g = np.zeros((m, m))
    sx = np.zeros(m)  # sum_{k<j} w F_x,k as a row over z
    sy = np.zeros(m)
    p = np.zeros(m)  # sum_{k<j} (X_k x w F_k)
    fx = np.zeros(m)
    fy = np.zeros(m)
    xk = 0.0
    yk = 0.0
    for k in range(n + 1):
        cn = np.cos(tn[k])
        sn = np.sin(tn[k])
        w = weights[k]
        rxx = w * (eta_par * cn * cn + eta_perp * sn * sn)
        ryy = w * (eta_par * sn * sn + eta_perp * cn * cn)
        rxy = w * ((eta_par - eta_perp) * cn * sn)
        if k > 0:
            # torque row of the cut at joint k, from joints before it
            for q in range(m):
                g[1 + k, q] = p[q] - xk * sy[q] + yk * sx[q]
        fx[0] = -rxx
        fx[1] = -rxy
        fy[0] = -rxy
        fy[1] = -ryy
        for q in range(k):
            vx = -h * s[q]
            vy = h * c[q]
            fx[2 + q] = -(rxx * vx + rxy * vy)
            fy[2 + q] = -(rxy * vx + ryy * vy)
        for q in range(k + 2):
            sx[q] += fx[q]
            sy[q] += fy[q]
            p[q] += xk * fy[q] - yk * fx[q]
        if k < n:
            xk += h * c[k]
            yk += h * s[k]
    for q in range(m):
        g[0, q] = sx[q]
        g[1, q] = sy[q]
    return g
