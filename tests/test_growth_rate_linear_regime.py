"""describe's growth rate of the onset against linear stability theory.

The envelope of a run grows at the leading eigenvalue's real part only while the stroke is
small: the straight filament's linear regime. Beyond it (for the paper's filament, a tangent-angle
deflection of about 0.1 rad, one to a few % of the settled stroke's lateral amplitude) the tip's
lateral amplitude grows faster, by 3-13 % at a tenth of its final size when kappa_E is 1.2-2 times the
paper's. The reference is the discrete model's own leading eigenvalue at the run's N (the Jacobian
of the shape dynamics at the straight state, an independent linear computation; within 0.1 % of
the continuum theory's at N = 48, 0.6 % near the threshold)."""

import math

import pytest

import flutterswim as fs
from flutterswim.analysis.descriptors import describe
from flutterswim.initial import InitialState
from flutterswim.orbits.linear import leading_pair
from flutterswim.simulate import simulate

N = 48


def _run(ratio: float, t_end: float, tilt_deg: float = 0.01):
    p = fs.PAPER.replace(kappa_E=fs.PAPER.kappa_E * ratio)
    res = simulate(p, t_end, n_segments=N, initial=InitialState.straight(tilt_deg))
    d = describe(res)
    lam = leading_pair(p, N).real / p.tau
    # the discrete model's eigenvalue is the continuum theory's at this N (second order in 1/N;
    # 0.6 % of the small rate at 0.8, 0.06 % at 2)
    assert lam == pytest.approx(fs.physical_stability(p).growth_rate, rel=1e-2)
    return d, lam


def _agrees(d, lam) -> bool:
    rate, se = d.growth_rate_per_s, d.growth_rate_stderr_per_s
    return abs(rate - lam) <= max(2.0 * se, 1e-2 * lam)


@pytest.mark.parametrize("ratio, t_end", [(0.8, 20.0), (1.2, 8.0), (1.5, 6.0), (2.0, 5.0)])
def test_the_paper_start_gives_the_linear_rate_or_none(ratio, t_end):
    """From the paper's start (0.01 degree from straight), as ``flutterswim simulate
    --kappa-E-ratio K`` runs it: the growth rate agrees with the leading eigenvalue within
    max(2 standard errors, 1 %), or, where the start's transient (two relaxation times) and the
    end of the linear regime leave too few cycles to fit (fast growth), is not given (NaN) and the
    note says why. Before, the fit reached a tenth of the final amplitude: +2.8 % at 1.2 (3.7
    standard errors), +5.1 % at 1.5 (4.3), +4.6 % at 2 (91)."""
    d, lam = _run(ratio, t_end)
    if ratio <= 1.2:  # slow growth: linear cycles enough
        assert math.isfinite(d.growth_rate_per_s)
    if math.isfinite(d.growth_rate_per_s):
        assert _agrees(d, lam), (d.growth_rate_per_s, d.growth_rate_stderr_per_s, lam)
    else:
        assert "growth rate not measured" in d.note and "linear regime" in d.note


@pytest.mark.parametrize("ratio", [1.5, 2.0])
def test_a_fast_growth_from_closer_to_straight_gives_the_linear_rate(ratio):
    """Started 1e-4 degree from straight, a fast growth (kappa_E 1.5 and 2 times the paper's)
    spends several cycles in the linear regime after its start's transient: the growth rate is
    measured and agrees with the leading eigenvalue within max(2 standard errors, 1 %) (before,
    +1.4 % at 2: 2.1 standard errors)."""
    d, lam = _run(ratio, 7.0, tilt_deg=1e-4)
    assert math.isfinite(d.growth_rate_per_s)
    assert _agrees(d, lam), (d.growth_rate_per_s, d.growth_rate_stderr_per_s, lam)
