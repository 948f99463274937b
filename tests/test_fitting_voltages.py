"""The joint fit over voltages (kappa_E proportional to V): round trip, agreement with the
information comparison, calibrated 1-sigma and chi-square, the proportionality test, the CLI."""

import json
import math

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.fitting import DescriptorModel, fit, fit_voltages, to_identifiable
from flutterswim.fitting.richer import compare_information
from flutterswim.fitting.surrogate import ScalingSurrogate

BASE = fs.PAPER
TRUTH = np.array([1.94e-14, 0.375, 19.1e3])  # kappa_E at 85 V
V = np.array([75.0, 85.0, 95.0])


def _data(model, chi_factor=(1.0, 1.0, 1.0)):
    x = to_identifiable(BASE, *TRUTH)
    return np.array([model(np.array([x[0], x[1] + math.log(v / 85.0 * f), x[2]])) for v, f in zip(V, chi_factor)])


def test_round_trip_and_the_uncertainty_of_the_information_comparison():
    """Data made with kappa_E proportional to V are fitted back exactly from the paper's guess,
    chi2 ~ 0 (p = 1); the 1-sigma equals the one compare_information computes for the same data
    by another route (differences of the stacked residuals), and is below one voltage's."""
    sur = ScalingSurrogate(BASE)
    mu = _data(sur)
    se = 0.01 * mu
    res = fit_voltages(V, mu, se, model=sur, v_ref=85.0)
    assert res.converged
    np.testing.assert_allclose([res.B, res.tau, res.kappa_E], TRUTH, rtol=1e-8)
    assert res.settings["chi2"] < 1e-12 and res.settings["p_value"] == pytest.approx(1.0)
    np.testing.assert_allclose(res.settings["kappa_E_per_m_at_voltages"], TRUTH[2] * V / 85.0, rtol=1e-8)
    x = to_identifiable(BASE, *TRUTH)
    info = compare_information(sur, x, mu[1], se[1], voltages=(V, mu, se, 85.0))
    np.testing.assert_allclose(res.sigma_rel, info["several voltages (kappa_E ~ V)"], rtol=1e-4)
    assert np.all(res.sigma_rel < fit(mu[1], se[1], model=sur).sigma_rel)
    # kappa_E reported at another voltage: the same fit, scaled
    other = fit_voltages(V, mu, se, model=sur, v_ref=95.0)
    assert other.kappa_E == pytest.approx(TRUTH[2] * 95.0 / 85.0, rel=1e-8)
    assert other.B == pytest.approx(res.B, rel=1e-8)
    d = res.to_dict()
    assert d["data"]["measured"] == mu.tolist() and len(d["identifiability"][
        "sensitivities_dlog_descriptor_dlog_parameter"]) == 9
    assert "advance@95V" in d["identifiability"]["sensitivities_dlog_descriptor_dlog_parameter"]


def test_noisy_refits_scatter_as_the_1_sigma_says_and_chi2_follows_its_distribution():
    """200 noisy copies at the given SEMs: the spread of log(B, tau, kappa_E) matches the
    reported 1-sigma within 25 %, and the chi-square's mean its 3 m - 3 = 6 degrees of
    freedom (within 4 standard errors, sqrt(2 * 6 / 200))."""
    sur = ScalingSurrogate(BASE)
    mu = _data(sur)
    se = mu * np.array([0.002, 0.01, 0.006])
    rng = np.random.default_rng(11)
    ref = fit_voltages(V, mu, se, model=sur, v_ref=85.0, guess=tuple(TRUTH))
    logs, chi2 = [], []
    for _ in range(200):
        r = fit_voltages(V, mu + se * rng.standard_normal(mu.shape), se, model=sur, v_ref=85.0,
                         guess=tuple(TRUTH))
        assert r.converged
        logs.append(np.log([r.B, r.tau, r.kappa_E]))
        chi2.append(r.settings["chi2"])
    spread = np.std(np.array(logs), axis=0, ddof=1)
    assert np.all(np.abs(spread / ref.sigma_rel - 1) < 0.25), (spread, ref.sigma_rel)
    assert ref.settings["dof"] == 6 and abs(np.mean(chi2) - 6) < 4 * math.sqrt(2 * 6 / 200), np.mean(chi2)


def test_data_that_break_the_proportionality_are_rejected():
    """kappa_E at 95 V 12 % above the proportional value: with 1 % SEMs the chi-square test
    rejects the joint model (p < 1e-6), which proportional data at the same SEMs pass."""
    sur = ScalingSurrogate(BASE)
    bent = _data(sur, chi_factor=(1.0, 1.0, 1.12))
    res = fit_voltages(V, bent, 0.01 * bent, model=sur, v_ref=85.0)
    assert res.settings["p_value"] < 1e-6
    ok = _data(sur)
    assert fit_voltages(V, ok, 0.01 * ok, model=sur, v_ref=85.0).settings["p_value"] > 0.5


def test_bad_input_names_the_parameter():
    sur = ScalingSurrogate(BASE)
    mu = _data(sur)
    with pytest.raises(fs.ParameterError, match="voltages"):
        fit_voltages([85.0], mu[:1], mu[:1] * 0.01, model=sur)
    with pytest.raises(fs.ParameterError, match="sems"):
        fit_voltages(V, mu, np.full((3, 3), np.nan), model=sur)
    with pytest.raises(fs.ParameterError, match="means"):
        fit_voltages(V, mu[:2], mu * 0.01, model=sur)


