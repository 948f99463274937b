"""Batch tracking: a folder of trials -> one CSV row of descriptors per trial, in the input
format of the fitting (``voltage_V, sample, period_s, advance_mm, lateral_mm``, then more
columns), and the per-voltage mean +- SEM figure (the paper's Fig. 3e, drawn by
:func:`flutterswim.fitting.data.plot_trials`).

A trial is a TIFF stack or a movie in the folder, or a subfolder of frames. Its voltage and
sample come from a sidecar JSON (``<trial>.json`` next to it, or ``trial.json`` inside a
frame folder; keys ``voltage_V``, ``sample`` and optionally ``px_per_mm``, ``fps``, ``roi``,
``field_angle_deg``, ``start_end``, ``dark_line``, ``times``: a file of the frames' times, as
``track --times``, its path relative to the sidecar's folder) or else (each key the sidecar lacks) from the file name by a regular expression with
the named groups ``voltage`` and ``sample`` (default :data:`DEFAULT_PATTERN`, e.g.
``85V_sample3_trial2.tif``; a ``p`` or a comma may stand for the decimal point, ``72p5V``, ``72,5V``;
a minus sign before the voltage is not read as one: such a name is refused, give the voltage in
a sidecar).

Columns (the last, tracked_by, signs the file as ours): advance_mm is the advance per cycle along the field (its magnitude); lateral_mm is
the lateral peak-to-peak of the trailing end (the fitting's default), leading_lateral_mm that
of the leading end, lateral_se_mm and leading_lateral_se_mm their standard errors within the
trial (``Descriptors.*_lateral_p2p_se_mm``: the noise the trial's frames leave, not the spread
between trials). A trial that cannot be tracked (any error) or has no voltage and sample
(no sidecar and a name the pattern does not match, a voltage that is no finite number) is left
out of the CSV and listed, with its reason, in ``<out stem>_failed.csv`` (an old one of ours is
removed when none failed); the batch goes on. When none is tracked, no CSV of descriptors is
written (a file already there is left as it was). The sidecars' options, the options and the
output files are checked before the first trial.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .._validate import ParameterError, direction_deg, finite, positive, positive_int
from .io import FRAME_SUFFIXES, MOVIE_SUFFIXES, STACK_SUFFIXES, parse_roi

__all__ = ["DEFAULT_PATTERN", "CSV_COLUMNS", "Trial", "failures_path", "find_trials", "track_batch"]

# the voltage a whole number (not the end of one: "85,5V" read 5 V), its decimal mark a point, a
# comma or a p; the sample the token after the word "sample" (not inside "downsampled") and a
# separator, or right after it digits, a capital, or one lower-case letter standing alone but
# for the plural's "s" and the participle's "d" ("samples_A" and "sampled_" read as samples
# "s" and "d")
DEFAULT_PATTERN = (r"(?<![\d.,])(?P<voltage>\d+(?:[.,p]\d+)?)\s*V.*?"
                   r"(?<![A-Za-z])sample(?:[-_ ]|(?=\d)|(?=(?-i:[A-Z]))|(?=(?-i:[a-ce-rt-z])(?:[-_ .]|$)))"
                   r"(?P<sample>[A-Za-z0-9]+)")
CSV_COLUMNS = ("voltage_V", "sample", "period_s", "advance_mm", "lateral_mm", "leading_lateral_mm",
               "lateral_se_mm", "leading_lateral_se_mm", "period_std_s", "advance_std_mm", "n_cycles", "body_length_mm", "body_length_spread",
               "n_frames", "n_failed_frames", "trial", "tracked_by")
#: The columns before the standard errors (a header-only CSV of an older batch is still ours).
CSV_COLUMNS_BEFORE_SE = tuple(c for c in CSV_COLUMNS if not c.endswith("_se_mm"))
#: Columns of the failures file (``failures_path``).
FAILED_COLUMNS = ("trial", "reason", "tracked_by")


@dataclass(frozen=True)
class Trial:
    path: Path
    voltage_V: float
    sample: str
    options: dict
    problem: str = ""  # why the trial has no voltage and sample (then voltage_V is nan): it fails


def _is_trial(p: Path) -> bool:
    if p.name.startswith("."):
        return False
    if p.is_dir():
        return any(f.suffix.lower() in FRAME_SUFFIXES for f in p.iterdir() if f.is_file())
    return p.suffix.lower() in STACK_SUFFIXES + MOVIE_SUFFIXES


def _sidecar(p: Path) -> tuple[dict, Path] | None:
    """The sidecar's JSON object and its path, or None without one."""
    for cand in ([p / "trial.json"] if p.is_dir() else []) + [p.with_suffix(".json") if p.is_file() else p.parent / f"{p.name}.json"]:
        if cand.is_file():
            try:
                meta = json.loads(cand.read_text())
            except (json.JSONDecodeError, UnicodeDecodeError) as exc:
                raise ParameterError(f"sidecar={str(cand)!r} is not valid JSON ({exc})") from None
            if not isinstance(meta, dict):
                raise ParameterError(f"sidecar={str(cand)!r} is not a JSON object (it holds a {type(meta).__name__}); "
                                     '{"voltage_V": ..., "sample": ...} is required')
            return meta, cand
    return None


