"""A converged fit whose parameters the model's own resolution error would move is repeated
with the finer model: at a poorly conditioned point the 24/48-segment model's error of about
1e-4 moved B by 1 % (a review)."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.fitting import fit, to_identifiable
from flutterswim.fitting.surrogate import ScalingSurrogate


class _Resolved:
    """The surrogate with a resolution error ``error`` (relative, per descriptor) that halves
    with each refinement, from ``n_segments``."""

    def __init__(self, error, n_segments=24, calls=None):
        self.sur, self.error, self.n_segments = ScalingSurrogate(fs.PAPER), np.asarray(error, float), n_segments
        self.calls = [] if calls is None else calls

    def __call__(self, x):
        self.calls.append(self.n_segments)
        return self.sur(x) * (1.0 + self.error)

    def finer(self):
        return _Resolved(self.error / 4.0, 2 * self.n_segments, self.calls) if self.n_segments < 96 else None


def test_a_fit_the_resolution_would_move_is_repeated_finer():
    truth = (1.2e-14, 0.42, 25.2e3)
    y = ScalingSurrogate(fs.PAPER)(to_identifiable(fs.PAPER, *truth))
    sem = y * np.array([0.005, 0.05, 0.03])
    # an error in the lateral excursion alone: the coarse fit is off, the check sees it
    coarse = _Resolved([0.0, 0.0, 4e-3])
    single = _Resolved([0.0, 0.0, 4e-3])
    single.finer = lambda: None  # (a single resolution: no finer model to ask)
    first = fit(y, sem, model=single)
    res = fit(y, sem, model=coarse)
    assert res.converged and res.settings["refined_from_segments"] == 24
    assert 48 in coarse.calls
    err_first = max(abs(a / b - 1) for a, b in zip((first.B, first.tau, first.kappa_E), truth))
    err = max(abs(a / b - 1) for a, b in zip((res.B, res.tau, res.kappa_E), truth))
    assert err < err_first / 3
    # a model whose error moves nothing beyond the tolerance is not refitted
    fine = _Resolved([0.0, 0.0, 1e-7])
    res2 = fit(y, sem, model=fine)
    assert "refined_from_segments" not in res2.settings and res2.settings["resolution_shift_rel"] < 1e-3
    assert res2.B == pytest.approx(truth[0], rel=1e-3)


def test_profiles_are_computed_once(monkeypatch):
    """With profiles, a fit repeated finer computes them once (on the first fit's model: their
    widths come from the standard errors, and the finer model took 3-4 times as long)."""
    from flutterswim.fitting import profile as profile_module

    truth = (1.2e-14, 0.42, 25.2e3)
    y = ScalingSurrogate(fs.PAPER)(to_identifiable(fs.PAPER, *truth))
    seen = []
    real = profile_module.profile_likelihood

    def counting(model, *a, **kw):
        seen.append(model.n_segments)
        return real(model, *a, **kw)

    monkeypatch.setattr(profile_module, "profile_likelihood", counting)
    res = fit(y, y * np.array([0.005, 0.05, 0.03]), model=_Resolved([0.0, 0.0, 4e-3]), profiles=True)
    assert res.settings["refined_from_segments"] == 24 and seen == [24]
    assert set(res.profiles) == {"B", "tau", "kappa_E"}
