"""Targets and the engine that builds them.

A :class:`Target` names its output files, its inputs (a JSON-able dict, with the package
version and the output hashes of the targets it depends on; the manifest adds the mode and the
hashes of the source files its code depends on) and a ``build(ctx)`` function that
writes the outputs and returns an :class:`Outcome` (comparisons with the paper, notes). The
engine :func:`build_targets` skips targets whose manifest entry is up to date, records each
finished target in the manifest at once, and writes ``<name>.json`` (the outcome) as data.
"""

from __future__ import annotations

import os
import time
import traceback
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

from .._interrupt import interrupted
from .._validate import ParameterError
from .io import sha256_file, write_json
from .manifest import Manifest, code_hashes, input_key

__all__ = ["Settings", "Comparison", "Outcome", "Target", "Context", "TargetRecord", "build_targets",
           "MODES", "compare", "cross_check", "verdict"]

MODES = ("quick", "full")


@dataclass(frozen=True)
class Settings:
    """Resolution of a run. ``quick``: coarse grids, a short branch, small videos (minutes on
    two cores); ``full``: the paper's map step 0.1, a fine branch, the default simulator
    resolution."""

    mode: str = "quick"
    trials: str | None = None

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ParameterError(f"mode={self.mode!r} is not allowed; choose one of {MODES}")

    @property
    def quick(self) -> bool:
        return self.mode == "quick"

    def pick(self, quick: Any, full: Any) -> Any:
        return quick if self.quick else full


@dataclass(frozen=True)
class Comparison:
    """One row of a figure's table: what the paper says, its number (or None), ours, and the
    agreement (relative difference, or a verdict) with ``ok`` True/False/None (not applicable).
    ``from_paper``: compared with a number or statement printed in the paper; False for a number
    of ours alone (no paper value, or a :func:`cross_check` against another number of ours, then
    in ``paper_value``), which the report shows as ours only and does not count among the
    agreements with the paper."""

    quantity: str
    paper: str
    ours: str
    agreement: str
    ok: bool | None = None
    paper_value: float | None = None
    our_value: float | None = None
    from_paper: bool = True
    #: an input of ours as printed in the paper (Table 1's): a transcription check, counted apart
    #: from the results that agree with the paper
    is_input: bool = False


def compare(quantity: str, paper_value: float | None, our_value: float, *, unit: str = "",
            rtol: float | None = None, paper_text: str | None = None, fmt: str = "{:.4g}") -> Comparison:
    """A row comparing our number with the paper's (``paper_value``, printed in the paper; None:
    the paper states none, the row is ours only); relative difference and ok = |rel| <= rtol
    when both given."""
    u = f" {unit}" if unit else ""
    ours = fmt.format(our_value) + u
    if paper_value is None:
        return Comparison(quantity, paper_text or "not stated", ours, "-", None, None, float(our_value),
                          from_paper=False)
    rel = (our_value - paper_value) / abs(paper_value) if paper_value != 0 else float("nan")
    ok = None if rtol is None else bool(abs(rel) <= rtol)
    agree = f"{rel * 100:+.1f} %" + ("" if rtol is None else f" ({'within' if ok else 'outside'} {rtol * 100:g} %)")
    return Comparison(quantity, paper_text or (fmt.format(paper_value) + u), ours, agree, ok,
                      float(paper_value), float(our_value))


def cross_check(quantity: str, reference_value: float, our_value: float, *, reference: str, unit: str = "",
                rtol: float | None = None, fmt: str = "{:.4g}") -> Comparison:
    """A row comparing our number with another of ours (``reference_value``, e.g. a simulation
    against the periodic orbit, the discrete model against the linear theory), said in
    ``reference``: agreement as :func:`compare`'s, but ours only (not an agreement with the paper)."""
    return replace(compare(quantity, reference_value, our_value, unit=unit, rtol=rtol, paper_text=reference,
                           fmt=fmt), from_paper=False)


def verdict(quantity: str, paper_text: str, ours: str, ok: bool) -> Comparison:
    return Comparison(quantity, paper_text, ours, "agrees" if ok else "DISAGREES", bool(ok))


