"""The compiled Rosenbrock-W loop against the Python-stepped one, and its structured algebra."""

from __future__ import annotations

import numpy as np
import pytest

import flutterswim as fs
from flutterswim import mobility, rosw
from flutterswim.filament import Filament
from flutterswim.initial import InitialState
from flutterswim.integrators import integrate, integrate_filament

G = fs.PAPER.groups


def _state(n: int) -> np.ndarray:
    y = InitialState(theta=lambda s: 0.3 + 0.4 * np.sin(3.0 * s), kappa=lambda s: 2.0 * s - 0.5).state(n)
    return y


def test_compiled_ros34pw2_without_reuse_takes_the_python_steps():
    """Same method (ROS34PW2, fresh J every step), two implementations: the Hairer form with
    a (2N+3)-square LU in Python and the transformed form with the structured (N+2)-square
    W solve, compiled. They must take the same steps and agree far below the tolerance."""
    n = 16
    fil = Filament(n, G.eta_par, G.eta_perp, G.chi)
    y0 = _state(n)
    te = np.linspace(0.0, 1.0, 11)
    a = integrate_filament(fil, [(0.0, 0.2, 1.0)], 1.0, y0, te, method="ros34pw2", rtol=1e-6, atol=1e-8,
                           reuse=False)
    b = integrate(lambda t, y: fil.rhs(y, 0.2, 1.0), lambda t, y: fil.jacobian(y, 0.2, 1.0), (0.0, 1.0), y0, te,
                  method="ros34pw2-wave1", rtol=1e-6, atol=1e-8, time_dependent=False)
    assert a.stats.n_steps == b.stats.n_steps and a.stats.n_rejected == b.stats.n_rejected
    assert np.max(np.abs(a.y - b.y)) < 1e-9


def test_structured_solves_match_dense_algebra():
    rng = np.random.default_rng(3)
    k = rosw.kernels()
    for n in (6, 17, 48):
        fil = Filament(n, G.eta_par, G.eta_perp, G.chi)
        y = _state(n)
        y[n + 2 :] += rng.normal(size=n + 1)
        th = y[2 : n + 2]
        args = fil._args(th)
        b = rng.normal(size=n + 2)
        z = mobility.kernels().solve(*args, b)
        gm = mobility.kernels().assemble(*args)
        assert np.max(np.abs(gm @ z - b)) < 1e-9 * np.max(np.abs(gm)) * np.max(np.abs(z))
        # (I - c J) x = r with the W-Jacobian, against a dense solve
        c = 0.013
        lu, piv = np.zeros((n + 2, n + 2)), np.zeros(n + 2, dtype=np.int64)
        g0, s0 = np.zeros((n + 2, n + 2)), np.zeros(n + 1)
        assert k.w_factor(y, c, fil._avg, fil._diff, fil._weights, G.eta_par, G.eta_perp, G.chi, 0.4, lu, piv, g0, s0)
        r = rng.normal(size=y.size)
        x = k.w_solve(r, c, fil._avg, lu, piv, g0, s0, np.empty_like(y))
        dense = np.linalg.solve(np.eye(y.size) - c * fil.jacobian(y, 0.4, 1.0), r)
        assert np.max(np.abs(x - dense)) < 1e-9 * np.max(np.abs(dense))


@pytest.mark.parametrize("method", ["ros34pw2", "ndf"])
def test_a_hopelessly_stiff_run_says_so_early_on_both_compiled_paths(method):
    """chi 1e9 times the paper's: both compiled integrators stop with "too stiff" a tenth of
    the way to max_steps (the Rosenbrock path ran on to max_steps: ten times the work), and a
    run with room to finish does finish with the same max_steps."""
    n = 12
    y0 = _state(n)
    te = np.linspace(0.0, 1.0, 3)
    stiff = Filament(n, G.eta_par, G.eta_perp, G.chi * 1e9)
    sol = integrate_filament(stiff, [(0.0, 0.2, 1.0)], 1.0, y0, te, method=method, max_steps=20_000)
    assert sol.status == "failed" and "too stiff" in sol.message
    assert 2_000 <= sol.stats.n_steps + sol.stats.n_rejected < 4_000
    fine = integrate_filament(Filament(n, G.eta_par, G.eta_perp, G.chi), [(0.0, 0.2, 1.0)], 1.0, y0, te,
                              method=method, max_steps=20_000)
    assert fine.status == "completed"


def test_the_rosenbrock_path_returns_to_python_without_changing_a_step():
    """The compiled Rosenbrock loop comes back every max_steps/100 steps (at least 1000) for the
    "too stiff" check: a run of 9000 steps in chunks of 1000 is bit-identical to one in a
    single call."""
    n = 12
    fil = Filament(n, G.eta_par, G.eta_perp, G.chi)
    y0, te = _state(n), np.linspace(0.0, 20.0, 5)
    a = integrate_filament(fil, [(0.0, 0.2, 1.0)], 20.0, y0, te, method="ros34pw2", max_steps=12_000, rtol=1e-8,
                           atol=1e-10)
    b = integrate_filament(fil, [(0.0, 0.2, 1.0)], 20.0, y0, te, method="ros34pw2", rtol=1e-8, atol=1e-10)
    assert a.status == b.status == "completed" and a.stats.n_steps == b.stats.n_steps > 2_000
    assert np.array_equal(a.y, b.y)