def _sidecar_options(meta: dict, cand: Path) -> dict:
    """The tracking options of a sidecar, checked (before any trial is tracked); a null value
    is no value."""
    from .track import START_ENDS

    opts = {k: meta[k] for k in ("px_per_mm", "fps", "roi", "field_angle_deg", "start_end", "dark_line")
            if meta.get(k) is not None}
    try:
        # (JSON numbers only: true was read as 1.0 and "71" as 71)
        for k in ("px_per_mm", "fps"):
            if k in opts:
                opts[k] = positive(k, opts[k], strict=True)
        if "field_angle_deg" in opts:
            opts["field_angle_deg"] = finite("field_angle_deg", opts["field_angle_deg"], strict=True)
        if "fps" in opts and meta.get("times") is not None:
            raise ParameterError("give fps or times, not both: the times set the frame rate")
        if "roi" in opts:
            parse_roi(opts["roi"], None)
        if "start_end" in opts and opts["start_end"] not in START_ENDS:
            raise ParameterError(f"start_end={opts['start_end']!r} is not allowed; choose one of {', '.join(START_ENDS)}")
        if "dark_line" in opts and not isinstance(opts["dark_line"], bool):
            raise ParameterError(f"dark_line={opts['dark_line']!r} is not allowed; give true or false")
        if meta.get("times") is not None:
            opts["times"] = _sidecar_times(meta["times"], cand)
    except ParameterError as exc:
        raise ParameterError(f"sidecar={str(cand)!r}: {exc}") from None
    return opts


def _sidecar_times(value: Any, cand: Path):
    """The frames' times named by a sidecar's ``times`` (a path relative to the sidecar's
    folder), read now: a missing or unreadable file stops the batch before its first trial."""
    from .io import read_times

    if not isinstance(value, str) or not value.strip():
        raise ParameterError(f"times={value!r} is not allowed; give the path of a file of the frames' times "
                             "(relative to the sidecar's folder)")
    p = Path(value)
    return read_times(p if p.is_absolute() else cand.parent / p)


def _voltage(m: re.Match) -> str:
    """The voltage the name gives, as text for float(); not a number when a minus sign stands
    right before it at the start of the name or of a field ("-85V", "trial_-85V": a sign, which
    the pattern does not read; "run-85V" is a separator), so that the trial is refused by name."""
    v = m.group("voltage").replace("p", ".").replace("P", ".").replace(",", ".")
    start, name = m.start("voltage"), m.string
    if start > 0 and name[start - 1] == "-" and (start == 1 or name[start - 2] in "_ "):
        return f"-{v} (a sign the file name cannot give: write voltage_V in a sidecar)"
    return v


#: a trial whose tracked body length is this far (relative) from the batch's median is warned of
_LENGTH_SPREAD = 0.1


def _warn_disagreeing(p: Path, cand: Path, pairs) -> None:
    """A sidecar's voltage or sample that the trial's name contradicts: the sidecar's is used
    (it was, without a word: 90 V beside 85V_sample1.tif)."""
    for what, given, named in pairs:
        try:
            same = math.isclose(float(given), float(named), rel_tol=1e-9) if what == "voltage" else (
                str(given).strip() == str(named).strip())
        except (TypeError, ValueError):
            continue
        if not same:
            warnings.warn(f"trial {str(p)!r}: its sidecar {cand.name!r} gives {what} {given!r}, its name {named!r}; the "
                          "sidecar's is used", UserWarning, stacklevel=3)


