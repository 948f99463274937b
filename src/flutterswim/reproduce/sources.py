"""The flutterswim source files a function depends on, read from the sources alone (``ast``),
never from what happens to be imported in the process.

The closure is taken over top-level definitions: a reached function or class (whole, with its
methods) reaches the names it uses, resolved through its module's imports and its own
(function-level) imports, relative imports included; a reached module runs its top-level
statements, whose names are reached too (registries, decorators, kernels compiled at import).
A module is a dependency when any of it is reached; its parent packages' ``__init__`` files,
which run first, are hashed as well, but what they import is not followed: flutterswim's
``__init__`` files only import and re-export, so they run definitions, not code (followed,
``reproduce/__init__`` would make every target depend on the catalog of all the others). A module-level import alone reaches the imported module's
top level, not every function in it, so a lazy import in a helper nobody calls (``_paths``
importing ``tracking`` to recognise a CSV) does not drag a package into every closure.
Not seen: code found by a computed name (``getattr(module, "f" + x)``); flutterswim has none.
"""

from __future__ import annotations

import ast
import sys
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["PACKAGE", "package_root", "module_file", "function_closure"]

PACKAGE = "flutterswim"
# decorators that only wrap what they decorate (they register nothing to be found by name)
_PLAIN_DECORATORS = {"dataclass", "dataclasses", "functools", "contextlib", "contextmanager", "property",
                     "staticmethod", "classmethod", "cached_property", "lru_cache", "cache", "wraps",
                     "overload", "abstractmethod", "total_ordering"}


def package_root() -> Path:
    return Path(__file__).resolve().parents[1]


def module_file(name: str, root: Path) -> Path | None:
    """The source file of package module ``name`` under ``root`` (the package folder), or None."""
    parts = name.split(".")
    if parts[0] != PACKAGE:
        return None
    base = root.joinpath(*parts[1:])
    for p in (base / "__init__.py", base.with_suffix(".py")):
        if p.is_file():
            return p
    return None


@dataclass
class _Module:
    name: str
    package: str  # for relative imports
    tree: ast.Module
    defs: dict[str, ast.AST] = field(default_factory=dict)
    bound: dict[str, tuple[str, str | None]] = field(default_factory=dict)  # name -> (module, attr | None)
    lazy: dict[str, tuple[str, str]] = field(default_factory=dict)  # served by a module __getattr__
    reach: dict[str, set] = field(default_factory=dict)  # def name (or "" for the top level) -> refs


