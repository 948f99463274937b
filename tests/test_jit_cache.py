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