def find_trials(folder: str | os.PathLike, pattern: str = DEFAULT_PATTERN) -> list[Trial]:
    """Trials of ``folder`` (sorted by name) with their voltage and sample; the sidecars'
    options are checked here (a bad one is a ParameterError naming its file). A trial without
    a voltage and sample is returned with its ``problem`` (it fails alone, in track_batch)."""
    root = Path(os.fspath(folder))
    if not root.is_dir():
        raise ParameterError(f"folder={str(root)!r} is not a directory")
    try:
        rx = re.compile(pattern, re.IGNORECASE)
    except re.error as exc:
        raise ParameterError(f"pattern={pattern!r} is not a regular expression ({exc})") from None
    if not {"voltage", "sample"} <= set(rx.groupindex):
        raise ParameterError(f"pattern={pattern!r} must have the named groups (?P<voltage>...) and (?P<sample>...)")
    out = []
    for p in sorted(root.iterdir()):
        if not _is_trial(p):
            continue
        side = _sidecar(p)
        where = f"trial {str(p)!r}"
        m = rx.search(p.stem if p.is_file() else p.name)
        if side is not None:
            meta, cand = side
            v = meta.get("voltage_V", meta.get("voltage"))
            smp = meta.get("sample")
            opts = _sidecar_options(meta, cand)
            where = f"sidecar={str(cand)!r}"
            if m is not None:  # (what the sidecar gives, against the name: one key alone was not checked)
                _warn_disagreeing(p, cand, tuple((what, given, named) for what, given, named in (
                    ("voltage", v, _voltage(m)), ("sample", smp, m.group("sample"))) if given is not None))
            if (v is None or smp is None) and m is not None:
                # a sidecar of options only (px_per_mm, field_angle_deg ...): the name gives the rest
                v = _voltage(m) if v is None else v
                smp = m.group("sample") if smp is None else smp
            if v is None or smp is None:
                out.append(Trial(p, math.nan, str(smp), opts, f"{where} needs the keys voltage_V and sample (or a "
                                 f"name that the pattern {pattern!r} matches)"))
                continue
            if isinstance(v, bool) or not isinstance(smp, (str, int)) or isinstance(smp, bool) or not str(smp).strip():
                out.append(Trial(p, math.nan, str(smp), opts, f"{where}: voltage_V must be a number and sample a "
                                 f"name (text or a whole number); got voltage_V={v!r}, sample={smp!r}"))
                continue
        else:
            if m is None:
                out.append(Trial(p, math.nan, "", {}, f"no sidecar JSON and the name does not match the pattern "
                                 f"{pattern!r}; add {p.stem}.json with voltage_V and sample, or give pattern"))
                continue
            v, smp, opts = _voltage(m), m.group("sample"), {}
        try:
            v = float(v)
        except (TypeError, ValueError):
            out.append(Trial(p, math.nan, str(smp), opts, f"{where}: voltage {v!r} is not a number"))
            continue
        if not math.isfinite(v):
            out.append(Trial(p, math.nan, str(smp), opts, f"{where}: voltage {v!r} is not finite; a finite number "
                             "of volts is required"))
            continue
        out.append(Trial(p, v, str(smp), opts))
    if not out:
        raise ParameterError(f"folder={str(root)!r} holds no trials (TIFF stacks, movies or folders of frames)")
    return out


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return "" if not math.isfinite(v) else f"{v:.8g}"
    return str(v)


def failures_path(out: str | os.PathLike) -> Path:
    """Where :func:`track_batch` lists the trials that failed, with their reasons: next to the
    CSV ``out``, as ``<stem>_failed.csv``."""
    out = Path(out)
    return out.with_name(out.stem + "_failed.csv")


def _recorded_fps(path: Path) -> float | None:
    """The frame rate a trial's file records (None: none, or the file cannot be read: track
    says why)."""
    from .io import open_frames

    try:
        return open_frames(path).fps
    except (ParameterError, OSError):
        return None


def _write_rows(path: Path, rows: list) -> None:
    """The CSV of descriptors, each row signed (atomically)."""
    from .._paths import atomic_write_text, row_signature

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    for r in rows:
        fields = [_fmt(r[c]) for c in CSV_COLUMNS[:-1]]
        w.writerow(fields + [row_signature(fields)])
    atomic_write_text(path, buf.getvalue())


