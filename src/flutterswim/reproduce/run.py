"""``reproduce``: build the targets into a folder and write the report."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .._validate import ParameterError
from .targets import Settings, TargetRecord, build_targets

__all__ = ["ReproduceResult", "reproduce", "check_out"]

STORE_KIND = "reproduce"


@dataclass(frozen=True)
class ReproduceResult:
    """out: the folder; report: the HTML file; records: name -> TargetRecord; wall_time [s]."""

    out: Path
    report: Path
    records: dict[str, TargetRecord]
    wall_time: float

    @property
    def failed(self) -> list[str]:
        return [k for k, r in self.records.items() if r.status == "failed"]

    @property
    def ok(self) -> bool:
        return not self.failed


def check_out(out: str | os.PathLike, targets) -> Path:
    """The output folder: new, empty, or one of ours (marker file); every output file it would
    replace must have been written by flutterswim. Checked before any computation."""
    from .._paths import MARKER, check_files_in, check_store_path

    p = check_store_path(out, overwrite=False, what="--out", kind=STORE_KIND)
    names = ["report.html", "manifest.json"] + [f for t in targets for f in t.outputs]
    # (named as an output: "--out='c/fig6b.nc'" misnamed the folder given as c)
    check_files_in(p, names, what="output")
    del MARKER
    _check_unedited(p, targets)
    return p


def _check_unedited(folder: Path, targets) -> None:
    """An output the manifest records with another SHA-256 than the file's was changed after
    flutterswim wrote it (an edit saved through xarray keeps our signature): it is the user's
    now, and is not replaced. A target being built records no hashes until it is done, so the
    files of an interrupted build are not taken for edits."""
    from .io import sha256_file
    from .manifest import Manifest

    if not (folder / "manifest.json").is_file():
        return
    man = Manifest.load(folder)
    for t in targets:
        for rel, digest in man.targets.get(t.name, {}).get("outputs", {}).items():
            f = folder / rel
            if f.is_file() and sha256_file(f) != digest:
                raise ParameterError(
                    f"--out={str(folder)!r}: {rel} was changed after flutterswim wrote it (its SHA-256 is not the "
                    "one in manifest.json), so it is not replaced: move it elsewhere, or delete it to have it rebuilt")


def reproduce(out: str | os.PathLike, *, mode: str = "quick", trials: str | os.PathLike | None = None,
              targets: list[str] | None = None, force: bool = False,
              log: Callable[[str], None] | None = None) -> ReproduceResult:
    """Build every model figure and table of the paper (or the named ``targets`` and what they
    need) into ``out``, skipping targets that are up to date, and write ``report.html``."""
    from .._paths import write_marker
    from .catalog import select
    from .report import write_report

    t0 = time.perf_counter()
    settings = Settings(mode=mode, trials=None if trials is None else str(Path(trials).resolve()))
    if trials is not None and not Path(trials).is_file():
        raise ParameterError(f"trials={str(trials)!r} is not a file")
    todo = select(targets)
    if trials is not None:  # (also when fig3e is not built now: a bad CSV given is bad input)
        from .figures_fitting import fitting_available

        if fitting_available():  # a bad CSV is bad input, refused before any target is built
            from ..fitting import read_trials, summarise

            summarise(read_trials(trials))
    folder = check_out(out, todo)
    from .._lock import acquire

    # one run at a time in a folder: each keeps its manifest in memory, and two at once lost each
    # other's records (a full build recorded as quick)
    folder.mkdir(parents=True, exist_ok=True)
    write_marker(folder, STORE_KIND)  # (first: a folder holding a lock file alone would read as foreign)
    # (inside the folder: beside it, the folder's parent had to be writable, which it need not be)
    with acquire(folder, kind="reproduce", noun="folder", inside=True):
        from ..simulate import single_blas_thread

        from ..plotting._common import offscreen

        with single_blas_thread(), offscreen():  # (its figures are saved, never shown: no pyplot)
            records = build_targets(todo, folder, settings, log=log, force=force)
        from .catalog import TARGETS
        from .targets import with_earlier

        report = write_report(folder, with_earlier(list(TARGETS), folder, records), mode)
    return ReproduceResult(folder, report, records, time.perf_counter() - t0)
