"""Electric-field schedules: direction phi_E(t) and strength multiplier of kappa_E.

Each may be a constant, a piecewise schedule or any callable of time. Times are in
the units of the call that uses the field (seconds for physical parameters, tau for
dimensionless ones); :func:`as_schedule` turns any of these into a
:class:`Schedule`, which the integrator queries and whose breakpoints it steps to.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from ._validate import ParameterError, angle as _angle, finite, finite_array

__all__ = ["Constant", "Piecewise", "FromCallable", "Field", "as_schedule"]


class Schedule:
    """A scalar function of time with known breakpoints (where it may jump)."""

    breakpoints: tuple[float, ...] = ()
    is_constant: bool = False

    @property
    def jumps(self) -> tuple[float, ...]:
        """The breakpoints where the value may jump (a multistep integrator restarts there;
        at the others, kinks of a continuous schedule, it steps through). All of them unless
        the schedule knows better."""
        return tuple(self.breakpoints)

    @property
    def steady_between_breakpoints(self) -> bool:
        """True if the value only changes at the breakpoints (the integrator steps to
        them, so within a step the field does not depend on time)."""
        return self.is_constant

    def __call__(self, t: float) -> float:  # pragma: no cover - interface
        raise NotImplementedError

    def scaled(self, time_scale: float) -> "Schedule":
        """The same schedule seen in time units ``t' = t / time_scale``."""
        return _Rescaled(self, time_scale)

    def describe(self) -> str:  # pragma: no cover - interface
        raise NotImplementedError


@dataclass(frozen=True)
class Constant(Schedule):
    value: float
    is_constant: bool = field(default=True, init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", finite("value", self.value))

    def __call__(self, t: float) -> float:
        return self.value

    def scaled(self, time_scale: float) -> "Schedule":
        return self

    def describe(self) -> str:
        return f"constant({self.value:.10g})"


@dataclass(frozen=True)
class Piecewise(Schedule):
    """Values at ``times``; ``kind="hold"`` keeps each value until the next time
    (before the first time, the first value), ``kind="linear"`` interpolates."""

    times: Sequence[float]
    values: Sequence[float]
    kind: str = "hold"

    def __post_init__(self) -> None:
        t = finite_array("times", self.times)
        v = finite_array("values", self.values)
        if t.ndim != 1 or t.shape != v.shape or t.size == 0:
            raise ParameterError(
                f"times and values must be 1-D of equal, non-zero length; got {t.shape} and {v.shape}"
            )
        if np.any(np.diff(t) <= 0):
            raise ParameterError(f"times={t.tolist()} must be strictly increasing")
        if self.kind not in ("hold", "linear"):
            raise ParameterError(f"kind={self.kind!r} is unknown; choose 'hold' or 'linear'")
        object.__setattr__(self, "times", tuple(float(x) for x in t))
        object.__setattr__(self, "values", tuple(float(x) for x in v))

    @property
    def breakpoints(self) -> tuple[float, ...]:  # type: ignore[override]
        return self.times

    @property
    def steady_between_breakpoints(self) -> bool:
        return self.kind == "hold"

    @property
    def jumps(self) -> tuple[float, ...]:
        return self.times if self.kind == "hold" else ()  # linear: continuous, kinks only

    def __call__(self, t: float) -> float:
        if self.kind == "linear":
            return float(np.interp(t, self.times, self.values))
        i = int(np.searchsorted(self.times, t, side="right")) - 1
        return self.values[max(i, 0)]

    def scaled(self, time_scale: float) -> "Schedule":
        return Piecewise(tuple(x / time_scale for x in self.times), self.values, self.kind)

    def describe(self) -> str:
        pairs = ", ".join(f"({a:.6g}, {b:.6g})" for a, b in zip(self.times, self.values))
        return f"piecewise-{self.kind}[{pairs}]"


@dataclass(frozen=True)
class FromCallable(Schedule):
    func: Callable[[float], float]
    breakpoints: tuple[float, ...] = ()
    name: str = ""

    def __call__(self, t: float) -> float:
        v = float(self.func(t))
        if not np.isfinite(v):
            raise ParameterError(f"field schedule {self.describe()} returned {v!r} at t={t!r}")
        return v

    def describe(self) -> str:
        return f"callable({self.name or getattr(self.func, '__name__', 'function')})"


@dataclass(frozen=True)
class _Rescaled(Schedule):
    base: Schedule
    time_scale: float

    @property
    def breakpoints(self) -> tuple[float, ...]:  # type: ignore[override]
        return tuple(b / self.time_scale for b in self.base.breakpoints)

    @property
    def jumps(self) -> tuple[float, ...]:
        return tuple(b / self.time_scale for b in self.base.jumps)

    @property
    def steady_between_breakpoints(self) -> bool:
        return self.base.steady_between_breakpoints

    def __call__(self, t: float) -> float:
        return self.base(t * self.time_scale)

    def describe(self) -> str:
        return self.base.describe()


def as_schedule(value: "float | Schedule | Callable[[float], float]", name: str) -> Schedule:
    if isinstance(value, Schedule):
        return value
    if callable(value):
        return FromCallable(value, name=getattr(value, "__name__", name))
    return Constant(finite(name, value))  # raises ParameterError naming the value


@dataclass(frozen=True)
class Field:
    """Field direction ``direction`` (radians from e1, anticlockwise) and ``strength``
    (a multiplier of kappa_E; 0 switches the field off). A constant ``direction`` of
    magnitude above 2 pi warns (likely degrees: pass ``math.radians(90)``, not 90)."""

    direction: "float | Schedule | Callable[[float], float]" = 0.0
    strength: "float | Schedule | Callable[[float], float]" = 1.0

    def __post_init__(self) -> None:
        if not isinstance(self.direction, Schedule) and not callable(self.direction):
            # a number: an angle in radians (the caller's frame is two above: __init__, then it)
            object.__setattr__(self, "direction", _angle("direction", self.direction, stacklevel=2))
        object.__setattr__(self, "direction", as_schedule(self.direction, "direction"))
        object.__setattr__(self, "strength", as_schedule(self.strength, "strength"))

    @property
    def is_constant(self) -> bool:
        return self.direction.is_constant and self.strength.is_constant

    @property
    def steady_between_breakpoints(self) -> bool:
        return self.direction.steady_between_breakpoints and self.strength.steady_between_breakpoints

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return tuple(sorted(set(self.direction.breakpoints) | set(self.strength.breakpoints)))

    @property
    def jumps(self) -> tuple[float, ...]:
        return tuple(sorted(set(self.direction.jumps) | set(self.strength.jumps)))

    def scaled(self, time_scale: float) -> "Field":
        return Field(self.direction.scaled(time_scale), self.strength.scaled(time_scale))

    def describe(self) -> str:
        return f"direction={self.direction.describe()}; strength={self.strength.describe()}"
