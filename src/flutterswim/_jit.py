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


#: The file that marks a kernel cache directory as flutterswim's; its mtime is the last use.
CACHE_MARKER = "flutterswim-kernels.txt"
#: Kernel caches of other source versions unused for this many days are removed.
STALE_DAYS = 30.0


def prune_kernel_caches(base, keep, *, max_age_days: float = STALE_DAYS, now: float | None = None) -> list:
    """Remove the kernel caches under ``base``, other than ``keep``, that are provably ours and
    stale. A directory is removed only if it is named ``kernels-<16 hex digits>``, holds
    :data:`CACHE_MARKER` last touched more than ``max_age_days`` ago, and holds nothing but
    numba's cache files (``.nbi``, ``.nbc``) in plain folders (no symbolic links). Anything
    else is left alone, and an error leaves that directory as it is. Returns the removed
    directories."""
    import re
    import time
    from pathlib import Path

    now = time.time() if now is None else float(now)
    removed = []
    for d in sorted(Path(base).glob("kernels-*")):
        if d == Path(keep) or d.is_symlink() or not d.is_dir() or not re.fullmatch(r"kernels-[0-9a-f]{16}", d.name):
            continue
        marker = d / CACHE_MARKER
        try:
            if not marker.is_file() or now - marker.stat().st_mtime < max_age_days * 86400.0:
                continue
            entries = list(d.rglob("*"))
            if any(e.is_symlink() for e in entries):
                continue
            files = [e for e in entries if not e.is_dir()]
            if any(f != marker and f.suffix not in (".nbi", ".nbc") for f in files):
                continue
            for f in files:
                f.unlink()
            for sub in sorted((e for e in entries if e.is_dir()), key=lambda e: len(e.parts), reverse=True):
                sub.rmdir()
            d.rmdir()
            removed.append(d)
        except OSError:
            continue
    return removed


#: whether numba caches the compiled kernels (False: no writable folder for them was found)
_CACHE = True


def _private(folder) -> bool:
    """A folder of this user's that no one else may write (numba unpickles its cache index: a
    shared temporary folder another user made, or may write into, is not used)."""
    import os
    import stat

    try:
        if os.lstat(folder).st_uid != os.getuid() or os.path.islink(folder):
            return False  # (never changed: not ours)
        os.chmod(folder, 0o700)
        st = os.lstat(folder)
    except OSError:
        return False
    return st.st_uid == os.getuid() and not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)


def _set_cache_dir() -> None:
    """Point numba's cache at a directory keyed by :func:`_source_hash` (under the user's
    NUMBA_CACHE_DIR if set, else the user cache directory); left as it is if that cannot be
    made. The directory is marked as used now (:data:`CACHE_MARKER`), and the caches of other
    kernel versions unused for :data:`STALE_DAYS` are removed (:func:`prune_kernel_caches`)."""
    import os
    from pathlib import Path

    from numba.core import config

    import tempfile

    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "flutterswim")
    # a read-only home and install (an HPC node, a container) left numba nowhere to write, and
    # every run failed ("cannot cache function ...: no locator available"): a temporary folder
    # then, else no cache (compiled anew in each process)
    user = getattr(os, "getuid", lambda: "")()
    for root in (Path(base), Path(tempfile.gettempdir()) / f"flutterswim-{user}"):
        path = root / f"kernels-{_source_hash()}"
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError:
            continue
        if os.access(path, os.W_OK | os.X_OK) and (root == Path(base) or _private(root)):
            break
    else:
        global _CACHE
        _CACHE = False
        return
    config.CACHE_DIR = str(path)
    marker = path / CACHE_MARKER
    try:
        if marker.is_file():
            os.utime(marker)
        else:
            marker.write_text("numba's cache of flutterswim's compiled kernels; flutterswim removes it when "
                              f"unused for {STALE_DAYS:g} days\n")
        prune_kernel_caches(path.parent, path)
    except OSError:
        pass


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
                setattr(mod, name, njit(cache=_CACHE)(getattr(mod, name)))
        _DONE[key] = ok
    return _DONE[key]
