"""BLAS threads are limited inside simulate: no user has to set OPENBLAS_NUM_THREADS."""

import os
import time

import numpy as np
from threadpoolctl import threadpool_info, threadpool_limits

import flutterswim as fs


def _blas_threads() -> int:
    return max((i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"), default=1)


def test_simulate_runs_with_one_blas_thread():
    seen = []

    def check(t, y):
        seen.append(_blas_threads())
        return None

    with threadpool_limits(limits=max(2, os.cpu_count() or 2), user_api="blas"):
        before = _blas_threads()
        fs.simulate(fs.PAPER, 0.05, n_segments=24, check=check)
        after = _blas_threads()
    assert seen and max(seen) == 1
    assert after == before  # restored afterwards


def _wall(n_repeat=3):
    best = np.inf
    for _ in range(n_repeat):
        t0 = time.perf_counter()
        fs.simulate(fs.PAPER, 1.5, n_segments=96)
        best = min(best, time.perf_counter() - t0)
    return best


def test_n96_default_threads_within_1p5x_of_one_thread():
    """The issue's measure: a run at N = 96 with the default thread count against the same run
    with one BLAS thread (min of 3 each, interleaved)."""
    fs.simulate(fs.PAPER, 0.05, n_segments=96)  # warm up (numba cache, imports)
    with threadpool_limits(limits=1, user_api="blas"):
        one = _wall()
    # the machine's default (one BLAS thread per core), even if the test runner set
    # OPENBLAS_NUM_THREADS=1; without the limit inside simulate this ran 13x to 110x slower here
    with threadpool_limits(limits=max(2, os.cpu_count() or 2), user_api="blas"):
        default = _wall()
    assert default < 1.5 * one, (default, one)