def test_cli_joint_fit_recovers_the_truth_on_orbits(tmp_path, capsys):
    """Trials at three voltages made by the orbit model (16 segments alone, to be quick; two
    trials each, symmetric about the model, so the means are the model's), one voltage with a
    single trial: `fit --joint` recovers B, tau, kappa_E within 0.5 %, leaves the single trial
    out and says so, and writes the voltages and the chi-square test into fit.json."""
    from flutterswim.cli import main

    m = DescriptorModel(BASE, n_segments=16, extrapolate=False)
    mu = _data(m)
    rows = ["voltage_V,sample,period_s,advance_mm,lateral_mm"]
    for v, y in zip(V, mu):
        rows += [f"{v:g},A,{y[0] * 1.004},{y[1] * 0.99},{y[2] * 1.01}", f"{v:g},B,{y[0] * 0.996},{y[1] * 1.01},{y[2] * 0.99}"]
    rows.append("60,A,0.5,0.2,0.9")
    csv = tmp_path / "trials.csv"
    csv.write_text("\n".join(rows) + "\n")
    out = tmp_path / "fit.json"
    assert main(["fit", str(csv), "--joint", "--voltage", "85", "--segments", "16", "--no-extrapolate",
                 "--out", str(out), "--plot", str(tmp_path / "fit.png")]) == 0
    cap = capsys.readouterr()
    assert "left out (one trial, no SEM): 60 V" in cap.err and "from 3 voltages" in cap.out
    d = json.loads(out.read_text())
    got = np.array([d["values"]["B_N_m2"], d["values"]["tau_s"], d["values"]["kappa_E_per_m"]])
    assert np.all(np.abs(got / TRUTH - 1) < 5e-3), got / TRUTH - 1
    assert d["settings"]["voltages_V"] == V.tolist() and d["settings"]["v_ref_V"] == 85.0
    assert d["settings"]["dof"] == 6 and d["settings"]["chi2"] < 1e-6
    assert main(["fit", str(csv), "--joint", "--profiles", "--out", str(tmp_path / "f2.json")]) == 2
    assert "--joint" in capsys.readouterr().err


def test_the_p_value_allows_for_sems_from_few_trials():
    """Trials drawn around a model with kappa_E proportional to V, 3 per voltage: each weighted
    residual is then Student-t (2 degrees of freedom), so the chi-square distribution rejects
    the true model far more often than its 1 %; the simulated p-value (n_trials) rejects it at
    about 1 % (at most 3 % of 300 data sets)."""
    sur = ScalingSurrogate(BASE)
    mu = _data(sur)
    sd = mu * np.array([0.01, 0.05, 0.03])
    rng = np.random.default_rng(5)
    p_t, p_chi2 = [], []
    for _ in range(300):
        trials = mu[None] + sd[None] * rng.standard_normal((3, 3, 3))  # (trial, voltage, descriptor)
        mean, sem = trials.mean(axis=0), trials.std(axis=0, ddof=1) / math.sqrt(3)
        r = fit_voltages(V, mean, sem, model=sur, v_ref=85.0, guess=tuple(TRUTH), n_trials=[3, 3, 3])
        p_t.append(r.settings["p_value"])
        p_chi2.append(fit_voltages(V, mean, sem, model=sur, v_ref=85.0, guess=tuple(TRUTH)).settings["p_value"])
    assert np.mean(np.array(p_t) < 0.01) <= 0.03, np.mean(np.array(p_t) < 0.01)
    assert np.mean(np.array(p_chi2) < 0.01) > 0.1  # what the chi-square distribution alone would claim
    with pytest.raises(fs.ParameterError, match="n_trials"):
        fit_voltages(V, mu, 0.01 * mu, model=sur, n_trials=[3, 1, 3])


def test_a_chi_square_above_its_degrees_of_freedom_widens_the_1_sigma():
    """Data whose scatter is 3x their stated SEMs (SEMs from too few trials): the 1-sigma from
    the SEMs alone held the truth in about a quarter of 200 data sets; widened by sqrt(chi2 /
    dof), the Birge ratio, in over half (a 1-sigma of 6 degrees of freedom: 64 %)."""
    sur = ScalingSurrogate(BASE)
    mu = _data(sur)
    se = mu * np.array([0.002, 0.01, 0.006])
    rng = np.random.default_rng(12)
    inside, inside_unscaled, scales = [], [], []
    for _ in range(200):
        r = fit_voltages(V, mu + 3.0 * se * rng.standard_normal(mu.shape), se, model=sur, v_ref=85.0,
                         guess=tuple(TRUTH))
        err = np.abs(np.log([r.B, r.tau, r.kappa_E]) - np.log(TRUTH))
        scale = r.settings["sigma_scale"]
        assert scale == pytest.approx(max(1.0, math.sqrt(r.settings["chi2"] / r.settings["dof"])), rel=1e-12)
        inside.append(err < r.sigma_rel)
        inside_unscaled.append(err < r.sigma_rel / scale)
        scales.append(scale)
    cover, cover0 = np.mean(inside, axis=0), np.mean(inside_unscaled, axis=0)
    # (a scale estimated from 6 degrees of freedom: Student-t, |t| < 1 in 64 %; unscaled, the
    # truth within a third of the scatter: 26 %)
    assert np.all((cover > 0.5) & (cover < 0.8)), cover
    assert np.all(cover0 < 0.4), cover0
    assert 2.5 < np.median(scales) < 3.5
