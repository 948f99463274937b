"""A periodic orbit from a neighbouring one: the parameter sensitivity of the flow, the
first-order predictor with the neighbour's monodromy as chord, and the compiled stage solve."""

import pickle

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.orbits import periodic_orbit
from flutterswim.orbits.periodic import solve_orbit
from flutterswim.orbits.shooting import flow
from flutterswim.orbits.system import ShapeSystem
from flutterswim.params import Groups

N = 12
STEPS = 24


@pytest.fixture(scope="module")
def base():
    return periodic_orbit(fs.PAPER.groups, n_segments=N, steps=STEPS)


def test_flow_sensitivity_matches_differences_of_flows(base):
    """d(end shape)/d(groups) of the discrete flow against central differences of whole
    flows: the differences converge to it at second order."""
    g = np.array([fs.PAPER.groups.eta_par, fs.PAPER.groups.eta_perp, fs.PAPER.groups.chi])
    system = ShapeSystem.of(Groups(*g), N)
    u, T = base.u0, base.period_dimensionless
    fl = flow(system, u, T, STEPS, variational=True, sensitivity=True)
    assert fl.sensitivity.shape == (u.size, 3)
    plain = flow(system, u, T, STEPS, variational=True)
    assert np.abs(plain.monodromy - fl.monodromy).max() < 1e-9 * np.abs(fl.monodromy).max()

    def fd(rel):
        out = np.empty((u.size, 3))
        for k in range(3):
            d = np.zeros(3)
            d[k] = rel * g[k]
            ends = [flow(ShapeSystem.of(Groups(*(g + sgn * d)), N), u, T, STEPS).y[-1, 2:] for sgn in (1, -1)]
            out[:, k] = (ends[0] - ends[1]) / (2 * d[k])
        return out

    e1, e2 = (np.abs(fd(r) - fl.sensitivity).max(axis=0) / np.abs(fl.sensitivity).max(axis=0) for r in (2e-2, 1e-2))
    assert np.all(e1 < 1e-2)
    assert np.all((3.0 < e1 / e2) & (e1 / e2 < 5.0))


@pytest.mark.parametrize("change", [{"kappa_E": 1.02}, {"B": 0.97}, {"kappa_E": 0.99, "tau": 1.01}])
def test_orbit_from_a_neighbour_equals_the_orbit_from_scratch(base, change, monkeypatch):
    """The predictor + chord path (warm start kept on the neighbour: one derivative pass,
    the last) and Newton without the warm start land on the same orbit: period, advance and
    multipliers."""
    from flutterswim.orbits import periodic

    params = fs.PAPER.replace(**{k: getattr(fs.PAPER, k) * v for k, v in change.items()})
    assert base.warm_start is not None and base.warm_start.sensitivity is not None
    passes = []

    def counted(*args, **kwargs):
        passes.append(bool(kwargs.get("variational")))
        return flow(*args, **kwargs)

    monkeypatch.setattr(periodic, "flow", counted)
    near = periodic_orbit(params, base, n_segments=N, steps=STEPS)
    assert passes[-1] and sum(passes) == 1
    monkeypatch.undo()
    cold = periodic_orbit(params, base.compact(), n_segments=N, steps=STEPS)  # Newton, no warm start
    assert near.residual < 1e-10 and cold.residual < 1e-10
    assert abs(near.period / cold.period - 1) < 1e-9
    assert abs(near.advance / cold.advance - 1) < 1e-8
    assert near.trivial_multiplier_error < 1e-8
    lead = lambda o: np.sort(np.abs(o.multipliers))[::-1][:4]  # noqa: E731
    assert np.abs(lead(near) - lead(cold)).max() < 1e-7


def test_warm_start_is_not_pickled_and_compact_drops_it(base):
    again = pickle.loads(pickle.dumps(base))
    assert again.warm_start is None and base.warm_start is not None
    assert again.period == base.period and np.array_equal(again.theta, base.theta)
    assert base.compact().warm_start is None


@pytest.mark.parametrize("columns", [1, 7])
def test_reduced_step_solve_equals_the_full_step_matrix_solve(columns):
    """The kappa elimination (radau.factor + reduced_solve) against a dense solve of the
    full step matrix P = I - h (A x I) diag(J_j), for Jacobians with the model's kappa
    block -I; a Jacobian without it is refused."""
    from flutterswim.orbits import radau
    from flutterswim.orbits.shooting import RADAU_A

    k = radau.kernels()
    rng = np.random.default_rng(columns)
    n, h = 9, 0.04
    m = 2 * n + 1
    jac = rng.normal(scale=20.0, size=(3, m, m))
    jac[:, n:, n:] = -np.eye(n + 1)
    consts = radau.constants(h, RADAU_A)
    p = np.eye(3 * m) - (h * RADAU_A)[:, None, :, None].repeat(m, 1).repeat(m, 3).reshape(3 * m, 3 * m) * \
        np.tile(np.concatenate(list(jac), axis=1), (3, 1))
    r = rng.normal(size=(3 * m, columns))
    x = r.copy()
    assert k.reduced_solve(*radau.factor(jac, n, consts), *consts, x) == 0
    assert np.abs(x - np.linalg.solve(p, r)).max() < 1e-11 * np.abs(x).max()
    jac[1, n + 2, n + 3] = 0.5
    with pytest.raises(ValueError, match="kappa block"):
        radau.factor(jac, n, consts)


