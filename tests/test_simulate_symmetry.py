"""Invariances of the model: rotation, mirror, field reversal, end swap, similarity."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.field import Field
from flutterswim.initial import InitialState
from flutterswim.simulate import simulate

N = 20
T_END = 2.0
# A pure absolute error norm is invariant under these symmetries (rotations of (x0, y0),
# shifts of theta, permutations and sign changes of components), so both runs take the
# same steps and must agree to round-off, not merely to the tolerance.
TIGHT = dict(rtol=1e-14, atol=1e-7, n_segments=N, n_frames=21)


def _bent(theta0=0.3):
    return InitialState(theta=lambda s: theta0 + 0.4 * np.sin(3.0 * s), kappa=lambda s: 2.0 * s - 0.5,
                        position=(0.1, 0.2))


def _rotate(x, y, a):
    return np.cos(a) * x - np.sin(a) * y, np.sin(a) * x + np.cos(a) * y


def test_rotating_state_and_field_rotates_the_solution(paper_groups):
    a = 1.1
    ref = simulate(paper_groups, T_END, initial=_bent(), **TIGHT)
    x0, y0 = _rotate(0.1, 0.2, a)
    rot_init = InitialState(theta=lambda s: a + 0.3 + 0.4 * np.sin(3.0 * s), kappa=lambda s: 2.0 * s - 0.5,
                            position=(x0, y0))
    rot = simulate(paper_groups, T_END, initial=rot_init, field=Field(direction=a), **TIGHT)
    xr, yr = _rotate(ref.x, ref.y, a)
    assert np.max(np.abs(rot.theta - (ref.theta + a))) < 1e-9
    assert np.max(np.abs(rot.kappa - ref.kappa)) < 1e-9
    assert np.max(np.hypot(rot.x - xr, rot.y - yr)) < 1e-9
    assert np.ptp(ref.theta) > 0.5  # the motion is not trivial


def test_mirror_about_the_field_axis(paper_groups):
    ref = simulate(paper_groups, T_END, initial=_bent(), **TIGHT)
    mir_init = InitialState(theta=lambda s: -(0.3 + 0.4 * np.sin(3.0 * s)), kappa=lambda s: -(2.0 * s - 0.5),
                            position=(0.1, -0.2))
    mir = simulate(paper_groups, T_END, initial=mir_init, **TIGHT)
    assert np.max(np.abs(mir.theta + ref.theta)) < 1e-9
    assert np.max(np.abs(mir.kappa + ref.kappa)) < 1e-9
    assert np.max(np.abs(mir.x - ref.x)) < 1e-9 and np.max(np.abs(mir.y + ref.y)) < 1e-9


def test_reversing_kappa_E_equals_turning_the_field_by_pi(paper_groups):
    flipped = paper_groups.replace(chi=-paper_groups.chi)
    a = simulate(flipped, T_END, initial=_bent(), **TIGHT)
    b = simulate(paper_groups, T_END, initial=_bent(), field=Field(direction=np.pi), **TIGHT)
    assert np.max(np.abs(a.theta - b.theta)) < 1e-9
    assert np.max(np.abs(a.x - b.x)) < 1e-9


def test_describing_from_the_other_end_gives_the_same_motion(paper_groups):
    ref = simulate(paper_groups, T_END, initial=_bent(), **TIGHT)
    y0 = _bent().state(N)
    th, ka = y0[2 : N + 2], y0[N + 2 :]
    x, y = ref.x[0], ref.y[0]
    rev_init = InitialState(theta=th[::-1] + np.pi, kappa=-ka[::-1], position=(x[-1], y[-1]))
    opts = {**TIGHT, "atol": 1e-10}
    ref = simulate(paper_groups, T_END, initial=_bent(), **opts)
    rev = simulate(paper_groups, T_END, initial=rev_init, **opts)
    # The tracked end changes, so the error norm (and the steps) differ slightly: the
    # runs agree to the integration error (atol 1e-10), far below the motion (O(1)).
    assert np.max(np.abs(rev.theta - (ref.theta[:, ::-1] + np.pi))) < 1e-6
    assert np.max(np.abs(rev.kappa + ref.kappa[:, ::-1])) < 1e-5
    assert np.max(np.hypot(rev.x - ref.x[:, ::-1], rev.y - ref.y[:, ::-1])) < 1e-6


def test_same_groups_same_dimensionless_solution(paper_groups):
    g = paper_groups
    p1 = fs.Parameters.from_groups(g.eta_par, g.eta_perp, g.chi, l=3.7e-3, tau=0.375, B=1.9e-14)
    p2 = fs.Parameters.from_groups(g.eta_par, g.eta_perp, g.chi, l=1.0e-2, tau=2.0, B=4.0e-12)
    r1 = simulate(p1, T_END * p1.tau, initial=_bent(), **TIGHT).dimensionless()
    r2 = simulate(p2, T_END * p2.tau, initial=_bent(), **TIGHT).dimensionless()
    np.testing.assert_allclose(r1.t, r2.t, rtol=1e-12)
    assert np.max(np.abs(r1.theta - r2.theta)) < 1e-9
    assert np.max(np.abs(r1.x - r2.x)) < 1e-9
    # and the physical runs differ by the length and time scales
    assert r1.t[-1] == pytest.approx(T_END)
