"""A multi-start search over the paper's box finds every parameter set that fits (three
descriptors can be matched exactly at two sets, and one fit finds only one of them).

The model here has two exact solutions in closed form: its lateral excursion is symmetric in
log chi about the box's centre, so data made at chi = chi0 e^{+c} are matched as well at
chi0 e^{-c}, with eta_perp and tau from the advance and the period."""

import math

import numpy as np
import pytest

import flutterswim as fs
from flutterswim._validate import ParameterError
from flutterswim.fitting import fit, to_identifiable, to_physical
from flutterswim.fitting.fit import PAPER_GUESS, start_points
from flutterswim.fitting.model import NotSwimming

BASE = fs.PAPER
X0 = to_identifiable(BASE, *PAPER_GUESS)


class TwoRoots:
    """period = tau e^{0.3 a}, advance = 0.1 l e^{0.5 a + 0.2 b}, lateral = 0.3 l e^{-2 b^2},
    with a = log(eta_perp / eta0), b = log(chi / chi0) at the guess."""

    n_evaluations = 0

    def __call__(self, x):
        self.n_evaluations += 1
        a, b, lt = x[0] - X0[0], x[1] - X0[1], x[2]
        if not (abs(a) < 3 and abs(b) < 3 and abs(lt) < 10):  # (as the model: no stroke far off)
            raise NotSwimming("far from the box")
        tau, l_mm = math.exp(lt), BASE.l * 1e3
        return np.array([tau * math.exp(0.3 * a), 0.1 * l_mm * math.exp(0.5 * a + 0.2 * b),
                         0.3 * l_mm * math.exp(-2.0 * b * b)])

    def roots(self, y):
        """Both exact solutions (B, tau, kappa_E) of data y."""
        l_mm = BASE.l * 1e3
        c = math.sqrt(-math.log(y[2] / (0.3 * l_mm)) / 2.0)
        out = []
        for b in (c, -c):
            a = (math.log(y[1] / (0.1 * l_mm)) - 0.2 * b) / 0.5
            out.append(to_physical(BASE, np.array([X0[0] + a, X0[1] + b, math.log(y[0]) - 0.3 * a])))
        return np.array(out)


def _data(b):
    m = TwoRoots()
    x = X0 + np.array([0.1, b, math.log(1.1)])
    return m, m(x)


@pytest.mark.parametrize("b", [0.15, -0.2])
def test_the_starts_find_both_exact_solutions(b):
    m, y = _data(b)
    truth = m.roots(y)
    assert np.max(np.abs(truth[0] / truth[1] - 1)) > 0.1  # two sets far apart, both in the box
    assert np.all((truth / np.array(PAPER_GUESS) > 0.5) & (truth / np.array(PAPER_GUESS) < 1.5))
    one = fit(y, 0.01 * y, model=m)
    assert one.converged and "other_solutions" not in one.settings  # a single fit sees one
    r = fit(y, 0.01 * y, model=TwoRoots(), starts=8, seed=1)
    assert r.converged and r.settings["starts"]["n"] == 8
    got = [np.array([r.B, r.tau, r.kappa_E])] + [np.array([o["B_N_m2"], o["tau_s"], o["kappa_E_per_m"]])
                                                  for o in r.settings["other_solutions"]]
    assert len(got) == 2 == r.settings["starts"]["distinct_solutions"]
    for t in truth:  # each exact solution found, to the fit's tolerance
        assert min(np.max(np.abs(g / t - 1)) for g in got) < 1e-6
    assert all(o["chi2"] < 1e-8 and o["in_box"] for o in r.settings["other_solutions"])
    assert "other parameter set" in r.message


def test_a_unique_solution_stays_alone():
    """Data on the symmetry line (b = 0) have one solution: the starts add none."""
    m, y = _data(0.0)
    r = fit(y, 0.01 * y, model=m, starts=6)
    assert r.converged and "other_solutions" not in r.settings
    assert r.settings["starts"]["distinct_solutions"] == 1 and r.settings["starts"]["converged"] >= 1


def test_start_points_cover_the_box_and_repeat_with_the_seed():
    p = start_points(PAPER_GUESS, 16, seed=3) / np.array(PAPER_GUESS)
    assert p.shape == (16, 3) and np.all((p >= 0.55) & (p <= 1.45))
    for k in range(3):  # every factor spread over the box, not bunched
        assert p[:, k].min() < 0.75 and p[:, k].max() > 1.25
    np.testing.assert_array_equal(start_points(PAPER_GUESS, 16, seed=3), start_points(PAPER_GUESS, 16, seed=3))
    assert not np.array_equal(start_points(PAPER_GUESS, 16, seed=3), start_points(PAPER_GUESS, 16, seed=4))


