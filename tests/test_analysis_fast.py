"""The fast analysis paths (issue 10) against direct computations: turning-pruned
self-intersection counts, the Fourier peak-to-peak, sub-frame section crossings, and
descriptors of a long run from its cycles' frames only."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flutterswim.analysis import intersection
from flutterswim.analysis.descriptors import _fourier_p2p
from flutterswim.analysis.section import _local_root


def _curly(seed: int, frames: int = 200, n: int = 40, spread: float = 0.6):
    th = np.cumsum(np.random.default_rng(seed).normal(0.0, spread, (frames, n)), axis=1)
    x = np.concatenate([np.zeros((frames, 1)), np.cumsum(np.cos(th), axis=1)], axis=1)
    y = np.concatenate([np.zeros((frames, 1)), np.cumsum(np.sin(th), axis=1)], axis=1)
    return x, y


@pytest.mark.parametrize("seed,spread", [(0, 0.6), (1, 0.3), (2, 1.2)])
def test_pruned_counts_equal_all_pairs(seed, spread):
    """Pruning by turning (a crossing needs more than pi of turning between the two segments)
    drops no crossing: counts equal the test of every non-adjacent pair."""
    pytest.importorskip("numba")
    import sys

    from flutterswim import _jit

    mod = sys.modules[intersection.__name__]
    _jit.compile_module(mod, ("count_pruned",))
    x, y = _curly(seed, spread=spread)
    pruned = mod.count_pruned(x, y, np.empty(x.shape[0], np.int64))
    full = intersection._intersect_frames(x, y, 0.0)
    assert full.sum() > 0 and np.count_nonzero(full == 0) > 0  # both kinds of frames occur
    assert np.array_equal(pruned, full)


def test_fourier_p2p_of_a_known_series():
    """q = cos 2 pi p + 0.3 sin 6 pi p sampled unevenly: the fitted series is q itself, whose
    peak-to-peak follows from a fine grid."""
    rng = np.random.default_rng(4)
    p = np.sort(rng.uniform(0.0, 1.0, 40))
    f = lambda v: np.cos(2 * np.pi * v) + 0.3 * np.sin(6 * np.pi * v)  # noqa: E731
    fine = f(np.linspace(0.0, 1.0, 2_000_001))
    # the grid extremum refined by a parabola: error ~ (2 pi 3 / 256)^4 / 24 ~ 1e-6 of the amplitude
    assert _fourier_p2p(p, f(p), 6) == pytest.approx(fine.max() - fine.min(), rel=1e-5)


def test_local_root_of_a_cubic():
    """d(t) = (t - r)(1 + (t - r)^2) sampled on a grid: the local cubic fit is exact."""
    t = np.linspace(0.0, 1.0, 101)
    r = 0.4137
    d = (t - r) * (1 + (t - r) ** 2)
    m = int(np.searchsorted(t, r)) - 1
    assert _local_root(t, d, m, 0.05, 3) == pytest.approx(r, abs=1e-12)
    assert math.isfinite(_local_root(t, d, m, 0.0, 3))  # no window: the linear root


def test_batched_roots_equal_one_by_one():
    """The batched sub-frame roots of section crossings equal the scalar fits."""
    from flutterswim.analysis.section import _local_roots

    rng = np.random.default_rng(5)
    t = np.sort(rng.uniform(0.0, 10.0, 600))
    d = np.sin(2.0 * np.pi * t / 1.3) + 0.01 * rng.normal(size=t.size)
    ms = np.nonzero((d[:-1] <= 0) & (d[1:] > 0))[0]
    one = np.array([_local_root(t, d, int(m), 0.1, 3) for m in ms])
    assert np.allclose(_local_roots(t, d, ms, 0.1, 3), one, rtol=0, atol=1e-12)
