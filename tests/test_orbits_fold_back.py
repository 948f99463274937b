"""Continuation past the end of the range: an S-shaped branch that folds back into it."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.initial import InitialState
from flutterswim.orbits import continue_orbits, periodic_orbit
from flutterswim.simulate import simulate

N = 12


def _at(br, value):
    """The branch's stable orbits on either side of ``value`` (pairs of neighbours bracketing it)."""
    v = br.values
    return [br.orbits[i] for i in range(len(v) - 1)
            if (v[i] - value) * (v[i + 1] - value) <= 0 and br.orbits[i].stable and br.orbits[i + 1].stable]


@pytest.fixture(scope="module")
def branch():
    return continue_orbits(fs.PAPER, "kappa_E_ratio", 2.0, n_segments=N)


def test_fold_back_into_the_range_is_followed_and_reported(branch):
    """The kappa_E_ratio branch folds at ~2.03 and back at ~1.89 (N = 12; 2.108 and 1.899 at
    N = 24): stopping at 2 reported no crossing and one stroke where two coexist."""
    cross = branch.multiplier_crossings()
    assert any(c > 2.0 for c in cross) and any(1.0 < c < 2.0 for c in cross), cross
    assert branch.values[-1] == pytest.approx(2.0) and "folds back" in branch.message
    assert len(_at(branch, 1.95)) == 2  # two stable strokes at 1.95


def test_the_folds_are_named_where_the_branch_turns_back(branch):
    """Two independent readings of a fold of cycles: a real multiplier through +1, and the
    parameter turning back along the arclength. Each crossing is named a fold, within the
    orbits' spacing of a turning point of the parameter, and the file says so."""
    v = branch.values
    turns = [v[i] for i in range(1, v.size - 1) if (v[i] - v[i - 1]) * (v[i + 1] - v[i]) < 0]
    changes = branch.stability_changes()
    assert len(changes) == len(turns) == 2, (changes, turns)
    spacing = np.max(np.abs(np.diff(v)))
    for (at, kind), turn in zip(changes, turns):
        assert kind == "fold" and abs(at - turn) < spacing, (at, kind, turn)
    assert branch.to_dataset().attrs["multiplier_crossings"].count("(fold)") == 2


def test_crossings_are_classified_by_the_multiplier_that_leaves(monkeypatch):
    """A real multiplier through -1 is a period doubling, a complex pair a torus, a real one
    through +1 with the parameter going on a branch point (orbits made up: only their
    multipliers matter)."""
    from types import SimpleNamespace

    from flutterswim.orbits.continuation import Branch

    def orbit(mu):
        mu = np.r_[1.0, mu, 0.1, 0.01j].astype(complex)
        others = np.abs(mu[1:])
        return SimpleNamespace(multipliers=mu, max_multiplier=float(others.max()))

    for leaving, kind in ((-1.05, "period doubling"), (1.05 * np.exp(0.3j), "torus"), (1.05, "branch point")):
        inside = -0.95 if kind == "period doubling" else 0.95
        mus = [inside, inside, leaving, leaving]
        if kind == "torus":
            mus = [0.95 * np.exp(0.3j), 0.95 * np.exp(0.3j), leaving, leaving]
        orbits = []
        for m in mus:
            o = orbit(m)
            if kind == "torus":  # (the pair: both multipliers)
                o = orbit(np.array([m, np.conj(m)]))
            orbits.append(o)
        br = Branch(None, np.array([1.0, 1.1, 1.2, 1.3]), orbits, 0.5, 1.0, -1.0, 1.0, 12, 32, 0.0, "")
        (at, got), = br.stability_changes()
        assert got == kind and 1.1 < at < 1.2, (kind, got, at)


