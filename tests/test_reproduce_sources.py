"""A reproduce target's code fingerprint covers the modules its build depends on (the static
import closure), not every flutterswim module loaded in the process: an edit to a module
outside the closure leaves it unchanged, an edit inside (down to the physics core) changes it.
Edits are made to a temporary copy of the package, never to the sources."""

from __future__ import annotations

import shutil
import textwrap
from pathlib import Path

import pytest

import flutterswim
from flutterswim.reproduce.catalog import TARGETS
from flutterswim.reproduce.manifest import code_fingerprint, code_hashes
from flutterswim.reproduce.sources import function_closure
from flutterswim.reproduce.targets import build_targets

BY_NAME = {t.name: t for t in TARGETS}


def _functions(name):
    t = BY_NAME[name]
    return [t.build, t.params, build_targets]


def _copy_package(tmp_path) -> Path:
    root = tmp_path / "flutterswim"
    shutil.copytree(Path(flutterswim.__file__).parent, root, ignore=shutil.ignore_patterns("__pycache__"))
    return root


def _touch(path: Path) -> None:
    path.write_text(path.read_text() + "\n# an edit\n")


def test_fingerprint_follows_the_closure_not_the_process(tmp_path):
    import flutterswim.tracking.segment  # noqa: F401 - loaded in this process, as by the CLI

    root = _copy_package(tmp_path)
    before = {n: code_fingerprint(_functions(n), root=root) for n in ("fig6b", "table1", "paper_run")}
    hashes = code_hashes(_functions("fig6b"), root=root)
    assert "tracking/segment.py" not in hashes
    assert {"reproduce/figures_stability.py", "reproduce/targets.py", "filament.py"} <= set(hashes)
    _touch(root / "tracking" / "segment.py")  # used by no target
    assert {n: code_fingerprint(_functions(n), root=root) for n in before} == before
    _touch(root / "stability" / "modes.py")  # Fig. 6c-d's eigenmodes, not Table 1 or the run
    assert "stability/modes.py" in code_hashes(_functions("fig6cd"), root=root)
    assert code_fingerprint(_functions("table1"), root=root) == before["table1"]
    assert code_fingerprint(_functions("paper_run"), root=root) == before["paper_run"]
    _touch(root / "filament.py")  # the physics core, reached through the imports
    after = {n: code_fingerprint(_functions(n), root=root) for n in before}
    assert all(after[n] != before[n] for n in before)


def _write(root: Path, files: dict[str, str]) -> None:
    for rel, text in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(textwrap.dedent(text))


def _fn(module: str, name: str):
    def f():
        pass

    f.__module__, f.__qualname__ = module, name
    return f


def test_closure_rules_on_a_small_package(tmp_path):
    """Relative and function-level imports are followed; a lazy import in a helper nobody
    reaches is not; a registry at module level reaches what it lists; a name served by the
    package's ``__getattr__`` table reaches its module; parent packages' ``__init__`` count."""
    root = tmp_path / "flutterswim"
    _write(root, {
        "__init__.py": """
            _LAZY = {**{n: "flutterswim.lazy" for n in ("served",)}}
            def __getattr__(name):
                import importlib
                return getattr(importlib.import_module(_LAZY[name]), name)
            """,
        "main.py": """
            from . import util
            from .sub import deep
            def build():
                from .local import helper
                return helper() + util.CONST + deep.g()
            def unused():
                from . import never
            """,
        "util.py": "CONST = 1\n",
        "local.py": """
            from flutterswim import served
            def helper():
                return served()
            """,
        "lazy.py": "def served():\n    return 2\n",
        "sub/__init__.py": "",
        "sub/deep.py": """
            def g():
                from ..registry import run
                return run("a")
            """,
        "registry.py": """
            def _a():
                from .reg_a import value
                return value
            def _b():
                from .reg_b import value
                return value
            def _csv():
                from .tracking_like import CSV
                return CSV
            METHODS = {"a": _a, "b": _b}
            def run(name):
                return METHODS[name]()
            """,
        "reg_a.py": "value = 1\n", "reg_b.py": "value = 2\n", "tracking_like.py": "CSV = ()\n",
        "never.py": "", "other/__init__.py": "", "other/mod.py": "",
    })
    got = {str(p.relative_to(root)) for p in function_closure([_fn("flutterswim.main", "build")], root=root)}
    assert got == {"__init__.py", "main.py", "util.py", "local.py", "lazy.py", "sub/__init__.py", "sub/deep.py",
                   "registry.py", "reg_a.py", "reg_b.py"}


def test_closure_holds_every_function_a_build_runs(tmp_path):
    """Independent check: profile a build and ask that every flutterswim function it runs
    (not module or class bodies: definitions) comes from a file in the static closure."""
    import sys
    import threading

    pytest.importorskip("matplotlib")
    from flutterswim.reproduce.sources import package_root
    from flutterswim.reproduce.targets import Context, Settings

    root = package_root()
    for name in ("table1", "fig6cd"):
        ran: set[str] = set()

        def prof(frame, event, arg, ran=ran):
            if event == "call" and frame.f_code.co_flags & 1:  # CO_OPTIMIZED: a function
                ran.add(frame.f_code.co_filename)

        t = BY_NAME[name]
        sys.setprofile(prof)
        threading.setprofile(prof)
        try:
            t.build(Context(tmp_path, Settings("quick"), {}))
        finally:
            sys.setprofile(None)
            threading.setprofile(None)
        files = {Path(f).resolve() for f in ran if f.endswith(".py")}
        files = {p for p in files if root in p.parents}
        assert len(files) >= 3  # the build, its io, the physics it uses
        assert files <= function_closure(_functions(name)), name
