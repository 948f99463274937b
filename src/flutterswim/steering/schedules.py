"""Field-direction schedules for steering: constant rotation, steps, ramps, and a CSV of
``t, angle[, strength]``; and the ``flutterswim simulate`` options that build them.

Angles in the API are radians; on the command line and in CSV files, degrees.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._paths import check_text_file
from .._validate import ParameterError, angle as _angle, finite, positive
from ..field import Constant, Field, Piecewise, Schedule
from .path import header_unit, parse_number

__all__ = ["Rotation", "rotation", "step", "ramp", "from_csv", "add_field_options", "field_from_args"]


@dataclass(frozen=True)
class Rotation(Schedule):
    """phi(t) = phi0 + rate (t - start) for t > start, phi0 before: a field turning at a
    constant rate [rad per time unit] from ``start``."""

    rate: float
    start: float = 0.0
    phi0: float = 0.0

    def __post_init__(self) -> None:
        for k in ("rate", "start", "phi0"):
            object.__setattr__(self, k, finite(k, getattr(self, k)))

    @property
    def breakpoints(self) -> tuple[float, ...]:  # type: ignore[override]
        return (self.start,)

    def __call__(self, t: float) -> float:
        return self.phi0 + self.rate * max(0.0, t - self.start)

    def scaled(self, time_scale: float) -> "Schedule":
        return Rotation(self.rate * time_scale, self.start / time_scale, self.phi0)

    def describe(self) -> str:
        return f"rotation(rate={self.rate:.6g} rad per time unit, start={self.start:.6g}, phi0={self.phi0:.6g})"


def rotation(seconds_per_turn: float, start: float = 0.0, phi0: float = 0.0) -> Field:
    """A field turning once every ``seconds_per_turn`` (negative: clockwise) from ``start``,
    from the direction ``phi0`` [rad; a magnitude above 2 pi warns: likely degrees]."""
    phi0 = _angle("phi0", phi0)
    spt = finite("seconds_per_turn", seconds_per_turn)
    if spt == 0:
        raise ParameterError("seconds_per_turn=0 is not allowed: a turn takes a non-zero time")
    return Field(direction=Rotation(2 * math.pi / spt, start, phi0))


def step(angle: float, at: float, phi0: float = 0.0) -> Field:
    """The field jumps from ``phi0`` to ``angle`` at time ``at``. Angles in radians (the CLI's
    ``--field-step`` and the field CSV take degrees: pass ``math.radians(90)``, not 90); a
    magnitude above 2 pi warns (likely degrees)."""
    return _step(_angle("angle", angle), at, _angle("phi0", phi0))


def _step(angle: float, at: float, phi0: float) -> Field:
    at = finite("at", at)
    # (a hold schedule keeps its first value before its first time)
    return Field(direction=Piecewise([at - 1.0, at], [finite("phi0", phi0), finite("angle", angle)]))


def ramp(angle: float, start: float, duration: float, phi0: float = 0.0) -> Field:
    """The field turns linearly from ``phi0`` to ``angle`` over [start, start + duration].
    Angles in radians (the CLI's ``--field-ramp`` and the field CSV take degrees: pass
    ``math.radians(90)``, not 90); a magnitude above 2 pi warns (likely degrees)."""
    return _ramp(_angle("angle", angle), start, duration, _angle("phi0", phi0))


def _ramp(angle: float, start: float, duration: float, phi0: float) -> Field:
    duration = positive("duration", duration)
    start = finite("start", start)
    return Field(direction=Piecewise([start, start + duration], [finite("phi0", phi0), finite("angle", angle)],
                                     kind="linear"))


# units a field CSV's header may give its first two columns (t_ms, "angle [rad]"): factors to
# seconds and to degrees; any other unit (t_min, t_hours) is refused, not misread
_TIME_UNITS = {"s": 1.0, "ms": 1e-3, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0, "msec": 1e-3}
_ANGLE_UNITS = {"deg": 1.0, "degree": 1.0, "degrees": 1.0, "°": 1.0, "rad": math.degrees(1.0),
                "radian": math.degrees(1.0), "radians": math.degrees(1.0)}


def _header_unit(field: str, allowed: dict, what: str, where: str) -> float:
    """The factor of the unit a header field names (``t_ms``, ``angle [rad]``), 1 if none."""
    unit = header_unit(field)
    if unit is None:
        return 1.0
    unit = unit.lower()
    if unit not in allowed:
        raise ParameterError(f"{where}: the header's {what} column {field.strip()!r} is in {unit}; allowed: "
                             f"{', '.join(allowed)} (no unit: {next(iter(allowed))})")
    return allowed[unit]


def from_csv(path: str | Path) -> Field:
    """A schedule from a CSV of ``t, angle[, strength]`` (t in the run's time unit, angle in
    degrees), interpolated linearly and held after the last row. Blank lines and lines starting
    with ``#`` are skipped; a first row that holds no number is a header, whose first two
    columns may name their unit (``t_ms``, ``t [s]``, ``angle_rad``, ``angle [deg]``). Every row
    has two columns, or every row three."""
    p = Path(path)
    if not p.is_file():
        raise ParameterError(f"field CSV={str(p)!r} is not a file")
    rows, lines = [], []
    t_scale, a_scale, first = 1.0, 1.0, True
    check_text_file(p, "field CSV")
    with open(p, newline="", encoding="utf-8-sig") as f:
        reader = csv.reader(f)
        for row in reader:
            where = f"field CSV={str(p)!r}, line {reader.line_num}"
            while row and not row[-1].strip():
                row.pop()  # trailing empty fields
            if not row or row[0].strip().startswith("#"):
                continue
            try:
                vals = [float(v) for v in row[:3]]
            except ValueError:
                if first and all(parse_number(v) is None for v in row[:3]):
                    first = False
                    t_scale = _header_unit(row[0], _TIME_UNITS, "time", where)
                    if len(row) > 1:
                        a_scale = _header_unit(row[1], _ANGLE_UNITS, "angle", where)
                    continue  # a header
                raise ParameterError(f"{where}: numbers t, angle[, strength] are required, not "
                                     f"{','.join(row[:3])!r}") from None
            first = False
            if len(vals) < 2:
                raise ParameterError(f"{where}: {','.join(row)!r} has one field; t, angle[, strength] are required")
            if not all(np.isfinite(vals)):
                raise ParameterError(f"{where}: {row[:3]} is not finite; finite t, angle[, strength] are required")
            if rows and len(vals) != len(rows[0]):
                raise ParameterError(f"{where}: {len(vals)} columns, line {lines[0]} has {len(rows[0])}; give every "
                                     "row t, angle or every row t, angle, strength")
            if rows and not vals[0] > rows[-1][0]:
                raise ParameterError(f"{where}: t = {row[0].strip()} does not follow line {lines[-1]}'s "
                                     f"{rows[-1][0]:g}; the times must increase")
            rows.append(vals)
            lines.append(reader.line_num)
    if not rows:
        raise ParameterError(f"field CSV={str(p)!r} holds no rows of t, angle_deg[, strength]")
    a = np.array(rows)
    t = a[:, 0] * t_scale
    direction = Piecewise(t, np.radians(a[:, 1] * a_scale), kind="linear")
    if a.shape[1] == 3:
        return Field(direction=direction, strength=Piecewise(t, a[:, 2], kind="linear"))
    return Field(direction=direction)


def add_field_options(p) -> None:
    """Field options of ``flutterswim simulate``."""
    g = p.add_argument_group("field schedule (angles in degrees, times in s)")
    g.add_argument("--field-angle", "--field-angle-deg", type=float, default=None, dest="field_angle",
                   help="constant field direction [deg]; the filament starts along it (tilted 0.01 deg)")
    g.add_argument("--field-rotate", type=float, default=None, help="seconds per turn of a rotating field (negative: clockwise)")
    g.add_argument("--field-start", type=float, default=None,
                   help="time at which the rotation, step or ramp starts [s] (default 0)")
    g.add_argument("--field-step", type=float, default=None, help="jump to this direction [deg] at --field-start")
    g.add_argument("--field-ramp", type=float, nargs=2, default=None, metavar=("ANGLE_DEG", "DURATION_S"),
                   help="turn linearly to ANGLE_DEG over DURATION_S from --field-start")
    g.add_argument("--field-csv", default=None,
                   help="CSV of t, angle[, strength] in s and degrees, or the units its header names (t_ms, angle_rad); "
                        "linear between rows (0,0 then 10,180 is a 10 s turn; for a step give two rows a moment apart, "
                        "or use --field-step)")


def field_from_args(args) -> Field | None:
    """The Field the options describe, or None (the default field). At most one schedule."""
    chosen = [k for k in ("field_angle", "field_rotate", "field_step", "field_ramp", "field_csv")
              if getattr(args, k, None) is not None]
    if len(chosen) > 1:
        raise ParameterError(f"give one field schedule, not {', '.join('--' + c.replace('_', '-') for c in chosen)}")
    k = chosen[0] if chosen else None
    given_start = getattr(args, "field_start", None)
    if given_start is not None and k not in ("field_rotate", "field_step", "field_ramp"):
        why = {None: "and none was given", "field_angle": "not --field-angle (a constant direction)",
               "field_csv": "not --field-csv (its times are in the file)"}[k]
        raise ParameterError(f"--field-start={given_start!r} times --field-rotate, --field-step or --field-ramp, {why}")
    if k is None:
        return None
    start = finite("--field-start", 0.0 if given_start is None else given_start)
    if k == "field_angle":
        # (degrees here: Constant, so that Field does not warn about a large angle in radians)
        return Field(direction=Constant(math.radians(finite("--field-angle", args.field_angle))))
    if k == "field_rotate":
        if finite("--field-rotate", args.field_rotate) == 0:  # named as the option, not rotation()'s argument
            raise ParameterError("--field-rotate=0 is not allowed: seconds per turn of a rotating field, a "
                                 "non-zero number (negative: clockwise)")
        return rotation(args.field_rotate, start)
    if k == "field_step":
        return _step(math.radians(finite("--field-step", args.field_step)), start, 0.0)
    if k == "field_ramp":
        return _ramp(math.radians(finite("--field-ramp angle", args.field_ramp[0])), start,
                     positive("--field-ramp duration", args.field_ramp[1]), 0.0)
    return from_csv(args.field_csv)