def test_bad_starts_are_refused_by_name():
    m, y = _data(0.1)
    with pytest.raises(ParameterError, match=r"starts=-1"):
        fit(y, 0.01 * y, model=m, starts=-1)
    with pytest.raises(ParameterError, match=r"starts=65"):
        fit(y, 0.01 * y, model=m, starts=65)
    with pytest.raises(ParameterError, match=r"starts=2 .*paper"):
        fit(y, None, model=m, cost="paper", starts=2)


def test_the_command_line_reports_every_solution(tmp_path, monkeypatch, capsys):
    import importlib

    from flutterswim import cli

    ff = importlib.import_module("flutterswim.fitting.fit")
    m, y = _data(0.15)
    real_fit = ff.fit
    seen = {}

    def fake(mean, sem, **kw):
        seen.update(kw)
        return real_fit(mean, sem, model=TwoRoots(), starts=kw["starts"])

    monkeypatch.setattr(ff, "fit", fake)
    csv = tmp_path / "t.csv"
    csv.write_text("voltage_V,sample,period_s,advance_mm,lateral_mm\n"
                   + "".join(f"85,{k},{v[0]},{v[1]},{v[2]}\n" for k, v in enumerate((y * 1.01, y, y * 0.99))))
    assert cli.main(["fit", str(csv), "--out", str(tmp_path / "f.json"), "--starts", "6"]) == 0
    err = capsys.readouterr().err
    assert seen["starts"] == 6
    assert "another parameter set, inside the paper's box" in err and "6 starts" in err
    assert "1 other parameter set(s) fit as well" in err
    import json

    saved = json.loads((tmp_path / "f.json").read_text())
    assert len(saved["settings"]["other_solutions"]) == 1 and saved["settings"]["starts"]["n"] == 6
    for bad in (["--starts", "-2"], ["--starts", "3", "--paper-cost"], ["--starts", "3", "--joint"]):
        assert cli.main(["fit", str(csv), "--out", str(tmp_path / "g.json"), *bad]) == 2
        lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
        assert len(lines) == 1 and "--starts" in lines[0], lines
    assert not (tmp_path / "g.json").exists()


@pytest.mark.parametrize("b", [0.15, -0.2])
def test_deflation_finds_the_other_solution_from_the_same_start(b):
    """One start, the guess itself, from which the plain fit reached the first solution: the
    search deflated against that solution reaches the other."""
    m, y = _data(b)
    truth = m.roots(y)
    r = fit(y, 0.01 * y, model=TwoRoots(), starts=1)
    assert r.settings["starts"]["n"] == 1 and r.settings["starts"]["distinct_solutions"] == 2
    got = [np.array([r.B, r.tau, r.kappa_E])] + [np.array([o["B_N_m2"], o["tau_s"], o["kappa_E_per_m"]])
                                                  for o in r.settings["other_solutions"]]
    for t in truth:
        assert min(np.max(np.abs(g / t - 1)) for g in got) < 1e-6


def test_a_start_on_a_known_solution_and_a_failed_fit():
    """A review: a start equal to a known solution bit for bit divided by zero in the deflation;
    starts after a fit that did not converge were reported as searched."""
    from dataclasses import replace

    fit_module = __import__("importlib").import_module("flutterswim.fitting.fit")
    m, y = _data(0.15)
    r = fit(y, 0.01 * y, model=m)
    x = to_identifiable(BASE, r.B, r.tau, r.kappa_E)
    got = fit_module._deflated(TwoRoots(), BASE, PAPER_GUESS, x, y, 0.01 * y, [x])  # (no ZeroDivisionError)
    assert np.all(np.isfinite(got))
    failed = replace(r, converged=False)
    out = fit_module._search_starts(failed, 3, 0, PAPER_GUESS, BASE, m, lambda s: r)
    assert out.settings["starts"]["n"] == 3 and "did not converge" in out.settings["starts"]["skipped"]


@pytest.mark.slow  # about 5 minutes: two fits and a deflated search on the orbit model
def test_the_orbit_models_second_solution_is_found():
    """The model's own descriptors at (1.5, 0.7, 1.5) x the guess: the fit finds the other exact
    solution (B, tau, kappa_E 18, 14, 13 % low); two starts find the truth as well."""
    from flutterswim.fitting.model import DescriptorModel

    truth = np.array(PAPER_GUESS) * np.array([1.5, 0.7, 1.5])
    y = DescriptorModel(fs.PAPER)(to_identifiable(fs.PAPER, *truth))
    r = fit(y, 0.01 * y, starts=2)
    sets = [np.array([r.B, r.tau, r.kappa_E])] + [np.array([o["B_N_m2"], o["tau_s"], o["kappa_E_per_m"]])
                                                   for o in r.settings.get("other_solutions", [])]
    assert len(sets) >= 2
    assert min(np.max(np.abs(s / truth - 1)) for s in sets) < 5e-3  # (the refit's finer model: 0.2 %)
    assert max(np.max(np.abs(s / truth - 1)) for s in sets) > 0.1
