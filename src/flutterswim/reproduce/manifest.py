"""The manifest: one JSON file per output folder recording, for every target, its inputs
(and their key), the package version, the wall time, and the SHA-256 of each output file.

A target is up to date when its entry has the same input key, every listed output file
still has its recorded hash, and every flutterswim source file loaded when it was built is
unchanged. The manifest is rewritten atomically after each target, so an
interrupted run keeps every target finished before the interruption.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .io import clean_json, sha256_file

__all__ = ["Manifest", "input_key", "code_hashes", "code_fingerprint", "MANIFEST_NAME"]

MANIFEST_NAME = "manifest.json"


def input_key(inputs: dict) -> str:
    """SHA-256 of the canonical JSON of the inputs."""
    text = json.dumps(clean_json(inputs), sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def _root() -> Path:
    return Path(__file__).resolve().parents[1]


def code_hashes() -> dict[str, str]:
    """SHA-256 of the source of every flutterswim module loaded so far (path relative to the
    package) plus the report template: the code a target was built with. A change to one of
    them makes the target out of date; edits to modules it never loaded do not."""
    import sys

    root = _root()
    out = {}
    for name, mod in list(sys.modules.items()):
        f = getattr(mod, "__file__", None)
        if not (name == "flutterswim" or name.startswith("flutterswim.")) or not f:
            continue
        p = Path(f).resolve()
        if p.suffix == ".py" and p.is_file() and root in p.parents:
            out[str(p.relative_to(root))] = sha256_file(p)
    for p in sorted((root / "reproduce" / "templates").glob("*.j2")):
        out[str(p.relative_to(root))] = sha256_file(p)
    return dict(sorted(out.items()))


def code_fingerprint() -> str:
    """SHA-256 over all the package's Python sources (paths and contents, sorted)."""
    root = _root()
    h = hashlib.sha256()
    for p in sorted(root.rglob("*.py")) + sorted(root.rglob("*.j2")):
        h.update(str(p.relative_to(root)).encode())
        h.update(b"\0")
        h.update(p.read_bytes())
    return h.hexdigest()


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
        return cls(folder, dict(data.get("targets", {})), dict(data.get("run", {})))

    def up_to_date(self, name: str, key: str) -> bool:
        e = self.targets.get(name)
        if not e or e.get("key") != key or e.get("status") not in ("ok", "skipped"):
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

    def record(self, name: str, entry: dict[str, Any]) -> None:
        self.targets[name] = clean_json(entry)
        self.save()

    def save(self) -> Path:
        from .. import __version__
        from .._paths import atomic_path

        body = {"generator": f"flutterswim {__version__}", "run": clean_json(self.run),
                "targets": {k: self.targets[k] for k in sorted(self.targets)}}
        with atomic_path(self.path) as tmp:
            tmp.write_text(json.dumps(body, indent=1, sort_keys=True, allow_nan=False) + "\n")
        return self.path