def _absolute(mod: _Module, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    parts = mod.package.split(".")
    if node.level - 1 >= len(parts) or not mod.package:
        return ""
    base = ".".join(parts[:len(parts) - node.level + 1])
    return f"{base}.{node.module}" if node.module else base


def _bindings(mod: _Module, node: ast.Import | ast.ImportFrom) -> dict[str, tuple[str, str | None]]:
    """Names an import statement binds: name -> (module, None) for a module, (module, attr)."""
    out: dict[str, tuple[str, str | None]] = {}
    if isinstance(node, ast.Import):
        for a in node.names:
            out[a.asname or a.name.split(".")[0]] = (a.name if a.asname else a.name.split(".")[0], None)
    else:
        src = _absolute(mod, node)
        for a in node.names:
            if a.name != "*":
                out[a.asname or a.name] = (src, a.name)
    return out


def _lazy_table(tree: ast.Module) -> dict[str, tuple[str, str]]:
    """flutterswim's ``_LAZY`` table: name -> (module, attr), from top-level dicts whose values
    name modules (a string, or a (module, attr) tuple), keys given or from a comprehension."""
    out: dict[str, tuple[str, str]] = {}
    for node in tree.body:
        value = node.value if isinstance(node, (ast.Assign, ast.AnnAssign)) else None
        if not isinstance(value, ast.Dict):
            continue
        for k, v in zip(value.keys, value.values):
            if k is None and isinstance(v, ast.DictComp):
                pairs = [(e.value, v.value) for e in ast.walk(v.generators[0].iter) if isinstance(e, ast.Constant)]
            else:
                pairs = [(k.value, v)] if isinstance(k, ast.Constant) else []
            for n, m in pairs:
                attr = n
                if isinstance(m, ast.Tuple) and len(m.elts) == 2 and isinstance(m.elts[1], ast.Constant):
                    m, attr = m.elts[0], m.elts[1].value
                if isinstance(n, str) and isinstance(m, ast.Constant) and isinstance(m.value, str):
                    out[n] = (m.value, attr)
    return out


_PARSED: dict[tuple, _Module] = {}  # (name, path, mtime, size) -> parsed module, with its refs


class _Graph:
    def __init__(self, root: Path):
        self.root = root
        self.cache: dict[str, _Module | None] = {}

    def module(self, name: str, path: Path | None = None) -> _Module | None:
        if name not in self.cache:
            path = path or module_file(name, self.root)
            if path is None:
                self.cache[name] = None
                return None
            st = path.stat()
            key = (name, str(path), st.st_mtime_ns, st.st_size)
            if key in _PARSED:
                self.cache[name] = _PARSED[key]
                return _PARSED[key]
            tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
            pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
            m = _Module(name, pkg, tree)
            for node in tree.body:
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    m.defs[node.name] = node
                elif isinstance(node, (ast.Import, ast.ImportFrom)):
                    m.bound.update(_bindings(m, node))
            if "__getattr__" in m.defs:
                m.lazy = _lazy_table(tree)
            self.cache[name] = _PARSED[key] = m
        return self.cache[name]

    def is_module(self, name: str) -> bool:
        return module_file(name, self.root) is not None

    def refs(self, mod: _Module, nodes: list[ast.AST]) -> set[tuple]:
        """What ``nodes`` of ``mod`` reach: ("mod", M) or ("name", M, attr) or ("unit", M, def)."""
        local: dict[str, tuple[str, str | None]] = {}
        out: set[tuple] = set()
        for top in nodes:
            for n in ast.walk(top):
                if isinstance(n, (ast.Import, ast.ImportFrom)):
                    b = _bindings(mod, n)
                    local.update(b)
                    # running it runs the modules' top levels; the names count where they are used
                    for src, attr in b.values():
                        out.add(("mod", src))
                        if attr is not None and self.is_module(f"{src}.{attr}"):
                            out.add(("mod", f"{src}.{attr}"))
                    if isinstance(n, ast.Import):
                        out.update(("mod", a.name) for a in n.names)

        def resolve(name: str) -> tuple | None:
            if name in local:
                src, attr = local[name]
            elif name in mod.bound:
                src, attr = mod.bound[name]
            elif name in mod.defs:
                return ("unit", mod.name, name)
            else:
                return None
            return ("mod", src) if attr is None else ("name", src, attr)

        for top in nodes:
            for n in ast.walk(top):
                if isinstance(n, ast.Name):
                    r = resolve(n.id)
                    if r:
                        out.add(r)
                elif isinstance(n, ast.Attribute):  # module.attr, module.sub.attr
                    chain, v = [n.attr], n.value
                    while isinstance(v, ast.Attribute):
                        chain.append(v.attr)
                        v = v.value
                    r = resolve(v.id) if isinstance(v, ast.Name) else None
                    if r and r[0] != "unit":
                        m = r[1] if r[0] == "mod" else f"{r[1]}.{r[2]}"
                        for a in reversed(chain):
                            if not self.is_module(m):
                                break
                            out.add(("name", m, a))
                            m = f"{m}.{a}"
        return {r for r in out if r[1].split(".")[0] == PACKAGE or r[1] == mod.name}

    def body(self, mod: _Module) -> list[ast.AST]:
        """Top-level code run on import: all but plain definitions (decorated ones may register)."""
        out = []
        for node in mod.tree.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                heads = [d.func if isinstance(d, ast.Call) else d for d in node.decorator_list]
                roots = []
                for d in heads:
                    while isinstance(d, ast.Attribute):
                        d = d.value
                    roots.append(d.id if isinstance(d, ast.Name) else "")
                if all(r in _PLAIN_DECORATORS for r in roots):
                    continue
            out.append(node)
        return out


def function_closure(functions: list, *, root: str | Path | None = None) -> set[Path]:
    """The package source files the ``functions`` (Python functions) depend on, under ``root``
    (the package folder; default this installed package). A function outside the package
    (a test's) starts from its enclosing top-level definition in its own file."""
    g = _Graph(package_root() if root is None else Path(root))
    todo: list[tuple] = []
    for f in functions:
        name, top = f.__module__, f.__qualname__.split(".")[0]
        path = None
        if name.split(".")[0] != PACKAGE:  # a test's function: its own file, if it has one
            file = getattr(sys.modules.get(name), "__file__", None)
            if not file or not Path(file).is_file():
                continue
            path, name = Path(file), f"__outside__.{name}"
        mod = g.module(name, path)
        if mod is None:
            continue
        todo.append(("unit", name, top) if top in mod.defs else ("mod", name))
    seen: set[tuple] = set()
    reached: set[str] = set()
    while todo:
        item = todo.pop()
        if item in seen:
            continue
        seen.add(item)
        kind, name = item[0], item[1]
        mod = g.module(name)
        if mod is None:
            continue
        if kind in ("mod", "unit"):
            unit = "" if kind == "mod" else item[2]
            if unit not in mod.reach:
                mod.reach[unit] = g.refs(mod, [mod.defs[unit]] if unit else g.body(mod))
            todo += sorted(mod.reach[unit])
            if kind == "mod":
                reached.add(name)
            else:
                todo.append(("mod", name))
        else:  # ("name", module, attr)
            attr = item[2]
            todo.append(("mod", name))
            if g.is_module(f"{name}.{attr}"):
                todo.append(("mod", f"{name}.{attr}"))
            if attr in mod.defs:
                todo.append(("unit", name, attr))
            elif attr in mod.bound:
                src, a = mod.bound[attr]
                todo.append(("mod", src) if a is None else ("name", src, a))
            elif attr in mod.lazy:
                todo.append(("name", *mod.lazy[attr]))
    files = set()
    for name in reached:
        parts = name.split(".")
        if parts[0] != PACKAGE:
            continue
        for i in range(1, len(parts) + 1):  # the parent packages run first
            p = module_file(".".join(parts[:i]), g.root)
            if p is not None:
                files.add(p)
    return files
