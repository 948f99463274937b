"""Force and torque balance, passive relaxation, rest state, and failures."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.filament import Filament
from flutterswim.initial import InitialState
from flutterswim.simulate import simulate


def _states(res):
    return np.concatenate((res.r0, res.theta, res.kappa), axis=1)


def test_total_drag_force_and_torque_vanish(paper_groups):
    res = simulate(paper_groups, 3.0, initial=InitialState.straight(20.0), n_segments=24, n_frames=31)
    fil = Filament(24, paper_groups.eta_par, paper_groups.eta_perp, paper_groups.chi)
    for y in _states(res)[1:]:  # t = 0 is a stress-free rest state
        fx, fy, tq = fil.drag_totals(y)
        # scale: the drag on a filament translating at the speed of its fastest point
        wfx, wfy, _, _ = fil.joint_drag(y)
        scale = np.abs(wfx).sum() + np.abs(wfy).sum()
        assert scale > 0
        assert abs(fx) < 1e-12 * scale and abs(fy) < 1e-12 * scale and abs(tq) < 1e-12 * scale


def test_passive_relaxation_is_monotone():
    g = fs.Groups(eta_par=40.0, eta_perp=70.0, chi=0.0)
    bent = InitialState(theta=lambda s: 0.8 * np.sin(2.5 * s) + 0.3 * s**2)
    res = simulate(g, 2.5, initial=bent, n_segments=32, n_frames=101, rtol=1e-7, atol=1e-9)
    h = 1.0 / 32
    energy = 0.5 * h * np.sum((np.diff(res.theta, axis=1) / h) ** 2, axis=1)
    assert np.all(np.diff(energy) < 0)
    # slowest passive mode decays as exp(-k^4 t / eta_perp), k = 4.73: energy by ~e^-36
    assert energy[-1] < 1e-12 * energy[0]
    # it ends straight: the tangent angle is uniform
    assert np.ptp(res.theta[-1]) < 1e-3 * np.ptp(res.theta[0])


def test_straight_state_without_field_stays_at_rest():
    g = fs.Groups(eta_par=40.0, eta_perp=70.0, chi=0.0)
    res = simulate(g, 2.0, initial=InitialState.straight(30.0, position=(0.3, -0.2)), n_segments=16)
    assert np.max(np.abs(res.theta - np.radians(30.0))) < 1e-13
    assert np.max(np.abs(res.r0 - [0.3, -0.2])) < 1e-13


def test_straight_aligned_filament_is_an_equilibrium(paper_groups):
    res = simulate(paper_groups, 2.0, initial=InitialState.straight(0.0), n_segments=16)
    assert np.max(np.abs(res.theta)) == 0.0 and np.max(np.abs(res.kappa)) == 0.0


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(t_end=np.nan), "t_end"),
        (dict(t_end=1.0, n_segments=2), "n_segments"),
        (dict(t_end=1.0, rtol=-1.0), "rtol"),
        (dict(t_end=1.0, method="euler"), "method"),
    ],
)
def test_bad_arguments_name_the_parameter(paper_groups, kwargs, name):
    with pytest.raises(fs.ParameterError, match=name):
        simulate(paper_groups, **kwargs)


def test_self_intersection_stops_the_run_with_a_reason():
    # a strongly curled filament that closes on itself as it relaxes towards kappa
    g = fs.Groups(eta_par=40.0, eta_perp=70.0, chi=0.0)
    curl = InitialState(theta=0.0, kappa=9.0)
    res = simulate(g, 1.0, initial=curl, n_segments=32, stop_on_self_intersection=True)
    assert res.status == "stopped" and "self-intersection" in res.message
    assert res.t_final < 1.0


def test_assembled_matrix_and_matrix_free_product_agree():
    """G assembled column by column and the O(N) product G z are two codings of one balance."""
    rng = np.random.default_rng(1)
    for n in (5, 17, 40):
        theta = np.cumsum(rng.normal(scale=0.4, size=n))
        fil = Filament(n, 30.0, 55.0, 12.0)
        g = fil.matrix(theta)
        for _ in range(3):
            z = rng.normal(size=n + 2)
            r = fil._k.apply(*fil._args(theta), z)
            assert np.max(np.abs(g @ z - r)) < 1e-12 * np.max(np.abs(r))


def test_compiled_and_plain_kernels_agree():
    pytest.importorskip("numba")
    rng = np.random.default_rng(2)
    n = 9
    y = np.r_[0.0, 0.0, np.cumsum(rng.normal(scale=0.4, size=n)), rng.normal(size=n + 1)]
    fast, plain = Filament(n, 30.0, 55.0, 12.0), Filament(n, 30.0, 55.0, 12.0, compiled=False)
    assert np.max(np.abs(fast.rhs(y, 0.3, 1.0) - plain.rhs(y, 0.3, 1.0))) < 1e-12 * np.abs(plain.rhs(y, 0.3, 1.0)).max()
    ja, jb = fast.jacobian(y, 0.3, 1.0, exact=True), plain.jacobian(y, 0.3, 1.0, exact=True)
    assert np.max(np.abs(ja - jb)) < 1e-11 * np.abs(jb).max()


@pytest.mark.parametrize("n", [6, 20])
def test_exact_jacobian_matches_central_differences(n):
    """The exact Jacobian (with d(G z)/d theta) against central differences of rhs: the
    error must fall as the difference step squared; the W-method Jacobian must not match."""
    rng = np.random.default_rng(n)
    fil = Filament(n, 41.5, 71.5, 70.7)
    y = np.r_[0.1, -0.2, np.cumsum(rng.normal(scale=0.3, size=n)), rng.normal(size=n + 1)]
    jac = fil.jacobian(y, 0.2, 1.0, exact=True)

    def fd(eps):
        out = np.empty_like(jac)
        for i in range(y.size):
            e = np.zeros_like(y)
            e[i] = eps
            out[:, i] = (fil.rhs(y + e, 0.2, 1.0) - fil.rhs(y - e, 0.2, 1.0)) / (2 * eps)
        return out

    scale = np.abs(jac).max()
    e1, e2 = np.abs(fd(1e-3) - jac).max() / scale, np.abs(fd(5e-4) - jac).max() / scale
    assert e1 < 1e-5 and 3.0 < e1 / e2 < 5.0  # second-order convergence of the differences
    assert np.abs(fil.jacobian(y, 0.2, 1.0) - jac).max() > 1e-3 * scale


def test_internal_forces_vanish_at_free_ends_and_balance_the_moment(paper_groups):
    init = InitialState(theta=lambda s: 0.6 * np.sin(3.0 * s), kappa=lambda s: 4.0 * np.cos(2.0 * s))
    errs = []
    for n in (32, 64):
        res = simulate(paper_groups, 0.2, initial=init, n_segments=n, n_frames=3, forces=True)
        a, v, m = res.A[-1], res.V[-1], res.M[-1]
        scale = np.abs(v).max()
        assert scale > 0
        assert max(abs(a[0]), abs(a[-1]), abs(v[0]), abs(v[-1]), abs(m[0]), abs(m[-1])) < 1e-10 * scale
        # angular momentum balance, M_s + V = 0 (eq. MOD:eq:MBLs:BAM_components), inside
        ms = np.gradient(m, res.s)
        errs.append(np.max(np.abs(ms + v)[3:-3]) / scale)
    assert errs[1] < 0.5 * errs[0] and errs[1] < 0.05


def test_switching_the_field_off_relaxes_kappa_exponentially(paper_groups):
    """With strength 0 the activity law is kappa_t = -kappa: kappa(t) = kappa(t1) e^-(t - t1)."""
    from flutterswim.field import Field, Piecewise

    field = Field(direction=0.2, strength=Piecewise([0.0, 1.0], [1.0, 0.0]))
    res = simulate(paper_groups, 3.0, field=field, initial=InitialState.straight(5.0), n_segments=16,
                   n_frames=31, rtol=1e-9, atol=1e-12)
    i1 = np.searchsorted(res.t, 1.0)
    assert np.abs(res.kappa[i1]).max() > 0.1
    decay = np.exp(-(res.t[i1:] - res.t[i1]))[:, None] * res.kappa[i1]
    assert np.max(np.abs(res.kappa[i1:] - decay)) < 1e-7 * np.abs(res.kappa[i1]).max()
    assert np.all(res.field_strength[res.t >= 1.0] == 0.0)


def test_a_field_callable_returning_nan_is_reported(paper_groups):
    from flutterswim.field import Field

    with pytest.raises(fs.ParameterError, match="returned nan"):
        simulate(paper_groups, 1.0, field=Field(direction=lambda t: float("nan")), n_segments=8)


@pytest.mark.parametrize("n", [6, 20])
def test_group_derivatives_match_central_differences(n):
    """d rhs / d (eta_par, eta_perp, chi) from the model against central differences of the
    rhs in each group: second-order convergence of the differences to it."""
    rng = np.random.default_rng(n + 1)
    groups = np.array([41.5, 71.5, 70.7])
    fil = Filament(n, *groups)
    y = np.r_[0.1, -0.2, np.cumsum(rng.normal(scale=0.3, size=n)), rng.normal(size=n + 1)]
    der = fil.group_derivatives(y, 0.2, 0.8)

    def fd(rel):
        out = np.empty_like(der)
        for k in range(3):
            d = np.zeros(3)
            d[k] = rel * groups[k]
            out[:, k] = (Filament(n, *(groups + d)).rhs(y, 0.2, 0.8) - Filament(n, *(groups - d)).rhs(y, 0.2, 0.8)) / (2 * d[k])
        return out

    e1, e2 = (np.abs(fd(r) - der).max(axis=0) / np.abs(der).max(axis=0) for r in (0.2, 0.1))
    assert np.all(e1 < 0.05)
    assert np.all((e2 < 1e-12) | ((3.0 < e1 / e2) & (e1 / e2 < 5.0)))  # chi: exact (the rhs is linear in it)
