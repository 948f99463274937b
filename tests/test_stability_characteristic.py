"""Characteristic function: paper's f, reduced g, quartic roots (tests against mathematics)."""

import numpy as np
import pytest

from flutterswim.stability import boundary_matrix, char_f, quartic_roots, reduced_char
from flutterswim.stability.characteristic import reduced_char_expm

CASES = [(70.67, 71.5235), (5.0, 3.0), (-40.0, 200.0), (1.0, 10.0)]
OMEGAS = np.array([0.3 + 2.0j, -0.5 + 1.0j, 2.0 - 3.0j, 1.5 + 0.0j, -3.0 + 4.0j])


def _vander(lam):
    return np.prod([lam[..., j] - lam[..., i] for i in range(4) for j in range(i + 1, 4)], axis=0)


@pytest.mark.parametrize("chi,eta", CASES)
def test_quartic_roots_are_roots(chi, eta):
    lam = quartic_roots(OMEGAS, chi, eta)
    c = chi / (OMEGAS + 1)
    p = lam**4 + c[:, None] * lam**3 + eta * OMEGAS[:, None]
    scale = np.abs(lam) ** 4 + np.abs(c[:, None] * lam**3) + eta * np.abs(OMEGAS[:, None])
    assert np.all(np.abs(p) <= 1e-13 * scale)
    # Vieta: product of roots = eta omega, sum = -c
    assert np.allclose(np.prod(lam, axis=-1), eta * OMEGAS, rtol=1e-11)
    assert np.allclose(lam.sum(axis=-1), -c, rtol=1e-11, atol=1e-11)


@pytest.mark.parametrize("chi,eta", CASES)
def test_f_is_determinant_of_paper_boundary_matrix(chi, eta):
    f = char_f(OMEGAS, chi, eta)
    for w, fw in zip(OMEGAS, f):
        det = np.linalg.det(boundary_matrix(w, chi, eta))
        # same function; the printed f carries the opposite overall sign of that determinant
        assert abs(det + fw) <= 1e-9 * max(abs(det), 1e-300)


@pytest.mark.parametrize("chi,eta", CASES)
def test_derivatives_match_finite_differences(chi, eta):
    h = 1e-5
    f, df = char_f(OMEGAS, chi, eta, derivative=True)
    fd = (char_f(OMEGAS + h, chi, eta) - char_f(OMEGAS - h, chi, eta)) / (2 * h)
    assert np.allclose(df, fd, rtol=1e-6)
    g, dg = reduced_char(OMEGAS, chi, eta, derivative=True)
    gd = (reduced_char(OMEGAS + h, chi, eta) - reduced_char(OMEGAS - h, chi, eta)) / (2 * h)
    assert np.allclose(dg, gd, rtol=1e-6)
    # analytic in omega: the derivative along i h is the same
    gi = (reduced_char(OMEGAS + 1j * h, chi, eta) - reduced_char(OMEGAS - 1j * h, chi, eta)) / (2j * h)
    assert np.allclose(dg, gi, rtol=1e-6)


@pytest.mark.parametrize("chi,eta", CASES)
def test_reduced_is_f_over_prefactor_and_matches_expm(chi, eta):
    lam = quartic_roots(OMEGAS, chi, eta)
    f = char_f(OMEGAS, chi, eta)
    g = reduced_char(OMEGAS, chi, eta)
    assert np.allclose(f, -((eta * OMEGAS) ** 2) * _vander(lam) * g, rtol=1e-10)
    ref = np.array([reduced_char_expm(w, chi, eta) for w in OMEGAS])
    assert np.allclose(g, ref, rtol=1e-8)


def test_f_flips_sign_under_root_swap_but_g_does_not():
    w, chi, eta = 0.3 + 2.0j, 5.0, 3.0
    lam = quartic_roots(w, chi, eta)
    swapped = lam[[1, 0, 2, 3]]
    d1 = np.linalg.det(boundary_matrix(w, chi, eta, lam))
    d2 = np.linalg.det(boundary_matrix(w, chi, eta, swapped))
    assert abs(d1 + d2) <= 1e-10 * abs(d1)
    # g is the determinant ratio with the Vandermonde product, symmetric in the roots
    def e(l):
        return np.linalg.det(np.array([np.ones(4), l, np.exp(l), l * np.exp(l)]).T) / _vander(l)

    assert abs(e(lam) - e(swapped)) <= 1e-10 * abs(e(lam))


