"""Stop 45: the descriptors figure names the end whose lateral peak-to-peak it draws."""

import dataclasses
import math

import numpy as np
import pytest

import flutterswim as fs


@pytest.fixture(scope="module")
def settled():
    from flutterswim.analysis.track import as_track

    return as_track(fs.simulate(fs.PAPER, 12.0, n_segments=24))


def _flipped(tr):
    """The same swimmer with s counted from the other end."""
    return dataclasses.replace(tr, x=tr.x[:, ::-1], y=tr.y[:, ::-1], s=None, theta=None, kappa=None)


@pytest.mark.parametrize("flip", [False, True])
def test_descriptors_figure_names_the_end_it_draws(settled, flip):
    """The panel had read "tip lateral p-p" for the end s = l, leading or trailing by the run.
    Its legend must name the end whose values it draws: describe's leading and trailing ends
    differ threefold on the paper's stroke, so the named one must match within 2 %."""
    from flutterswim.plotting.figures import plot_descriptors

    tr = _flipped(settled) if flip else settled
    d = fs.describe(tr)
    ax = plot_descriptors(tr).axes[2]
    (line,) = [ln for ln in ax.get_lines() if "lateral p-p" in ln.get_label()]
    label = line.get_label()
    which = "leading" if "leading" in label else "trailing" if "trailing" in label else None
    assert which is not None, label
    assert ("s = 0" in label) == (d.leading_end == ("s=0" if which == "leading" else "s=l")), (label, d.leading_end)
    last = float(np.asarray(line.get_ydata())[-1])
    named = getattr(d, f"{which}_lateral_p2p_mm")
    other = getattr(d, f"{'trailing' if which == 'leading' else 'leading'}_lateral_p2p_mm")
    assert abs(last - named) < 0.02 * named < abs(last - other)


def test_both_tolerances_are_named_as_typed(tmp_path, capsys):
    """`simulate --rtol 1e-13 --atol 1e-14` named its second option `atol=`; each named option
    must be one the command parses."""
    import re

    from flutterswim.cli import build_parser, main

    assert main(["simulate", "--rtol", "1e-13", "--atol", "1e-14", "--out", str(tmp_path / "r.nc")]) == 2
    err = capsys.readouterr().err.strip()
    named = re.findall(r"(--[\w-]+)=", err)
    assert named == ["--rtol", "--atol"], err
    build_parser().parse_args(["simulate"] + [f"{o}=1e-6" for o in named])  # both parse
    assert not (tmp_path / "r.nc").exists()


def test_round_off_makes_no_spurious_flutter_at_high_resolution():
    """A review (stop 45): at N = 384-512 and eta_perp = 8 the dense eigensolver's round-off
    (||J|| ~ N^4 / eta_perp ~ 1e11) made a spurious pair 0.73 +- 1.68i, read as an unstable
    straight state 14 % below the threshold; the Hopf search then found chi = 104 for 121.
    The leading pair must stay the continuum's (characteristic equation) within its
    discretisation error, and say that round-off limits it; N = 48 must not warn."""
    import warnings

    from flutterswim.orbits.linear import RoundoffWarning, leading_pair
    from flutterswim.stability import critical_chi, leading_eigenvalue

    g = fs.Groups(8 / 1.7, 8.0, 104.433232)
    assert g.chi < 0.9 * critical_chi(g.eta_perp)[0]  # the straight state is stable here
    ref = leading_eigenvalue(g.chi, g.eta_perp).omega
    with warnings.catch_warnings():
        warnings.simplefilter("error", RoundoffWarning)
        coarse = leading_pair(g, 48)
    for n in (384,):
        with pytest.warns(RoundoffWarning, match=f"n_segments={n}"):
            lam = leading_pair(g, n)
        assert lam.real < 0
        assert abs(lam - ref) < abs(coarse - ref)  # no worse than N = 48's discretisation error


def test_the_look_beyond_leg_stays_where_the_parameter_is_physical():
    """A review (stop 45): past ``to`` the branch was followed look_beyond times the range
    more; below a small ``to`` in B or tau that reach was negative, so the branch was followed
    towards B = 0 (eta_perp -> infinity, each orbit stiffer) until the corrector failed: 10-15
    times the cost, all of it dropped. The reach must stay positive and lie past ``to`` for any
    range, and not fall short of a fold the linear reach found (a second review: at twice the
    paper's field the B branch folds at 0.75 B_paper, past a ``to`` of 1.24 B_paper)."""
    from flutterswim.orbits.continuation import look_beyond_limit
    from flutterswim.orbits.parameter import Axis

    rng = np.random.default_rng(45)
    for name in ("B", "tau", "mu", "l", "eta_perp"):
        axis = Axis(fs.PAPER, name)
        v = axis.value()
        for hopf, to in v * np.exp(rng.uniform(-5, 5, size=(20, 2))):
            side = 1 if to > hopf else -1
            lim = look_beyond_limit(axis, hopf, to, 0.2, side)
            linear = to + side * 0.2 * abs(to - hopf)
            assert lim > 0 and (lim - to) * side > 0, (name, hopf, to, lim)
            assert lim == pytest.approx(linear) or (side < 0 and linear < lim <= 0.5 * to * (1 + 1e-12))
    b = Axis(fs.PAPER, "B").value()
    assert look_beyond_limit(Axis(fs.PAPER, "B"), 12.48 * b, 1.24 * b, 0.2, -1) < 0.75 * b
    chi = Axis(fs.PAPER, "chi")
    assert look_beyond_limit(chi, 48.3, -10.0, 0.2, -1) == pytest.approx(-10.0 - 0.2 * 58.3)


