"""The compiled kernels' on-disk cache is keyed by all the kernel sources: a kernel holds its
callees from other files, and numba alone would only notice edits to the kernel's own file."""

import shutil
from pathlib import Path

import pytest

from flutterswim import _jit


def test_an_edit_to_any_kernel_source_moves_the_cache(tmp_path):
    root = Path(_jit.__file__).resolve().parent
    for name in _jit.KERNEL_SOURCES:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(root / name, tmp_path / name)
    base = _jit._source_hash(tmp_path)
    assert base == _jit._source_hash(root)
    for name in ("activity.py", "drag.py"):  # laws compiled into the rhs, the Jacobian and the stage iteration
        text = (tmp_path / name).read_text()
        (tmp_path / name).write_text(text + "\n# edited\n")
        assert _jit._source_hash(tmp_path) != base
        (tmp_path / name).write_text(text)
    assert _jit._source_hash(tmp_path) == base


def test_kernels_are_cached_under_the_hash_and_unlisted_modules_are_refused():
    pytest.importorskip("numba")
    from numba.core import config

    from flutterswim.orbits import radau

    radau.kernels()
    assert Path(config.CACHE_DIR).name == f"kernels-{_jit._source_hash()}"
    import flutterswim.params as unlisted

    with pytest.raises(RuntimeError, match="KERNEL_SOURCES"):
        _jit.compile_module(unlisted, ("Groups",))


def _cache(base: Path, name: str, files=("a/k.py311.nbi", "a/k.py311.1.nbc"), marker=True, age_days=40.0):
    import os
    import time

    d = base / name
    for f in files:
        (d / f).parent.mkdir(parents=True, exist_ok=True)
        (d / f).write_bytes(b"x")
    if marker:
        m = d / _jit.CACHE_MARKER
        m.write_text("ours\n")
        t = time.time() - age_days * 86400.0
        os.utime(m, (t, t))
    return d


def test_only_stale_kernel_caches_that_are_provably_ours_are_pruned(tmp_path):
    keep = _cache(tmp_path, "kernels-0123456789abcdef")  # the one in use, however old its marker
    stale = _cache(tmp_path, "kernels-1111111111111111")
    recent = _cache(tmp_path, "kernels-2222222222222222", age_days=3.0)
    unmarked = _cache(tmp_path, "kernels-3333333333333333", marker=False)
    foreign = _cache(tmp_path, "kernels-4444444444444444", files=("a/k.py311.nbi", "notes.txt"))
    odd_name = _cache(tmp_path, "kernels-old")
    other = _cache(tmp_path, "results-5555555555555555")
    linked = _cache(tmp_path, "kernels-6666666666666666")
    (linked / "a" / "link.nbi").symlink_to(tmp_path / "results-5555555555555555" / "a" / "k.py311.nbi")
    removed = _jit.prune_kernel_caches(tmp_path, keep)
    assert removed == [stale] and not stale.exists()
    for d in (keep, recent, unmarked, foreign, odd_name, other, linked):
        assert d.is_dir() and any(d.rglob("*.nbi")), d
    assert (foreign / "notes.txt").read_bytes() == b"x"
    # with a shorter age the recent one goes too; the rest stay
    assert _jit.prune_kernel_caches(tmp_path, keep, max_age_days=1.0) == [recent]


def test_the_cache_in_use_is_marked(tmp_path, monkeypatch):
    pytest.importorskip("numba")
    from numba.core import config

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    old = config.CACHE_DIR
    stale = _cache(tmp_path, "kernels-1111111111111111")
    try:
        _jit._set_cache_dir()
        here = Path(config.CACHE_DIR)
        assert here == tmp_path / f"kernels-{_jit._source_hash()}"
        assert (here / _jit.CACHE_MARKER).is_file()
        assert not stale.exists()
    finally:
        config.CACHE_DIR = old
