"""Root-following map vs spectral solver; neutral curve vs map; physical units."""

import functools
import numpy as np
import pytest
import scipy.interpolate

from flutterswim import ParameterError
from flutterswim.params import PAPER
from flutterswim.stability import (
    critical_chi, eigenmodes, leading_eigenvalue, load_map, neutral_curve, physical_stability,
    spectrum, stability_map,
)
from flutterswim.stability import _kernels
from flutterswim.stability.leading import FREE_FREE_K1

ETA = np.array([0.0, 0.5, 2.0, 10.0, 40.0, 71.5, 150.0, 350.0])
CHI = np.array([-130.0, -70.0, -50.0, -20.0, -5.0, -0.5, 0.0, 0.5, 5.0, 20.0, 50.0, 70.0, 130.0])
BACKENDS = ["numpy"] + (["numba"] if _kernels.HAVE_NUMBA else [])


@functools.lru_cache(maxsize=None)
def _leading(chi, eta):
    return leading_eigenvalue(chi, eta, n=64).omega


@functools.lru_cache(maxsize=None)
def _spectral_top(chi, eta):
    w = spectrum(chi, eta, n=64).omega[0]
    return complex(w.real, abs(w.imag))


@pytest.fixture(scope="module", params=BACKENDS)
def coarse(request):
    return stability_map(eta_perp=ETA, chi=CHI, backend=request.param)


def test_map_follows_leading_branch_without_jumps(coarse):
    om = coarse.omega
    assert np.all(np.isnan(om[0]))  # eta_perp = 0: no drag, not computed
    assert np.all(np.isfinite(om[1:]))
    for i, eta in enumerate(ETA[1:], start=1):
        for j, chi in enumerate(CHI):
            if chi == 0:
                assert om[i, j] == pytest.approx(max(-1.0, -(FREE_FREE_K1**4) / eta), rel=1e-14)
                continue
            # independent: whole collocation spectrum, no guess, largest real part
            w = _spectral_top(chi, eta)
            if abs(w + 1) > 1e-2:  # away from the accumulation point -1 the raw spectrum is resolved
                assert abs(om[i, j] - w) <= 1e-7 * max(1, abs(w)), (eta, chi)
            le = _leading(chi, eta)
            assert abs(om[i, j] - le) <= 1e-9 * max(1, abs(le)), (eta, chi)


def test_map_builtin_spectral_check():
    m = stability_map(eta_perp=np.linspace(0, 350, 8), chi=np.linspace(-130, 130, 9), check_stride=2)
    assert m.check_points == 12  # eta = 0 and chi = 0 are skipped
    assert m.check_max_rel_diff < 1e-9


def test_map_symmetric_in_chi(coarse):
    om = coarse.omega[1:]
    assert np.allclose(om, om[:, ::-1], rtol=1e-12)


def test_map_netcdf_roundtrip(coarse, tmp_path):
    pytest.importorskip("h5py")  # h5netcdf's HDF5 backend
    path = tmp_path / "map.nc"
    coarse.save(path)
    back = load_map(path)
    assert np.array_equal(back.omega, coarse.omega, equal_nan=True)
    ds = coarse.to_dataset()
    assert ds["re_omega"].dims == ("eta_perp", "chi")
    # eta_perp = 0 (no drag) has no eigenvalue: NaN in both parts (its imaginary part read 0,
    # a neutral non-oscillating mode), and no Newton iterations
    row = ds.sel(eta_perp=0.0)
    assert np.all(np.isnan(row["re_omega"])) and np.all(np.isnan(row["im_omega"]))
    assert np.all(row["iterations"] == -1)
    assert np.all(np.isfinite(ds["im_omega"].sel(eta_perp=ETA[1:])))


@pytest.mark.slow
def test_whole_coarse_map_against_spectral():
    m = stability_map(step=5.0)
    for i in range(1, m.eta_perp.size, 3):
        for j in range(0, m.chi.size, 2):
            chi, eta = m.chi[j], m.eta_perp[i]
            if chi == 0:
                continue
            le = leading_eigenvalue(chi, eta, n=64).omega
            assert abs(m.omega[i, j] - le) <= 1e-9 * max(1, abs(le)), (eta, chi)


def test_neutral_curve_matches_map_sign_changes():
    eta = np.array([1.0, 5.0, 20.0, 71.5, 160.0, 349.0])
    nc = neutral_curve(np.arange(0.5, 350.01, 0.5))
    chi = np.arange(-130.0, 130.01, 0.5)
    m = stability_map(eta_perp=eta, chi=chi)
    for i, e in enumerate(eta):
        k = np.argmin(np.abs(nc.eta_perp - e))
        assert nc.eta_perp[k] == e
        ccr = nc.chi_cr[k]
        re = m.omega[i].real
        if np.isfinite(ccr) and ccr < 130:
            assert np.all(re[np.abs(chi) < ccr] < 0)
            assert np.all(re[np.abs(chi) > ccr] > 0)
        else:
            assert np.all(re < 0)
    # directly: Re omega_max vanishes on the curve and the frequency is the Hopf frequency
    for k in range(0, nc.eta_perp.size, 97):
        if np.isfinite(nc.chi_cr[k]):
            le = leading_eigenvalue(nc.chi_cr[k], nc.eta_perp[k]).omega
            assert abs(le.real) <= 1e-9 * abs(le)
            assert le.imag == pytest.approx(nc.beta[k], rel=1e-9)


