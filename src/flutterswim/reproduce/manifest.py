"""The manifest: one JSON file per output folder recording, for every target, its inputs
(and their key), the package version, the wall time, and the SHA-256 of each output file.

A target is up to date when its entry has the same input key and mode (quick or full), every
listed output file still has its recorded hash, and every flutterswim source file its code
depends on (the static import closure of its build, :mod:`.sources`) is unchanged. The run
summary gives the folder's mode: quick, full, or mixed with the targets of each. The manifest
is rewritten atomically after each target, so an interrupted run keeps every target finished
before the interruption.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._json import dumps
from .io import clean_json, sha256_file

__all__ = ["Manifest", "input_key", "code_hashes", "code_fingerprint", "mode_summary", "MANIFEST_NAME"]

MANIFEST_NAME = "manifest.json"


def input_key(inputs: dict) -> str:
    """SHA-256 of the canonical JSON of the inputs."""
    text = dumps(inputs, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _root() -> Path:
    return Path(__file__).resolve().parents[1]


def code_hashes(functions: list, *, root: str | os.PathLike | None = None) -> dict[str, str]:
    """SHA-256 of each package source file the ``functions`` depend on (their static import
    closure, :func:`.sources.function_closure`; path relative to the package folder ``root``):
    the code a target was built with. A change to one of them makes the target out of date;
    edits to modules outside the closure do not."""
    from .sources import function_closure

    root = _root() if root is None else Path(root).resolve()
    files = function_closure(functions, root=root)
    return {str(p.relative_to(root)): sha256_file(p) for p in sorted(files, key=lambda p: p.relative_to(root))}


def code_fingerprint(functions: list, *, root: str | os.PathLike | None = None) -> str:
    """SHA-256 over :func:`code_hashes` (paths and digests, sorted)."""
    text = json.dumps(code_hashes(functions, root=root), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def mode_summary(modes: dict[str, str]) -> str:
    """The mode of a folder from each built target's mode: "quick", "full", or, when they differ,
    "mixed: fig6cd full; the other 12 quick" (the smaller groups by name, the largest counted)."""
    groups: dict[str, list[str]] = {}
    for name, mode in modes.items():
        groups.setdefault(mode or "mode not recorded", []).append(name)
    if len(groups) <= 1:
        return next(iter(groups), "none built")
    order = sorted(groups, key=lambda m: (-len(groups[m]), m))
    parts = [f"{', '.join(sorted(groups[m]))} {m}" for m in reversed(order[1:])]
    return f"mixed: {'; '.join(parts)}; the other {len(groups[order[0]])} {order[0]}"


@dataclass
class Manifest:
    """In-memory manifest bound to ``folder``; :meth:`save` writes it atomically."""

    folder: Path
    targets: dict[str, dict[str, Any]] = field(default_factory=dict)
    run: dict[str, Any] = field(default_factory=dict)

    @property
    def path(self) -> Path:
        return self.folder / MANIFEST_NAME

    @classmethod
    def load(cls, folder: str | os.PathLike) -> "Manifest":
        folder = Path(folder)
        p = folder / MANIFEST_NAME
        if not p.is_file():
            return cls(folder)
        try:
            data = json.loads(p.read_text())
        except (OSError, ValueError):
            return cls(folder)  # unreadable: every target reruns
        # a manifest of another shape (edited by hand: "targets": NaN made a TypeError, exit 1):
        # as unreadable; each target's entry that is not a record is dropped (it reruns)
        if not isinstance(data, dict):
            return cls(folder)
        targets, run = data.get("targets", {}), data.get("run", {})
        targets = {str(k): v for k, v in targets.items() if isinstance(v, dict)} if isinstance(targets, dict) else {}
        return cls(folder, targets, run if isinstance(run, dict) else {})

    def up_to_date(self, name: str, key: str, mode: str | None = None) -> bool:
        """``mode``: the mode asked for (a quick build is not up to date for --full, nor a full
        one for --quick); None accepts either. An entry of another shape is not (it reruns)."""
        try:
            return self._up_to_date(name, key, mode)
        except (AttributeError, TypeError, ValueError):
            return False

    def _up_to_date(self, name: str, key: str, mode: str | None) -> bool:
        e = self.targets.get(name)
        if not e or e.get("key") != key or e.get("status") not in ("ok", "skipped"):
            return False
        if mode is not None and e.get("mode") != mode:
            return False
        for rel, digest in e.get("outputs", {}).items():
            p = self.folder / rel
            if not p.is_file() or sha256_file(p) != digest:
                return False
        code = e.get("code")
        if not code:
            return False
        root = _root()
        for rel, digest in code.items():
            p = root / rel
            if not p.is_file() or sha256_file(p) != digest:
                return False
        return True

    def modes(self) -> dict[str, str]:
        """name -> mode of every target built ok ("" when an older manifest did not record it)."""
        return {k: e.get("mode", "") for k, e in self.targets.items() if e.get("status") == "ok"}

    def run_summary(self) -> dict[str, Any]:
        """``run`` (this run's settings) with the folder's mode and its quick and full targets."""
        modes = self.modes()
        text = mode_summary(modes)
        return {**self.run, "mode": text.split(":")[0], "mode_summary": text,
                "quick_targets": sorted(k for k, m in modes.items() if m == "quick"),
                "full_targets": sorted(k for k, m in modes.items() if m == "full")}

    def record(self, name: str, entry: dict[str, Any]) -> None:
        self.targets[name] = clean_json(entry)
        self.save()

    def save(self) -> Path:
        from .. import __version__
        from .._paths import atomic_path

        body = {"generator": f"flutterswim {__version__}", "run": clean_json(self.run_summary()),
                "targets": {k: self.targets[k] for k in sorted(self.targets)}}
        with atomic_path(self.path) as tmp:
            tmp.write_text(json.dumps(body, indent=1, sort_keys=True, allow_nan=False) + "\n")
        return self.path
