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


#: Every file with compiled kernels (or the laws compiled into them), relative to the package.
KERNEL_SOURCES = ("_jit.py", "drag.py", "activity.py", "mobility.py", "rosw.py", "ndf.py", "orbits/radau.py",
                  "analysis/intersection.py")


def _source_hash(root=None) -> str:
    """Hash of the kernels' source files. numba's on-disk cache checks only the file of each
    compiled function, but a kernel has its callees from other files compiled into it (the
    Radau stage iteration holds the rhs, which holds the drag and activity laws): after an
    edit, cached kernels could silently run the old physics. So the cache lives in a
    directory named by this hash."""
    import hashlib
    from pathlib import Path

    root = Path(__file__).resolve().parent if root is None else Path(root)
    h = hashlib.sha1()
    for name in KERNEL_SOURCES:
        h.update(name.encode())
        h.update((root / name).read_bytes())
    return h.hexdigest()[:16]


def _set_cache_dir() -> None:
    """Point numba's cache at a directory keyed by :func:`_source_hash` (under the user's
    NUMBA_CACHE_DIR if set, else the user cache directory); left as it is if that cannot be
    made."""
    import os
    from pathlib import Path

    from numba.core import config

    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "flutterswim")
    path = Path(base) / f"kernels-{_source_hash()}"
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return
    config.CACHE_DIR = str(path)


def compile_module(module: ModuleType | str, names: tuple[str, ...]) -> bool:
    """Compile ``names`` of ``module`` in place (once). False if numba is not installed."""
    mod = importlib.import_module(module) if isinstance(module, str) else module
    key = mod.__name__
    if key not in _DONE:
        rel = key.split(".", 1)[1].replace(".", "/") + ".py"
        if rel not in KERNEL_SOURCES:
            raise RuntimeError(f"{rel} has kernels: list it in flutterswim._jit.KERNEL_SOURCES")
        ok = have_numba()
        if ok:
            from numba import njit

            if not _DONE:
                _set_cache_dir()

            for name in names:
                setattr(mod, name, njit(cache=True)(getattr(mod, name)))
        _DONE[key] = ok
    return _DONE[key]