def test_neutral_curve_default_grid_and_degenerate_eta():
    nc = neutral_curve(step=1.0)
    assert nc.eta_perp[0] == 0 and np.isnan(nc.chi_cr[0])
    assert np.all(nc.iterations[1:] > 0)
    c, b = critical_chi(float(nc.eta_perp[200]))
    assert c == pytest.approx(nc.chi_cr[200], rel=1e-9)


def test_paper_parameters_flutter():
    g = PAPER.groups
    le = leading_eigenvalue(g.chi, g.eta_perp)
    assert le.omega.real > 0 and le.omega.imag > 0 and le.flutter
    assert le.second.real < 0  # as stated in the paper's figure caption


def test_physical_units_and_critical_field():
    ps = physical_stability(PAPER)
    g = PAPER.groups
    le = leading_eigenvalue(g.chi, g.eta_perp)
    assert ps.growth_rate == pytest.approx(le.omega.real / PAPER.tau, rel=1e-12)
    assert ps.frequency == pytest.approx(le.omega.imag / (2 * np.pi * PAPER.tau), rel=1e-12)
    k = ps.critical_kappa_E
    below = physical_stability(PAPER.replace(kappa_E=0.999 * k))
    above = physical_stability(PAPER.replace(kappa_E=1.001 * k))
    assert below.growth_rate < 0 < above.growth_rate
    neg = physical_stability(PAPER.replace(kappa_E=-1.001 * k))
    assert neg.growth_rate == pytest.approx(above.growth_rate, rel=1e-9)


def test_modes_match_spectral_eigenvectors():
    g = PAPER.groups
    modes = eigenmodes(g.chi, g.eta_perp)
    sp, V, s = spectrum(g.chi, g.eta_perp, n=64, vectors=True)
    for mode in modes:
        assert mode.residual < 1e-12
        j = np.argmin(np.abs(sp.omega - mode.omega))
        if abs(sp.omega[j] - mode.omega) > 1e-8:
            j = np.argmin(np.abs(sp.omega - mode.omega.conjugate()))
        r = V[: s.size, j]
        if abs(sp.omega[j] - mode.omega) > 1e-8:
            r = r.conj()
        ri = scipy.interpolate.BarycentricInterpolator(s, r)(mode.s)
        k = np.argmax(np.abs(mode.r))
        ri = ri / ri[k]
        assert np.max(np.abs(ri - mode.r)) < 1e-7
        # real and imaginary parts are not proportional (non-reciprocal shape change)
        assert abs(np.corrcoef(mode.r.real, mode.r.imag)[0, 1]) < 0.99


def test_input_validation_names_parameter():
    with pytest.raises(ParameterError, match="eta_perp"):
        leading_eigenvalue(10.0, -1.0)
    with pytest.raises(ParameterError, match="chi"):
        leading_eigenvalue(float("nan"), 1.0)
    with pytest.raises(ParameterError, match="backend"):
        stability_map(eta_perp=[1.0, 2.0], chi=[1.0, 2.0], backend="cuda")
    with pytest.raises(ParameterError, match="eta_perp"):
        stability_map(eta_perp=[-1.0, 2.0], chi=[1.0, 2.0])
    with pytest.raises(ParameterError, match="increasing"):
        stability_map(eta_perp=[2.0, 1.0], chi=[1.0, 2.0])


@pytest.mark.parametrize("eta", [10.0, 200.0, 700.0])
def test_small_chi_limit_is_continuous_with_chi_zero(eta):
    # as chi -> 0 the leading eigenvalue tends to the exact chi = 0 value max(-1, -k1^4/eta)
    w0 = max(-1.0, -(FREE_FREE_K1**4) / eta)
    ws = [leading_eigenvalue(c, eta).omega for c in (1e-2, 1e-4, 1e-6)]
    d = [abs(w - w0) for w in ws]
    assert d[0] > d[1] > d[2] and d[2] < 1e-5
    if w0 == -1.0:
        # omega + 1 = a chi + b chi^2 + ...: (omega + 1)/chi converges linearly in chi
        r = [(w + 1) / c for w, c in zip(ws, (1e-2, 1e-4, 1e-6))]
        assert abs(r[0].imag) > 0.01
        assert 50 < abs(r[0] - r[2]) / abs(r[1] - r[2]) < 200
    m = stability_map(eta_perp=[eta], chi=[-1e-2, 0.0, 1e-4, 1e-2])
    assert abs(m.omega[0, 3] - ws[0]) <= 1e-9 and abs(m.omega[0, 2] - ws[1]) <= 1e-9
    assert m.omega[0, 1] == w0


def test_works_without_numba():
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['numba'] = None\n"
        "import numpy as np\n"
        "from flutterswim.stability import _kernels, leading_eigenvalue, neutral_curve, stability_map\n"
        "assert not _kernels.HAVE_NUMBA\n"
        "m = stability_map(eta_perp=[10.0, 71.5], chi=[-60.0, 0.0, 60.0])\n"
        "nc = neutral_curve([70.0, 71.5])\n"
        "print(repr(complex(m.omega[1, 2])), repr(float(nc.chi_cr[1])))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    w, chi_cr = (eval(x) for x in out.stdout.split())
    assert abs(w - leading_eigenvalue(60.0, 71.5).omega) <= 1e-9 * abs(w)
    assert chi_cr == pytest.approx(neutral_curve([70.0, 71.5]).chi_cr[1], rel=1e-9)