def test_a_motion_about_an_unstable_orbit_is_not_promised_a_stroke():
    """A review (stop 45): Groups(10, 20, 100) at N = 48 has lost its stroke to a torus (the
    orbit's complex pair |mu| = 1.0129 by the review's own monodromy; a run stays
    quasi-periodic for 800 tau). run_to_limit_cycle said "capped ... a longer t_max may reach
    the stroke". Newton finds that orbit: the verdict must be not periodic, and say why."""
    import re

    run = fs.run_to_limit_cycle(fs.Groups(10.0, 20.0, 100.0), n_segments=48)
    out, why = run.settings["outcome"], run.settings["outcome_reason"]
    assert out == "not_periodic", (out, why)
    assert "longer t_max may reach" not in why
    mu = float(re.search(r"\|mu\| = ([0-9.]+)", why).group(1))
    assert 1.0 < mu < 1.05 and "complex pair" in why


def test_small_bad_inputs_of_the_hopf_tools_are_named():
    from flutterswim._validate import ParameterError
    from flutterswim.orbits import hopf_point, normal_form

    with pytest.raises(ParameterError, match="hopf=3 must be a HopfPoint"):
        normal_form(3)  # (had been an AttributeError)
    with pytest.raises(ParameterError, match="start=0"):
        hopf_point(fs.PAPER, "kappa_E_ratio", start=0.0)  # (had searched "between 0 and 0")


def test_a_range_holding_both_branches_names_the_mirror_one(tmp_path, capsys):
    """A review (stop 45): `branch chi=-100:100` wrote the branch from +48.3 and said nothing of
    the mirror branch from -48.3 in the same range. The note must name it, at minus the Hopf
    point written, and the command it suggests must continue it."""
    import re

    import xarray as xr

    from flutterswim.cli import main

    opts = ["--points", "4", "--segments", "8", "--steps", "16", "--quiet"]
    a = tmp_path / "a.nc"
    assert main(["branch", "kappa_E_ratio=-1:1", "--out", str(a), *opts]) == 0
    err = capsys.readouterr().err
    hopf = xr.open_dataset(a, engine="h5netcdf").attrs["hopf_kappa_E_ratio"]
    m = re.search(r"continue it with (kappa_E_ratio=\S+:\S+)", err)
    assert m, err
    b = tmp_path / "b.nc"
    assert main(["branch", m.group(1), "--out", str(b), *opts]) == 0
    assert xr.open_dataset(b, engine="h5netcdf").attrs["hopf_kappa_E_ratio"] == pytest.approx(-hopf, rel=1e-9)
    # one branch per sign: a range on one side has no note
    assert main(["branch", "kappa_E_ratio=0.7:1", "--out", str(tmp_path / "c.nc"), *opts]) == 0
    assert "mirror" not in capsys.readouterr().err


def test_the_half_thickness_is_no_continuation_parameter():
    """`branch a=1e-6:1e-4` answered "no Hopf point ... (unstable throughout)" for a range it had
    not been asked: a does not enter the dynamics (the drag holds b; B the thickness)."""
    from flutterswim._validate import ParameterError
    from flutterswim.orbits.linear import leading_pair
    from flutterswim.orbits.parameter import Axis

    # the reason, checked: the spectrum does not move with a
    g1, g2 = (fs.PAPER.replace(a=a).groups for a in (2e-6, 8e-6))
    assert leading_pair(g1, 12) == leading_pair(g2, 12)
    with pytest.raises(ParameterError, match="half thickness"):
        Axis(fs.PAPER, "a")


@pytest.mark.parametrize("dt", [0.10, 0.12])
def test_below_four_frames_per_stroke_no_lateral_excursion_is_measured(dt):
    """A review (stop 45): at 3.1-3.8 frames per stroke some cycles hold 4 frames, and the
    ends' lateral excursions were reported 8-11 % short, without the README's note. On average
    below 4 frames per stroke they must be NaN, and the note must say so."""
    run = fs.simulate(fs.PAPER, 30.0, frame_dt=dt, n_segments=24)
    d = fs.describe(run, n_last=15)
    assert 0.377 / dt < 4  # (the paper's stroke: 0.377 s)
    assert math.isnan(d.leading_lateral_p2p_mm) and math.isnan(d.trailing_lateral_p2p_mm)
    assert math.isnan(d.tip_lateral_p2p_mm)
    assert "lateral excursions are not measured" in d.note