@dataclass(frozen=True)
class Outcome:
    """What a build returns. status: "ok" or "skipped" (with the reason in notes)."""

    status: str = "ok"
    comparisons: tuple[Comparison, ...] = ()
    notes: tuple[str, ...] = ()
    values: dict = field(default_factory=dict)  # numbers other targets or the report may use


@dataclass(frozen=True)
class Context:
    out: Path
    settings: Settings
    records: dict  # name -> TargetRecord of the targets built or found up to date so far

    def path(self, name: str) -> Path:
        return self.out / name


@dataclass(frozen=True)
class Target:
    """name: short id (file stem); title: the paper's figure name (the numbering of the issue that
    specified reproduce); caption: the paper's words; source: its label in the LaTeX source;
    figures / data / videos: output file names (relative to the output folder);
    params: JSON-able inputs of the build; deps: targets whose outputs this one reads."""

    name: str
    title: str
    caption: str
    build: Callable[[Context], Outcome]
    params: Callable[[Settings], dict]
    figures: tuple[str, ...] = ()
    data: tuple[str, ...] = ()
    videos: tuple[str, ...] = ()
    deps: tuple[str, ...] = ()
    #: where it stands in the paper's LaTeX source (label, and its number there when it differs)
    source: str = ""

    @property
    def summary_file(self) -> str:
        return f"{self.name}.json"

    @property
    def outputs(self) -> tuple[str, ...]:
        return self.figures + self.data + self.videos + (self.summary_file,)


@dataclass(frozen=True)
class TargetRecord:
    """A target after the run: status ok / skipped / failed; reran: built in this run;
    wall_time [s] of the build that made the outputs; mode: quick or full, of that build."""

    target: Target
    status: str
    reran: bool
    wall_time: float
    outcome: Outcome
    error: str = ""
    outputs: dict = field(default_factory=dict)  # file -> sha256
    mode: str = ""


def _inputs(t: Target, settings: Settings, records: dict) -> dict:
    from .. import __version__

    deps = {d: records[d].outputs for d in t.deps if d in records}
    return {"target": t.name, "settings": t.params(settings), "version": __version__, "deps": deps}


def target_code(t: Target) -> dict[str, str]:
    """SHA-256 of the package sources ``t`` is built with: the closure of its build and params
    functions and of this engine (which writes its summary)."""
    return code_hashes([t.build, t.params, build_targets])


def _outcome_from_summary(t: Target, out: Path) -> Outcome:
    from .io import read_json

    d = read_json(out / t.summary_file)
    comps = tuple(Comparison(**c) for c in d.get("comparisons", []))
    return Outcome(d.get("status", "ok"), comps, tuple(d.get("notes", [])), d.get("values", {}))


def with_earlier(all_targets: list[Target], out: Path, records: dict[str, TargetRecord]) -> dict[str, TargetRecord]:
    """``records``, and (in the order of ``all_targets``) every target an earlier run built into
    ``out`` that this run did not select (``--only``): from its manifest entry and summary
    file, with a note saying so. The report shows the whole folder, not only this run."""
    man = Manifest.load(out)
    merged: dict[str, TargetRecord] = {}
    for t in all_targets:
        if t.name in records:
            merged[t.name] = records[t.name]
        elif t.name in man.targets and (out / t.summary_file).is_file():
            e = man.targets[t.name]
            oc = _outcome_from_summary(t, out)
            oc = Outcome(oc.status, oc.comparisons, oc.notes + ("built by an earlier run (not selected by this "
                                                               "run's --only)",), oc.values)
            merged[t.name] = TargetRecord(t, e.get("status", oc.status), False, float(e.get("wall_time_s", 0.0)), oc,
                                          e.get("error", ""), dict(e.get("outputs", {})), e.get("mode", ""))
    return merged