def test_the_second_stroke_is_an_attractor_of_the_time_stepper(branch):
    """Independent check: the stroke after the folds, perturbed by 2 % and simulated for 8
    periods, returns to itself, not to the stroke reached first (their periods differ)."""
    lower, upper = sorted(_at(branch, 1.95), key=lambda o: o.period)
    g = fs.PAPER.groups.replace(chi=1.95 * fs.PAPER.groups.chi)  # (dimensionless: kappa l, t / tau)
    lo = periodic_orbit(g, lower)
    up = periodic_orbit(g, upper)
    assert up.stable and lo.stable and up.period > 1.1 * lo.period
    u0 = up.u0
    T = up.period
    run = simulate(g, 8 * T, initial=InitialState.from_state(np.r_[0.0, 0.0, 1.02 * u0], N), n_segments=N,
                   n_frames=8 * 64 + 1, rtol=1e-8, atol=1e-10)
    last = np.concatenate((run.theta, run.kappa), axis=1)[-64:]
    orbit_states = np.concatenate((up.theta, up.kappa), axis=1)
    lower_states = np.concatenate((lo.theta, lo.kappa), axis=1)

    def dist(states, ref):
        return max(np.min(np.max(np.abs(ref - s), axis=1)) for s in states)

    assert dist(last, orbit_states) < 0.05 * np.max(np.abs(u0)) < dist(last, lower_states)


def test_without_a_fold_back_the_branch_ends_where_it_did():
    """Past the end, a branch that does not turn back is dropped: the same orbits as stopping at the end."""
    a = continue_orbits(fs.PAPER, "kappa_E_ratio", 1.0, n_segments=N, n_points=20)
    b = continue_orbits(fs.PAPER, "kappa_E_ratio", 1.0, n_segments=N, n_points=20, look_beyond=0.0)
    assert np.array_equal(a.values, b.values) and a.message == b.message
    assert [o.period for o in a.orbits] == [o.period for o in b.orbits]


def test_branch_size_is_bounded_before_any_work(tmp_path):
    """--points 100000000 grew to 11 GB before it was stopped; now one line, exit 2, at once
    (the limit read from the module, not copied)."""
    import subprocess
    import sys
    import time

    from flutterswim.orbits.continuation import MAX_POINTS

    with pytest.raises(fs.ParameterError, match=rf"n_points={MAX_POINTS + 1}.*at most {MAX_POINTS}"):
        continue_orbits(fs.PAPER, "kappa_E_ratio", 1.0, n_points=MAX_POINTS + 1)
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "flutterswim", "branch", "kappa_E_ratio=0.6:1", "--points", "100000000",
                        "--out", str(tmp_path / "b.nc")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "--points=100000000" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert time.perf_counter() - t0 < 60 and not (tmp_path / "b.nc").exists()


def test_branch_figure_breaks_the_lateral_curves_where_the_other_end_leads(branch):
    """The swimmer reverses on the middle branch and the other end leads: the figure drew a
    vertical line from one end's excursion to the other's; now the curves break there."""
    import matplotlib

    matplotlib.use("Agg")
    from flutterswim.orbits.plot import plot_branch

    ds = branch.to_dataset()
    assert np.any(np.diff(ds["leading_end"].values) != 0)
    fig = plot_branch(ds)
    ys = [ln.get_ydata() for ln in fig.axes[2].lines if len(ln.get_ydata()) > 10 and ln.get_linestyle() != "None"]
    span = np.nanmax(np.concatenate(ys)) - np.nanmin(np.concatenate(ys))
    assert max(np.nanmax(np.abs(np.diff(y))) for y in ys) < 0.15 * span


def test_a_folded_branch_file_is_cf_and_indexable(branch, tmp_path):
    """Past a fold the parameter turns back: as the dimension coordinate it was neither
    monotonic (CF) nor unique (xarray: sel raised 'Reindexing only valid with uniquely valued
    Index objects'). The file runs along `orbit`, the parameter an auxiliary coordinate."""
    import xarray as xr

    x = np.asarray(branch.values)
    assert np.any(np.diff(x) < 0)  # the branch folds back (else this test tests nothing)
    path = tmp_path / "b.nc"
    branch.to_dataset().to_netcdf(path, engine="h5netcdf")
    ds = xr.open_dataset(path, engine="h5netcdf")
    assert ds.indexes["orbit"].is_monotonic_increasing and ds.indexes["orbit"].is_unique
    np.testing.assert_array_equal(ds["kappa_E_ratio"].values, x)  # every orbit, in the order continued
    assert "kappa_E_ratio" in ds.coords and "kappa_E_ratio" not in ds.indexes
    # the orbits at one value, found by a mask on the coordinate: the two coexisting strokes
    # of the bistable range (periods far apart) are both there
    near = ds.where(np.abs(ds["kappa_E_ratio"] - 1.95) < 0.03, drop=True)
    per = near.period.values
    assert per.size >= 2 and per.max() > 1.1 * per.min()
    for v in ds.data_vars.values():
        assert "units" in v.attrs