def test_solve_orbit_rejects_a_warm_start_from_another_field_direction(base):
    """The predictor needs the neighbour's own field direction: a rotated system falls back
    to Newton and still converges (rotating the field rotates the stroke)."""
    from flutterswim.orbits import periodic

    system = ShapeSystem.of(fs.PAPER.groups, N, phi=0.3)
    # the neighbour's own start, unshifted: only the field direction tells it apart
    assert periodic._is_neighbour(base.warm_start, ShapeSystem.of(fs.PAPER.groups, N), base.u0,
                                  base.period_dimensionless, STEPS)
    assert not periodic._is_neighbour(base.warm_start, system, base.u0, base.period_dimensionless, STEPS)
    u = base.u0.copy()
    u[:N] += 0.3  # the stroke turned with the field
    _, T, fl, res, _ = solve_orbit(system, u, base.period_dimensionless, steps=STEPS, warm=base.warm_start)
    assert res < 1e-10 and abs(T / base.period_dimensionless - 1) < 1e-8


def test_a_far_neighbour_falls_back_to_newton(base):
    """25 % away (the period changes by 15 %) the chord converges too slowly: Newton takes
    over from the predicted orbit. Newton alone, in two halves without warm starts, lands on
    the same orbit."""
    params = fs.PAPER.replace(kappa_E=fs.PAPER.kappa_E * 1.25)
    near = periodic_orbit(params, base, n_segments=N, steps=STEPS)
    mid = periodic_orbit(fs.PAPER.replace(kappa_E=fs.PAPER.kappa_E * 1.12), base.compact(), n_segments=N, steps=STEPS)
    chained = periodic_orbit(params, mid.compact(), n_segments=N, steps=STEPS)
    assert near.residual < 1e-10 and abs(near.period / chained.period - 1) < 1e-9
    assert abs(near.period / base.period - 1) > 0.1
    # the trivial multiplier is 1 up to the time discretisation: at most 1e-7 at 24 steps, and
    # an order 4 or more smaller at twice the steps
    finer = periodic_orbit(params, near.compact(), n_segments=N, steps=2 * STEPS)
    assert near.trivial_multiplier_error < 1e-7
    assert finer.trivial_multiplier_error < near.trivial_multiplier_error / 16


def test_resolution_defaults_to_the_guess(base):
    near = periodic_orbit(fs.PAPER.replace(kappa_E=fs.PAPER.kappa_E * 1.01), base)
    assert (near.n_segments, near.steps) == (N, STEPS)
    from flutterswim._validate import ParameterError

    with pytest.raises(ParameterError, match="n_segments"):
        periodic_orbit(fs.PAPER, base, n_segments=N + 4)


def test_plain_python_stage_solve_equals_the_compiled_one():
    """The kernels are written once and run as plain Python without numba: same result."""
    pytest.importorskip("numba")
    from flutterswim.orbits import radau
    from flutterswim.orbits.shooting import RADAU_A

    k = radau.kernels()
    rng = np.random.default_rng(5)
    n, m = 7, 15
    jac = rng.normal(scale=10.0, size=(3, m, m))
    jac[:, n:, n:] = -np.eye(n + 1)
    consts = radau.constants(0.05, RADAU_A)
    fac = radau.factor(jac, n, consts)
    r = rng.normal(size=(3 * m, 3))
    a, b = r.copy(), r.copy()
    assert k.reduced_solve(*fac, *consts, a) == 0
    assert k.reduced_solve.py_func(*fac, *consts, b) == 0
    assert np.abs(a - b).max() < 1e-12 * np.abs(a).max()


def test_without_numba_the_same_kernels_give_the_same_flow(tmp_path):
    """Kernels are written once: run as plain Python (numba hidden, in a subprocess) the
    variational pass and the chord pass equal the compiled ones."""
    pytest.importorskip("numba")
    import subprocess
    import sys
    from pathlib import Path

    small = periodic_orbit(fs.PAPER.groups, n_segments=8, steps=16)
    np.savez(tmp_path / "in.npz", u=small.u0, T=small.period_dimensionless, n=8, steps=16)
    script = Path(__file__).with_name("_plain_flow.py")
    r = subprocess.run([sys.executable, str(script), str(tmp_path / "in.npz"), str(tmp_path / "out.npz")],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    plain = np.load(tmp_path / "out.npz")
    s = ShapeSystem.of(fs.PAPER.groups, 8)
    f0 = flow(s, small.u0, small.period_dimensionless, 16, variational=True, sensitivity=True)
    f1 = flow(s, small.u0, small.period_dimensionless, 16, warm=f0)
    for a, b in ((f0.y, plain["y"]), (f0.monodromy, plain["mono"]), (f0.sensitivity, plain["sens"]), (f1.y, plain["y1"])):
        assert np.abs(a - b).max() < 1e-9 * np.abs(a).max()


def test_a_failed_predictor_falls_back_to_newton_from_the_neighbour(base, monkeypatch):
    from flutterswim.orbits import OrbitNotFound, periodic

    real = periodic.solve_orbit

    def failing_warm(*args, warm=None, **kwargs):
        if warm is not None:
            raise OrbitNotFound("chord diverged (test)")
        return real(*args, **kwargs)

    monkeypatch.setattr(periodic, "solve_orbit", failing_warm)
    params = fs.PAPER.replace(kappa_E=fs.PAPER.kappa_E * 1.02)
    near = periodic_orbit(params, base)
    monkeypatch.undo()
    assert near.residual < 1e-10
    assert abs(near.period / periodic_orbit(params, base).period - 1) < 1e-9
