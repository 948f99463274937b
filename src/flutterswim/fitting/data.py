"""Trial data: the CSV of measured descriptors, per-voltage means and standard errors, and
the paper's Fig. 3e (mean +- SEM against voltage).

CSV columns (others are ignored): ``voltage_V, sample, period_s, advance_mm, lateral_mm``.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validate import ParameterError

__all__ = ["Trials", "Summary", "read_trials", "summarise", "check_spread", "plot_trials", "COLUMNS"]

COLUMNS = ("voltage_V", "sample", "period_s", "advance_mm", "lateral_mm")
DESCRIPTORS = ("period_s", "advance_mm", "lateral_mm")


@dataclass(frozen=True)
class Trials:
    """One row per trial."""

    voltage_V: np.ndarray
    sample: np.ndarray
    values: np.ndarray  # (n, 3): period_s, advance_mm, lateral_mm
    source: str = ""  # the file read (for messages)
    body_length_mm: np.ndarray | None = None  # (n,) the tracked body length, where the CSV has it (NaN: none)


@dataclass(frozen=True)
class Summary:
    """Per voltage: number of trials, mean and SEM of the three descriptors (period [s],
    advance [mm], lateral [mm])."""

    voltage_V: np.ndarray
    n: np.ndarray
    mean: np.ndarray  # (m, 3)
    sem: np.ndarray  # (m, 3)

    def at(self, voltage: float) -> tuple[np.ndarray, np.ndarray]:
        i = np.nonzero(np.isclose(self.voltage_V, voltage))[0]
        if i.size == 0:
            raise ParameterError(f"voltage={voltage!r} V is not in the data; it has {self.voltage_V.tolist()} V")
        return self.mean[i[0]], self.sem[i[0]]


# a stroke slower than this is not a flutter of the paper's kind (0.3-0.5 s): most likely a
# period column in ms; said, not refused
_MAX_PLAUSIBLE_PERIOD_S = 60.0
#: an advance or lateral excursion beyond this [mm] is not a millimetre-sized ribbon's (in um?)
_MAX_PLAUSIBLE_LENGTH_MM = 50.0
#: voltages all below this [V] are likely in kV (the paper's: 70-100 V)
_MIN_PLAUSIBLE_VOLTAGE_V = 1.0
#: a tracked body length this far from the model's l (relative) is noted; beyond the second,
#: refused: the geometry is not the sample's, or the pixel scale is wrong
BODY_LENGTH_NOTE, BODY_LENGTH_REFUSE = 0.02, 0.10


def read_trials(path: str | Path) -> Trials:
    """Read the trials CSV; a clear error names a missing column or a bad value."""
    p = Path(path)
    if not p.is_file():
        raise ParameterError(f"trials={str(p)!r} is not a file")
    try:
        with open(p, newline="", encoding="utf-8-sig") as f:  # (a spreadsheet's byte-order mark)
            reader = csv.DictReader(f)
            rows = list(reader)
            header = [str(h) for h in (reader.fieldnames or [])]
    except (UnicodeDecodeError, csv.Error) as exc:
        with open(p, "rb") as f:
            netcdf = f.read(8) in (b"\x89HDF\r\n\x1a\n",) or p.suffix.lower() in (".nc", ".zarr")
        if netcdf:  # a track or a run: the trials' descriptors are what fit reads
            raise ParameterError(f"trials={str(p)!r} is a NetCDF file (a track or a run), not a CSV of trials: make one "
                                 "with 'flutterswim track-batch FOLDER' (one row per trial), or describe the track "
                                 "('flutterswim describe') and fit its figures with the API's fit()") from None
        raise ParameterError(f"trials={str(p)!r} is not a readable CSV file ({exc})") from None
    if not rows:
        raise ParameterError(f"trials={str(p)!r} has no data rows")
    # names padded with spaces (", period_s") are the names
    rows = [{(k.strip() if isinstance(k, str) else k): v for k, v in r.items()} for r in rows]
    missing = [c for c in COLUMNS if c not in rows[0]]
    if missing:
        sep = next((f" (its header is separated by {d!r}: the file must be comma-separated)"
                    for d in (";", "\t") if len(header) == 1 and d in header[0]), "")
        raise ParameterError(f"trials={str(p)!r} lacks the column(s) {', '.join(missing)}{sep}; its header has "
                             f"{', '.join(repr(h) for h in header[:8])}{' ...' if len(header) > 8 else ''}; "
                             f"required (spelt so): {', '.join(COLUMNS)}")
    vals = np.empty((len(rows), 3))
    volt = np.empty(len(rows))
    for i, r in enumerate(rows):
        extra = [v for v in r.get(None) or [] if v.strip()]  # (empty ones: a trailing comma)
        short = any(v is None for k, v in r.items() if k is not None)
        if extra or short:  # a shifted row, not to be guessed at
            n = sum(v is not None for k, v in r.items() if k is not None) + len(r.get(None) or [])
            raise ParameterError(f"trials={str(p)!r}, row {i + 2} has {n} fields under a header of {len(header)}; "
                                 "every row needs one value per column")
        try:
            volt[i] = float(r["voltage_V"])
            vals[i] = [float(r[c]) for c in DESCRIPTORS]
        except (TypeError, ValueError):
            raise ParameterError(f"trials={str(p)!r}, row {i + 2}: a number is required in "
                                 f"{', '.join(('voltage_V',) + DESCRIPTORS)}") from None
        if not (math.isfinite(volt[i]) and volt[i] > 0):
            raise ParameterError(f"trials={str(p)!r}, row {i + 2}: voltage_V={r['voltage_V']!r} is not allowed; "
                                 "a finite voltage > 0 is required (the magnitude of the voltage that makes the field; "
                                 "without one there is no stroke)")
        for k, c in enumerate(DESCRIPTORS):
            if not (math.isfinite(vals[i, k]) and (vals[i, k] > 0 if k == 0 else vals[i, k] >= 0)):
                raise ParameterError(f"trials={str(p)!r}, row {i + 2}: {c}={r[c]!r} is not allowed; periods must "
                                     "be finite and > 0, advances and lateral excursions finite and >= 0")
    _warn_repeated(p, rows)
    import warnings

    if vals[:, 0].max() > _MAX_PLAUSIBLE_PERIOD_S:
        warnings.warn(f"trials={str(p)!r}: periods up to {vals[:, 0].max():g} s (the paper's strokes beat in "
                      f"0.3-0.5 s): is period_s in seconds (not ms)?", UserWarning, stacklevel=2)
    for k, c in ((1, "advance_mm"), (2, "lateral_mm")):  # (1170 mm for a 3.7 mm ribbon went in without a word)
        if vals[:, k].max() > _MAX_PLAUSIBLE_LENGTH_MM:
            warnings.warn(f"trials={str(p)!r}: {c} up to {vals[:, k].max():g} mm, for a millimetre-sized ribbon (the "
                          f"paper's: 0.4-1.2 mm): is {c} in millimetres (not um)?", UserWarning, stacklevel=2)
    if volt.max() < _MIN_PLAUSIBLE_VOLTAGE_V:
        warnings.warn(f"trials={str(p)!r}: voltages up to {volt.max():g} V (the paper's: 70-100 V): is voltage_V in "
                      "volts (not kV)?", UserWarning, stacklevel=2)
    body = None
    if "body_length_mm" in rows[0]:  # (track-batch writes it: the fit's geometry is checked against it)
        def number(v) -> float:
            try:
                x = float(v)
            except (TypeError, ValueError):
                return math.nan
            return x if math.isfinite(x) and x > 0 else math.nan

        body = np.array([number(r["body_length_mm"]) for r in rows])
    return Trials(volt, np.array([r["sample"] for r in rows]), vals, str(p), body)


def check_geometry(trials: Trials, base, voltages=None) -> str:
    """The tracked body length (the CSV's ``body_length_mm``, where given) against the model's
    l: a ParameterError beyond :data:`BODY_LENGTH_REFUSE`, a note (returned, else "") beyond
    :data:`BODY_LENGTH_NOTE`. A fit with the paper's geometry of a 3 mm ribbon returned B 187 %
    off, 7-160 sigma from the truth, without a word."""
    if trials.body_length_mm is None:
        return ""
    body = np.asarray(trials.body_length_mm, float)
    if voltages is not None:  # the trials fitted only (another sample at another voltage is not checked)
        body = body[np.any(np.isclose(trials.voltage_V[:, None], np.atleast_1d(voltages)[None, :]), axis=1)]
    if not np.any(np.isfinite(body)):
        return ""
    measured = float(np.nanmedian(body))
    l_mm = base.l * 1e3
    off = measured / l_mm - 1.0
    where = "" if voltages is None else " at " + ", ".join(f"{v:g} V" for v in np.atleast_1d(voltages))
    what = (f"the trials' tracked body length{where}, {measured:.4g} mm (median of "
            f"{int(np.count_nonzero(np.isfinite(body)))}), is {100 * abs(off):.2g} % "
            f"{'longer' if off > 0 else 'shorter'} than the model's l = {l_mm:.4g} mm")
    advice = ("give the sample's geometry (--length-mm, --width-mm, --thickness-mm), or check the movies' scale "
              "(--px-per-mm)")
    if abs(off) > BODY_LENGTH_REFUSE:
        raise ParameterError(f"trials={trials.source!r}: {what}; the model would fit another ribbon: {advice}")
    if abs(off) > BODY_LENGTH_NOTE:
        return f"{what}: the fit holds the model's geometry; {advice}"
    return ""


def _warn_repeated(p: Path, rows: list[dict]) -> None:
    """Warn (not refuse: real trials may coincide) about rows that repeat another row."""
    import warnings

    seen: dict[tuple, list[int]] = {}
    for i, r in enumerate(rows):
        seen.setdefault(tuple(str(r[c]).strip() for c in COLUMNS), []).append(i + 2)
    repeats = [g for g in seen.values() if len(g) > 1]
    if repeats:
        warnings.warn(f"trials={str(p)!r}: rows {'; '.join(', '.join(map(str, g)) for g in repeats)} repeat the "
                      "same trial (copied rows?)", UserWarning, stacklevel=3)


def check_spread(trials: Trials, summary: "Summary", voltages=None) -> None:
    """Refuse voltages (default: all with two or more trials) whose trials have no spread in a
    descriptor: its standard error is 0 and cannot weight a fit (identical trials)."""
    vs = summary.voltage_V if voltages is None else np.atleast_1d(np.asarray(voltages, float))
    for v in vs:
        at = trials.voltage_V == v
        if at.sum() < 2:
            continue
        same = [c for k, c in enumerate(DESCRIPTORS) if np.ptp(trials.values[at, k]) == 0]
        if same:
            rows = ", ".join(str(i + 2) for i in np.nonzero(at)[0])
            raise ParameterError(
                f"trials={trials.source!r}: at {v:g} V the {int(at.sum())} trials (rows {rows}) have the same "
                f"{' and '.join(same)}: no spread, so the standard error is 0 and cannot weight the fit (identical "
                "trials: copied rows?); correct the file, or use the paper's cost (--paper-cost)")


def summarise(trials: Trials) -> Summary:
    """Mean and standard error of the mean per voltage (SEM = std(ddof=1) / sqrt(n); with
    one trial the SEM is unknown: NaN)."""
    # voltages that agree within Summary.at's tolerance are one voltage (85 and 85.0000001 had
    # been two, and --voltage 85 fitted the first alone)
    vs: list[float] = []
    for v in np.unique(trials.voltage_V):
        if not (vs and np.isclose(v, vs[-1])):
            vs.append(float(v))
    # each trial in the group of its nearest voltage (a chain 85, 85.0008, 85.0016 had put the
    # middle one in two groups)
    near = np.argmin(np.abs(np.asarray(trials.voltage_V, float)[:, None] - np.array(vs)[None, :]), axis=1)
    group = [near == g for g in range(len(vs))]
    n = np.array([np.count_nonzero(g) for g in group])
    mean = np.array([trials.values[g].mean(axis=0) for g in group])
    sem = np.array([trials.values[g].std(axis=0, ddof=1) / math.sqrt(k) if k > 1
                    else np.full(3, np.nan) for g, k in zip(group, n)])
    # identical trials have no spread: exactly 0 (not the round-off of their mean)
    for i, g in enumerate(group):
        sem[i, np.ptp(trials.values[g], axis=0) == 0] = 0.0 if n[i] > 1 else np.nan
    return Summary(np.array(vs), n, mean, sem)


LABELS = ("period [s]", "advance per cycle [mm]", "lateral peak-to-peak [mm]")


def draw_trials(ax, k: int, summary: Summary, trials: Trials | None = None, tip: str | None = None) -> None:
    """Descriptor k (period, advance, lateral) against voltage on ``ax``: mean +- SEM (red) and
    the trials (grey dots, drawn 5 points left of their voltage so the error bar does not hide them);
    the number of trials under each voltage's mean on the first panel. ``tip``: which end the
    lateral excursions are ("trailing", "leading"), said on its axis."""
    if trials is not None:
        from matplotlib.transforms import offset_copy

        # 5 points left of their voltage on the page, not in volts (one voltage, 700 V: the dots sat
        # at 658 V on the axis, a voltage never applied)
        left = offset_copy(ax.transData, fig=ax.figure, x=-5.0, y=0.0, units="points")
        xy = np.column_stack([np.asarray(trials.voltage_V, float), trials.values[:, k]])
        ax.plot(xy[:, 0], xy[:, 1], ".", color="0.5", ms=4, label="trials", transform=left)
        ax.update_datalim(xy)  # (a line drawn with an offset is not counted by the autoscaling)
        ax.autoscale_view()
    ax.errorbar(summary.voltage_V, summary.mean[:, k], yerr=summary.sem[:, k], fmt="o", color="tab:red",
                capsize=3, label="mean \u00b1 SEM")
    ax.set_xlabel("voltage [V]")
    ax.set_ylabel(LABELS[k] if k != 2 or tip is None else f"lateral p-p, {tip} end [mm]")
    if k == 0:  # (along the bottom of the panel, below the points)
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo - 0.1 * (hi - lo), hi)
        for v, n in zip(summary.voltage_V, summary.n):
            ax.text(v, 0.01, f"n={int(n)}", transform=ax.get_xaxis_transform(), ha="center", va="bottom",
                    fontsize=7, color="tab:red")


def plot_trials(summary: Summary, path=None, *, trials: Trials | None = None, model=None, tip: str | None = None):
    """Fig. 3e: advance per cycle and period against voltage, mean +- SEM (red), the trials
    (grey dots) and, optionally, model values per voltage (``model``: (m, 3) array); ``tip``:
    which end the lateral column measures, for its axis label."""
    from ..plotting._common import new_figure

    fig = new_figure((10, 3.4), shown=path is None)

    axs = fig.subplots(1, 3)
    for k, ax in enumerate(axs):
        draw_trials(ax, k, summary, trials, tip)
        if model is not None:
            ax.plot(summary.voltage_V, np.asarray(model)[:, k], "s", mfc="none", color="k", label="model")
    axs[0].legend(fontsize=8)
    if path is not None:
        from .._paths import save_figure_file

        save_figure_file(fig, path, dpi=150)
    return fig