def test_spurious_double_zero_of_f_at_zero_removed_in_g():
    chi, eta = 5.0, 3.0
    eps = np.array([1e-3, 1e-4])
    f = char_f(eps, chi, eta)
    # (eta omega)^2 prefactor times the Vandermonde of the triple root lambda = 0 (~ omega)
    assert abs(f[1] / f[0]) == pytest.approx(1e-3, rel=2e-2)
    pts = np.array([0.0, 1e-9, 1e-3j])
    g = reduced_char(pts, chi, eta)
    ref = np.array([reduced_char_expm(w, chi, eta) for w in pts])
    assert np.all(np.abs(ref) > 1e-6)
    assert np.allclose(g, ref, rtol=1e-9)


def test_reduced_regular_near_coinciding_roots():
    # p has a double root lambda = -3c/4 when q = 27 c^4/256: eta w (w+1)^4 = 27 chi^4/256
    chi, eta = 2.0, 3.0
    poly = np.polymul([eta, 0.0], np.poly([-1.0] * 4))
    poly[-1] -= 27 * chi**4 / 256
    w0 = complex(sorted(np.roots(poly), key=lambda z: -z.real)[0])
    lam = quartic_roots(w0, chi, eta)
    d = np.abs(lam[:, None] - lam[None, :]) + np.eye(4)
    assert d.min() < 1e-6  # genuinely a (numerically) double root
    pts = w0 + np.array([0.0, 1e-12, 1e-9, 1e-7j, 1e-5, 1e-3])
    g, dg = reduced_char(pts, chi, eta, derivative=True)
    ref = np.array([reduced_char_expm(w, chi, eta) for w in pts])
    assert np.all(np.isfinite(g)) and np.all(np.isfinite(dg))
    assert np.allclose(g, ref, rtol=1e-9)
    h = 1e-6
    dref = (reduced_char_expm(w0 + h, chi, eta) - reduced_char_expm(w0 - h, chi, eta)) / (2 * h)
    assert abs(dg[0] - dref) <= 1e-6 * abs(dref)
    from flutterswim.stability import _kernels

    n = pts.size
    gk, dgk, dck, mk = (np.empty(n, complex), np.empty(n, complex), np.empty(n, complex), np.empty(n))
    _kernels._gval_batch(pts, np.full(n, chi), np.full(n, eta), gk, dgk, dck, mk)
    assert np.allclose(gk * np.exp(2 * mk), ref, rtol=1e-9)
    assert abs(dgk[0] * np.exp(2 * mk[0]) - dref) <= 1e-6 * abs(dref)


@pytest.mark.parametrize("chi,eta", CASES)
def test_reduced_chi_reflection_identity(chi, eta):
    # s -> 1 - s maps chi -> -chi; Jacobi's complementary-minor identity with det expm(A) = e^{-c}
    g_plus = reduced_char(OMEGAS, chi, eta)
    g_minus = reduced_char(OMEGAS, -chi, eta)
    assert np.allclose(g_minus, np.exp(chi / (OMEGAS + 1)) * g_plus, rtol=1e-9)


def test_numba_and_numpy_agree():
    from flutterswim.stability import _kernels

    if not _kernels.HAVE_NUMBA:
        pytest.skip("numba not installed")
    chi = np.array([70.67, 5.0, -40.0, 1.0, 2.0])
    eta = np.array([71.5, 3.0, 200.0, 10.0, 3.0])
    n = chi.size
    g, dg, dgc, m = (np.empty(n, complex), np.empty(n, complex), np.empty(n, complex), np.empty(n))
    _kernels._gval_batch(OMEGAS, chi, eta, g, dg, dgc, m)
    g2, dg2 = reduced_char(OMEGAS, chi, eta, derivative=True)
    assert np.allclose(g * np.exp(2 * m), g2, rtol=1e-10)
    assert np.allclose(dg * np.exp(2 * m), dg2, rtol=1e-10)
    h = 1e-6
    dchi = (reduced_char(OMEGAS, chi + h, eta) - reduced_char(OMEGAS, chi - h, eta)) / (2 * h)
    assert np.allclose(dgc * np.exp(2 * m), dchi, rtol=1e-6)