def _one_trial(tr_: Trial, rows: list, failed: list, *, px_per_mm, fps, track_kwargs: dict, n_last: int) -> None:
    """Track and describe one trial: its row appended to ``rows``, or its failure to ``failed``."""
    from .. import __version__
    from ..analysis.descriptors import _ALONG_FIELD_COS, describe
    from .track import NO_FRAME_RATE, track

    o = dict(tr_.options)
    ppm = o.pop("px_per_mm", px_per_mm)
    # a trial's own times set its frame rate, and so does its movie's recorded rate (the
    # batch's fps is for trials without them: it had overridden a 40 fps AVI, period 20 % off)
    f = o.pop("fps", None if "times" in o else fps)
    if f is not None and "fps" not in tr_.options:
        rec = _recorded_fps(tr_.path)
        if rec is not None:
            if abs(f / rec - 1.0) > 0.01:
                warnings.warn(f"trial {str(tr_.path)!r} records {rec:g} fps, used; the batch's fps={f:g} is for "
                              "trials that record none (a high-speed camera's playback rate? put fps in the "
                              "trial's sidecar)", stacklevel=3)
            f = None
    kw = dict(track_kwargs)
    if "field_angle_deg" in o:
        kw["field_angle"] = direction_deg("field_angle_deg", o.pop("field_angle_deg"))
    kw.update(o)
    try:
        tk = track(tr_.path, px_per_mm=ppm, fps=f, **kw)
        d = describe(tk, n_last=n_last)
    except Exception as exc:  # noqa: BLE001 - one trial's failure, with its reason; the batch goes on
        why = " ".join(str(exc).split()).replace(NO_FRAME_RATE, "give fps, or fps or times in the trial's sidecar")
        failed.append((str(tr_.path), why if isinstance(exc, ParameterError) else
                       f"{type(exc).__name__}: {why}" if why else type(exc).__name__))
        return
    if abs(math.cos(math.radians(d.direction_to_field_deg))) < _ALONG_FIELD_COS:
        # the stroke swims along the field's line: this far off it, the field's direction is wrong
        warnings.warn(f"trial {str(tr_.path)!r} swims at {d.direction_to_field_deg:.0f} deg to the field, taken "
                      f"at {d.field_direction_deg:.0f} deg in the image; advance_mm is the advance along it. "
                      "Give the field's direction: --field-angle-deg, or field_angle_deg in the trial's sidecar",
                      stacklevel=3)
    m = tk.meta
    rows.append({
        "voltage_V": tr_.voltage_V, "sample": tr_.sample, "period_s": d.period_s,
        "advance_mm": abs(d.advance_per_cycle_mm), "lateral_mm": d.trailing_lateral_p2p_mm,
        "leading_lateral_mm": d.leading_lateral_p2p_mm, "lateral_se_mm": d.trailing_lateral_p2p_se_mm,
        "leading_lateral_se_mm": d.leading_lateral_p2p_se_mm, "period_std_s": d.period_std_s,
        "advance_std_mm": d.advance_per_cycle_std_mm, "n_cycles": d.n_cycles_used,
        "body_length_mm": tk.length, "body_length_spread": m["length_spread"], "n_frames": m["n_frames"],
        "n_failed_frames": m["n_failed"], "trial": str(tr_.path), "tracked_by": f"flutterswim {__version__}",
    })