@pytest.mark.parametrize("dimensionless", [False, True])
def test_the_settle_reason_gives_its_time_with_its_unit(dimensionless):
    """A review (stop 45): a sweep's reason said "from t=21.21" in tau beside a store's
    time_to_limit_cycle_s of 6.36 s, and in seconds on another axis. The reason's time must
    carry its unit and equal the run's limit-cycle time in it."""
    import re

    p = fs.PAPER.groups if dimensionless else fs.PAPER
    run = fs.run_to_limit_cycle(p, n_segments=12)
    why = run.settings["outcome_reason"]
    m = re.search(r"from t=([0-9.e+-]+) (s|tau)\b", why)
    assert m, why
    assert m.group(2) == ("tau" if dimensionless else "s")
    assert float(m.group(1)) == pytest.approx(run.settings["limit_cycle_time"], rel=1e-3)


def test_a_transient_past_a_saddle_orbit_is_not_called_not_periodic():
    """A second review (stop 45): near a subcritical Hopf point (Groups(173.4, 300, chi), fold
    ~43.1, Hopf ~50.65) a run started 10 % outside the unstable small orbit grows, slowly, to
    the stable stroke (reached at 289 tau). At t_max = 200 it had been called not periodic,
    "a longer t_max will not reach one": the saddle's multiplier is real, and the motion is
    passing it. It stays undecided (capped)."""
    from flutterswim.initial import InitialState
    from flutterswim.orbits.continuation import continue_orbits, multiplier_kind
    from flutterswim.settle import settle

    br = continue_orbits(fs.Groups(173.4, 300.0, 50.0), "chi", 50.0, n_points=6, n_segments=24, look_beyond=0.0)
    i = int(np.argmin(np.abs(br.values - 50.3)))
    orb, chi = br.orbits[i], float(br.values[i])
    assert not orb.stable and multiplier_kind(orb) == "real"  # a saddle
    m = orb.theta[0].mean()
    init = InitialState(theta=m + 1.1 * (orb.theta[0] - m), kappa=1.1 * orb.kappa[0])
    st = settle(fs.Groups(173.4, 300.0, chi), initial=init, n_segments=24, t_max=200.0)
    assert st.outcome == "capped" and "longer t_max may reach" in st.reason, (st.outcome, st.reason)


def test_a_refused_scheduler_is_not_said_to_have_timed_out():
    """`--scheduler tcp://127.0.0.1:1` is refused at once, but the message said "no Dask
    scheduler answered within 10 s"."""
    pytest.importorskip("distributed")
    from flutterswim.sweep.backends import SchedulerUnreachable, _reachable

    with pytest.raises(SchedulerUnreachable) as exc:
        _reachable("tcp://127.0.0.1:1", 5.0)
    assert "connection failed" in str(exc.value) and "within" not in str(exc.value)


def test_a_whole_number_of_frames_per_stroke_is_said_to_bunch_the_phases():
    """A diff review (stop 45): at 5.0 and 6.0 frames per stroke every cycle's frames fall on
    the same phases, the trailing end reads ~6 % short, and its standard error (1e-5 mm) does
    not hold it, without a word. describe must say so there, and not at 4.5 frames per stroke,
    where the phases drift over the cycles and the excursion is right."""
    ref = fs.describe(fs.simulate(fs.PAPER, 30.0, n_segments=24), n_last=15)
    for per_stroke, bunched in ((5.0, True), (4.5, False)):
        run = fs.simulate(fs.PAPER, 30.0, frame_dt=ref.period_s / per_stroke, n_segments=24)
        d = fs.describe(run, n_last=15)
        err = abs(d.trailing_lateral_p2p_mm / ref.trailing_lateral_p2p_mm - 1)
        assert ("fall on few phases" in d.note) == bunched, (per_stroke, d.note)
        assert (err > 0.02) == bunched, (per_stroke, err)  # the note where the excursion is short


def test_a_leading_pair_in_the_cluster_at_minus_one_says_its_frequency_is_unresolved():
    """A second diff review (stop 45): far below the threshold (|chi| < 1) the pairs crowd at
    Re = -1 and which one leads is decided by 1e-5 in Re; at N = 128 the pair taken had 0.58 of
    the continuum's frequency, without a word. Its growth rate is right; it must say that its
    frequency is not resolved. The paper's pair at N = 48 and 192 must not."""
    import warnings

    from flutterswim.orbits.linear import UnresolvedFrequencyWarning, flutter_growth, leading_pair
    from flutterswim.orbits.parameter import Axis
    from flutterswim.stability import leading_eigenvalue

    g = fs.Groups(0.8, 0.8, 0.24)
    ref = leading_eigenvalue(g.chi, g.eta_perp).omega
    with pytest.warns(UnresolvedFrequencyWarning):
        lam = leading_pair(g, 128)
    assert lam.real == pytest.approx(ref.real, abs=1e-4)  # the growth rate is resolved
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        flutter_growth(Axis(g, "chi"), g.chi, 128)  # (its growth rate alone: no warning)
        for n in (48, 192):
            leading_pair(fs.PAPER.groups, n)