def test_steps_per_period_follow_the_branch(branch):
    """Near the folds the strokes are stiff: 32 Radau steps per period put the advance 2.6e-3
    off at N = 24 (1.6e-3 at N = 12), 16 times the branch's step tolerance. The continuation
    doubles its steps where the step screen asks. Checked independently: each orbit solved
    again from itself with twice its steps changes period and advance within the tolerance
    (1.5 times it: the screen estimates the advance's change within a factor 0.5-1.4)."""
    from flutterswim.orbits.continuation import BRANCH_STEP_TOLERANCE, BRANCH_STEPS

    steps = np.array([o.steps for o in branch.orbits])
    assert steps.min() == BRANCH_STEPS and steps.max() >= 4 * BRANCH_STEPS
    screened = np.isfinite([o.step_error for o in branch.orbits])
    assert screened.mean() > 0.5  # (one after an orbit that passed with room is not screened)
    worst = 0.0
    for o in branch.orbits[::5] + [branch.orbits[int(np.nanargmax([o.step_error for o in branch.orbits]))]]:
        fine = periodic_orbit(o.params, o, steps=2 * o.steps)
        e_t = abs(fine.period / o.period - 1.0)
        e_a = abs(fine.advance - o.advance) / max(abs(fine.advance), 1e-3 * o.params.l)
        worst = max(worst, e_t / BRANCH_STEP_TOLERANCE[0], e_a / BRANCH_STEP_TOLERANCE[1])
    assert worst < 1.5


def test_steps_given_are_kept_unchecked():
    br = continue_orbits(fs.PAPER, "kappa_E_ratio", 0.8, n_points=4, n_segments=8, steps=24)
    assert {o.steps for o in br.orbits} == {24} and br.steps == 24
    assert all(np.isnan(o.step_error) for o in br.orbits)


def test_the_branch_figure_signs_the_advance_along_the_field(branch):
    """Past the fold the strokes swim against the field (swim_direction 180 degrees): drawn as
    a magnitude, the advance bounced off zero and the reversed stable strokes at 1.9-2 looked
    like a second forward branch (a review of the reproduce report). The legend sits outside
    the panels (inside, it covered the stroke just past the onset)."""
    import matplotlib

    matplotlib.use("Agg")
    from flutterswim.orbits.plot import plot_branch

    ds = branch.to_dataset()
    direction = ds.swim_direction.values
    assert np.any(np.abs(direction) > 179.0) and np.any(np.abs(direction) < 1.0)
    fig = plot_branch(ds)
    signed = ds.advance.values * np.cos(np.radians(direction)) * 1e3
    lines = [np.asarray(ln.get_ydata(), float)[1:] for ln in fig.axes[0].lines
             if len(ln.get_xdata()) == signed.size + 1]
    drawn = np.nanmax(np.vstack(lines), axis=0) if lines else None  # black and red runs, NaN elsewhere
    assert drawn is not None and np.allclose(drawn, signed, rtol=1e-9, atol=1e-12)
    assert drawn.min() < 0 < drawn.max()
    assert fig.axes[0].get_legend() is None and fig.legends


def test_the_step_screen_sees_the_shape_correction_near_the_hopf_point():
    """Near the Hopf point the orbit attracts weakly and the Newton step's shape correction is
    most of what twice the steps change in the advance: without it the screen recorded 1.7e-7
    where a full solve at twice the steps moved the advance 8.9e-5 (a review). Its estimate
    now agrees with the full solve within a factor 2 (fixed steps: the screen alone)."""
    from flutterswim.orbits.periodic import _scales, _step_screen
    from flutterswim.orbits.system import ShapeSystem

    br = continue_orbits(fs.PAPER, "kappa_E_ratio", 0.70, n_points=6, n_segments=N, steps=16)
    for o in br.orbits[:3]:
        o = periodic_orbit(o.params, o)  # the same orbit, with its flow (a branch keeps none)
        fine = periodic_orbit(o.params, o, steps=2 * o.steps)
        L = _scales(o.params)[1]
        full = abs(fine.advance - o.advance) / max(abs(fine.advance), 1e-3 * L)
        est = _step_screen(ShapeSystem.of(o.params, N), o)[1]
        assert 0.5 < est / full < 2.0, (est, full)