def track_batch(folder: str | os.PathLike, out: str | os.PathLike, *, px_per_mm: float | None = None,
                fps: float | None = None, pattern: str = DEFAULT_PATTERN, n_last: int = 5, plot: str | None = None,
                progress: bool = False, as_typed: Callable[[str], str] | None = None,
                **track_kwargs: Any) -> tuple[Path, list[dict], list[tuple[str, str]]]:
    """Track every trial of ``folder`` and write the CSV ``out`` (and the Fig. 3e figure
    ``plot``). A sidecar's px_per_mm / fps override the arguments. Returns (CSV path, rows,
    failures [(trial, reason)]); the CSV is written only if a trial was tracked. The reasons name this function's parameters ("give fps");
    ``as_typed(reason)`` says them as the caller's user typed them (the command line's
    options: :func:`flutterswim.cli.as_typed`)."""
    from .._paths import atomic_write_text, check_output_file, is_ours, row_signature
    from .track import check_options

    # every input checked before the first trial is tracked
    out_p = check_output_file(out, (".csv",), what="out")
    if plot is not None:
        check_output_file(plot, (".png", ".pdf", ".svg"), what="plot")
    failed_p = check_output_file(failures_path(out_p), (".csv",), what="failures file")
    px_per_mm = None if px_per_mm is None else positive("px_per_mm", px_per_mm)
    fps = None if fps is None else positive("fps", fps)
    n_last = positive_int("n_last", n_last)
    track_kwargs = check_options(**track_kwargs)
    trials = find_trials(folder, pattern)
    if all(tr_.problem for tr_ in trials):  # (not one trial to track: the pattern or the sidecars are wrong)
        raise ParameterError(f"folder={str(folder)!r}: none of its {len(trials)} trials has a voltage and a sample; "
                             f"the first, {trials[0].path.name!r}: {trials[0].problem}")
    failed: list[tuple[str, str]] = [(str(tr_.path), tr_.problem) for tr_ in trials if tr_.problem]
    trials = [tr_ for tr_ in trials if not tr_.problem]  # (those without a voltage fail alone)
    for tr_ in trials:
        if tr_.options.get("px_per_mm", px_per_mm) is None:
            raise ParameterError(f"px_per_mm is needed for trial {str(tr_.path)!r}: give px_per_mm or put it in the sidecar")
        own = tr_.options.get("px_per_mm")
        if own is not None and px_per_mm is not None and abs(own / px_per_mm - 1.0) > 0.01:
            # (it overrode a command line 43 % off without a word)
            warnings.warn(f"trial {str(tr_.path)!r}: its sidecar's px_per_mm={own:g} is used, not px_per_mm="
                          f"{px_per_mm:g}", UserWarning, stacklevel=2)
    rows: list[dict] = []
    it = trials
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(trials, unit="trial", desc="track-batch")
    stopped, n_refused = None, len(failed)  # (trials refused before tracking: no voltage ...)
    try:
        for tr_ in it:
            _one_trial(tr_, rows, failed, px_per_mm=px_per_mm, fps=fps, track_kwargs=track_kwargs, n_last=n_last)
    except KeyboardInterrupt as exc:
        # the trials tracked so far are written before the interrupt goes on (an interrupt after
        # 2 of 3 trials had kept nothing)
        stopped = exc
        if bar_close := getattr(it, "close", None):
            bar_close()
    lengths = np.array([r["body_length_mm"] for r in rows], float)
    if np.count_nonzero(np.isfinite(lengths)) >= 2:
        med = float(np.nanmedian(lengths))
        odd = [(r["trial"], r["body_length_mm"]) for r, L in zip(rows, lengths) if abs(L / med - 1.0) > _LENGTH_SPREAD]
        if odd:  # (5.28 and 3.70 mm in one batch, from a sidecar's scale 43 % off, went unflagged)
            warnings.warn(f"{len(odd)} trial(s) measure a body length more than {100 * _LENGTH_SPREAD:g} % from the "
                          f"batch's median {med:.4g} mm (" + ", ".join(f"{Path(t).name}: {L:.4g} mm" for t, L in odd[:4])
                          + "): another sample, or a wrong px_per_mm (a sidecar's?)", UserWarning, stacklevel=2)
    failed.sort(key=lambda f: f[0])  # in the trials' order (by name), as the rows
    if as_typed is not None:
        failed = [(trial, as_typed(why)) for trial, why in failed]
    part = out_p.with_name(out_p.stem + "_interrupted.csv")
    if stopped is None and part.is_file() and not part.is_symlink() and is_ours(part):
        part.unlink()  # (an earlier interrupted run's trials: this run tracked them all)
    if stopped is not None:
        # (written beside, never over, the CSV: an interrupted rerun had replaced a complete batch's
        # CSV with its first trials, which fit then read as the batch)
        kept = ""
        if rows and not (part.exists() and not is_ours(part)):
            _write_rows(part, rows)
            kept = f": their descriptors are in {str(part)!r} ({str(out_p)!r} is as it was)"
        raise KeyboardInterrupt(f"interrupted after {len(rows) + len(failed) - n_refused} of {len(trials)} trials "
                                f"({len(rows)} tracked){kept}; a rerun tracks every trial again") from None
    if rows:  # (none tracked: no CSV of descriptors, a header alone read as a batch of none)
        _write_rows(out_p, rows)
    if failed:
        check_output_file(failed_p, (".csv",), what="failures file")
        fb = io.StringIO()
        fw = csv.writer(fb, lineterminator="\n")
        fw.writerow(FAILED_COLUMNS)
        fw.writerows([(a, b, row_signature([a, b])) for a, b in failed])
        atomic_write_text(failed_p, fb.getvalue())
    elif failed_p.is_file() and is_ours(failed_p):
        failed_p.unlink()  # our failures of an earlier run: none of them failed now
    if plot is not None and rows:
        from ..fitting.data import plot_trials, read_trials, summarise

        trials_data = read_trials(out_p)
        plot_trials(summarise(trials_data), plot, trials=trials_data, tip="trailing")
    return out_p, rows, failed
