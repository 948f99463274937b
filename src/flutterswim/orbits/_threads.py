"""The orbit solvers factor and multiply small matrices (N ~ 100): BLAS threads only cost."""

from __future__ import annotations

import functools


def one_blas_thread(func):
    """Run ``func`` with BLAS limited to one thread (threadpoolctl)."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        from ..simulate import single_blas_thread

        with single_blas_thread():
            return func(*args, **kwargs)

    return wrapper