def build_targets(targets: list[Target], out: Path, settings: Settings, *, log: Callable[[str], None] | None = None,
                  force: bool = False) -> dict[str, TargetRecord]:
    """Build ``targets`` in order into ``out`` (checked by the caller), skipping up-to-date ones.
    A failing target is recorded (status failed, the error) and the others go on; targets
    depending on a failed one fail too. A quick build is rebuilt for a full run; a full build
    that is up to date serves a quick run (it is not replaced by a coarser one)."""
    log = log or (lambda msg: None)
    man = Manifest.load(out)
    man.run = {"this_run_mode": settings.mode, "trials": settings.trials}
    mode = settings.mode
    records: dict[str, TargetRecord] = {}
    for t in targets:
        inputs = _inputs(t, settings, records)
        key = input_key(inputs)
        bad = [d for d in t.deps if d not in records or records[d].status == "failed"]
        if bad:
            err = f"needs target(s) {', '.join(bad)}, which failed"
            records[t.name] = TargetRecord(t, "failed", True, 0.0, Outcome("failed", notes=(err,)), err, mode=mode)
            man.record(t.name, {"title": t.title, "status": "failed", "error": err, "key": key, "inputs": inputs,
                                "mode": mode})
            log(f"{t.name}: FAILED ({err})")
            continue
        kept = None
        if not force:
            if man.up_to_date(t.name, key, mode):
                kept = mode
            elif mode == "quick" and man.up_to_date(
                    t.name, input_key(_inputs(t, replace(settings, mode="full"), records)), "full"):
                kept = "full"  # a full build serves a quick run: not replaced by a coarser one
        if kept:
            e = man.targets[t.name]
            oc = _outcome_from_summary(t, out)
            records[t.name] = TargetRecord(t, e["status"], False, float(e.get("wall_time_s", 0.0)), oc,
                                           outputs=dict(e["outputs"]), mode=kept)
            log(f"{t.name}: up to date" + (" (a full build)" if kept != mode else ""))
            continue
        log(f"{t.name}: building ...")
        # no output hashes while it builds: files an interrupted build leaves are ours, not edits
        man.record(t.name, {"title": t.title, "status": "building", "key": key, "inputs": inputs, "mode": mode})
        t0 = time.perf_counter()
        ctx = Context(out, settings, records)
        try:
            oc = t.build(ctx)
        except KeyboardInterrupt:
            raise
        except Exception as exc:  # noqa: BLE001 - a failed target is recorded, the rest go on
            if interrupted(exc):  # Ctrl-C inside a compiled kernel surfaces as its SystemError
                raise KeyboardInterrupt from exc
            wall = time.perf_counter() - t0
            err = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
            if os.environ.get("FLUTTERSWIM_DEBUG"):
                traceback.print_exc()
            records[t.name] = TargetRecord(t, "failed", True, wall, Outcome("failed", notes=(err,)), err, mode=mode)
            man.record(t.name, {"title": t.title, "status": "failed", "error": err, "key": key,
                                "inputs": inputs, "wall_time_s": wall, "mode": mode})
            log(f"{t.name}: FAILED in {wall:.1f} s: {err}")
            continue
        write_json(out / t.summary_file, {"target": t.name, "title": t.title, "status": oc.status,
                                          "comparisons": [asdict(c) for c in oc.comparisons],
                                          "notes": list(oc.notes), "values": oc.values})
        wall = time.perf_counter() - t0
        produced = [f for f in t.outputs if (out / f).is_file()]
        missing = [f for f in t.outputs if f not in produced]
        if oc.status == "ok" and missing:
            err = f"the build did not write {missing}"
            records[t.name] = TargetRecord(t, "failed", True, wall, oc, err, mode=mode)
            man.record(t.name, {"title": t.title, "status": "failed", "error": err, "key": key, "inputs": inputs,
                                "mode": mode})
            log(f"{t.name}: FAILED: {err}")
            continue
        hashes = {f: sha256_file(out / f) for f in produced}
        records[t.name] = TargetRecord(t, oc.status, True, wall, oc, outputs=hashes, mode=mode)
        from .. import __version__

        man.record(t.name, {"title": t.title, "status": oc.status, "key": key, "inputs": inputs, "mode": mode,
                            "version": __version__, "wall_time_s": wall, "outputs": hashes,
                            "code": target_code(t)})
        log(f"{t.name}: {oc.status} in {wall:.1f} s")
    return records
