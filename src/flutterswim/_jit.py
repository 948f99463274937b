"""Compile kernels with numba when it is installed; plain Python otherwise.

Each kernel is written once, as a Python function on arrays. :func:`compile_module`
replaces a module's kernels by numba-compiled versions on first use (importing numba costs
tens of MB, so it is not done at ``import flutterswim``). Kernels that call other kernels
find the compiled callees through the module's globals, so callees are listed first.
"""

from __future__ import annotations

import importlib
from types import ModuleType

_DONE: dict[str, bool] = {}


def have_numba() -> bool:
    try:
        import numba  # noqa: F401
    except ImportError:  # pragma: no cover - the plain-Python kernels are used
        return False
    return True


def compile_module(module: ModuleType | str, names: tuple[str, ...]) -> bool:
    """Compile ``names`` of ``module`` in place (once). False if numba is not installed."""
    mod = importlib.import_module(module) if isinstance(module, str) else module
    key = mod.__name__
    if key not in _DONE:
        ok = have_numba()
        if ok:
            from numba import njit

            for name in names:
                setattr(mod, name, njit(cache=True)(getattr(mod, name)))
        _DONE[key] = ok
    return _DONE[key]
