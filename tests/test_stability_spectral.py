"""Spectral collocation vs Newton on the characteristic function; symmetries; chi = 0."""

import numpy as np
import pytest
import scipy.optimize

from flutterswim.stability import critical_chi, newton_root, spectrum
from flutterswim.stability.characteristic import reduced_char


def _near_neutral():
    pts = []
    for eta in (20.0, 150.0):
        chi_cr, _ = critical_chi(eta)
        pts += [(chi_cr * (1 - 1e-3), eta), (chi_cr * (1 + 1e-3), eta)]
    return pts


SPREAD = [(70.67, 71.52354521259821), (5.0, 3.0), (130.0, 350.0), (-40.0, 200.0), (1.0, 300.0),
          (20.0, 0.5), (-100.0, 10.0), (0.5, 50.0)]


def _resolved(chi, eta, n1=48, n2=64, count=8):
    """Eigenvalues of the n1 collocation that the n2 one reproduces to 1e-10 (resolved)."""
    a = spectrum(chi, eta, n=n1).omega
    b = spectrum(chi, eta, n=n2).omega
    a = a[np.abs(a + 1) > 1e-3][: 2 * count]  # the accumulation point -1 is not resolvable
    ok = [w for w in a if np.min(np.abs(b - w)) <= 1e-10 * max(1, abs(w))]
    return np.array(ok)


@pytest.mark.parametrize("chi,eta", SPREAD + _near_neutral())
def test_newton_and_spectral_agree(chi, eta):
    w = _resolved(chi, eta)
    assert w.size >= 2
    res = newton_root(w, chi, eta, tol=1e-14)
    assert np.all(res.converged)
    rel = np.abs(res.omega - w) / np.maximum(np.abs(w), 1)
    assert rel.max() < 1e-8
    # and they are zeros of g: |g| small compared with |g'| |omega| (relative residual)
    g, dg = reduced_char(res.omega, chi, eta, derivative=True)
    assert np.all(np.abs(g) <= 1e-10 * np.abs(dg) * np.maximum(np.abs(res.omega), 1))


@pytest.mark.parametrize("chi,eta", [(70.67, 71.5), (30.0, 200.0), (-90.0, 10.0)])
def test_spectral_error_decreases_under_refinement(chi, eta):
    ref = newton_root(spectrum(chi, eta, n=48).omega[:1], chi, eta, tol=1e-14).omega[0]
    errs = []
    for n in (10, 14, 18, 22):
        w = spectrum(chi, eta, n=n).omega
        errs.append(np.min(np.abs(w - ref)) / abs(ref))
    assert errs[0] > 1e-12  # visible discretisation error at the coarsest level
    for e0, e1 in zip(errs[:-1], errs[1:]):
        assert e1 < e0 or e1 < 1e-11


@pytest.mark.parametrize("chi,eta", [(70.67, 71.5), (13.0, 4.0), (120.0, 300.0)])
def test_spectrum_invariant_under_chi_sign(chi, eta):
    a = _resolved(chi, eta)
    b = spectrum(-chi, eta, n=48, use_symmetry=False).omega
    for w in a:
        assert np.min(np.abs(b - w)) <= 1e-9 * max(1, abs(w))
    # Newton side: a root at chi is a root at -chi (converges where it starts)
    res = newton_root(a, -chi, eta, tol=1e-14)
    assert np.all(res.converged)
    assert np.allclose(res.omega, a, rtol=1e-10)


def _free_free_k(count):
    def f(k):
        return np.cos(k) * np.cosh(k) - 1

    return [scipy.optimize.brentq(f, (j + 0.5) * np.pi - 0.3, (j + 0.5) * np.pi + 0.3, xtol=1e-15)
            for j in range(1, count + 1)]


@pytest.mark.parametrize("eta", [3.0, 71.5, 600.0])
def test_chi_zero_spectrum(eta):
    sp = spectrum(0.0, eta, n=48)
    w = sp.omega
    assert np.all(np.abs(w.imag) <= 1e-8 * np.maximum(1, np.abs(w)))
    assert np.all(w.real <= 1e-10)
    for k in _free_free_k(3):
        target = -(k**4) / eta
        assert np.min(np.abs(w - target)) <= 1e-9 * abs(target)
        # the characteristic function has this zero too (clamped-moment form)
        r = newton_root(target * (1 + 1e-3), 0.0, eta, tol=1e-14)
        assert r.converged and abs(r.omega - target) <= 1e-10 * abs(target)
    # curvature relaxation mode omega = -1 and two rigid (neutral) modes at 0
    assert np.min(np.abs(w + 1)) <= 1e-9
    assert sp.neutral.size == 2
    assert np.all(np.abs(sp.neutral) <= 1e-8)


def test_neutral_modes_recognised_for_nonzero_chi():
    sp = spectrum(70.67, 71.5, n=48)
    assert sp.neutral.size == 2
    assert np.all(np.abs(sp.omega) > 1e-3)
