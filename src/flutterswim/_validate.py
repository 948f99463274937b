"""Input checks that name the parameter, its value and what is allowed."""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np


class ParameterError(ValueError):
    """A parameter value is outside what the model or the solver allows."""


def finite(name: str, value: Any, *, strict: bool = False) -> float:
    """Return ``value`` as float, or raise if it is not a finite real number; ``strict``: also
    if it is a string or a bool (``"1"``, ``True``), which ``float`` would read as a number."""
    if strict and isinstance(value, (str, bytes, bool, np.bool_)):
        raise ParameterError(f"{name}={value!r} is a {type(value).__name__}, not a number; a finite float "
                             "is required")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} is not a real number; a finite float is required") from None
    if not math.isfinite(v):
        raise ParameterError(f"{name}={value!r} is not finite; a finite float is required")
    return v


def positive(name: str, value: Any, *, strict: bool = False) -> float:
    """Return ``value`` as float, or raise if it is not finite and > 0 (``strict``: as :func:`finite`)."""
    v = finite(name, value, strict=strict)
    if v <= 0.0:
        raise ParameterError(f"{name}={value!r} must be > 0")
    return v


#: Largest relative or absolute tolerance of the time integrator accepted: beyond it the error
#: control no longer controls anything (the state is O(1): angles in rad, positions in units of l).
MAX_TOLERANCE = 0.1
#: rtol and atol may not both be below this: the error asked for, atol + rtol |y| on an O(1)
#: state, would be below what round-off leaves (~1e-16 per step, summed over the steps), and the
#: step size collapses (a review: rtol 1e-13, atol 1e-15 ran 24 s, 1.9 million steps, and failed
#: at t = 32 tau; 1e-12 completes). Either alone may be smaller (rtol 1e-14 with atol 1e-7: an
#: absolute error norm)
MIN_TOLERANCE = 1e-12


def tolerance(name: str, value: Any, *, strict: bool = False) -> float:
    """An integrator tolerance (rtol, atol): finite, > 0 and at most :data:`MAX_TOLERANCE`."""
    v = positive(name, value, strict=strict)
    if v > MAX_TOLERANCE:
        raise ParameterError(f"{name}={value!r} is too large; a tolerance in (0, {MAX_TOLERANCE:g}] is required "
                             "(default rtol 1e-4, atol 1e-6)")
    return v


def tolerances_reachable(rtol: float, atol: float) -> None:
    """Refuse rtol and atol both below :data:`MIN_TOLERANCE` (the step size would collapse)."""
    if max(rtol, atol) < MIN_TOLERANCE:
        raise ParameterError(f"rtol={rtol!r} and atol={atol!r} are both below {MIN_TOLERANCE:g}: round-off in the state "
                             "exceeds the error asked for, and the step size would collapse; at least one of them "
                             f">= {MIN_TOLERANCE:g} is required")


def non_negative(name: str, value: Any) -> float:
    v = finite(name, value)
    if v < 0.0:
        raise ParameterError(f"{name}={value!r} must be >= 0")
    return v


def within(name: str, value: Any, lo: float, hi: float, why: str = "") -> float:
    """A finite number in [lo, hi]; ``why``: what the bounds mean, said with them."""
    v = finite(name, value)
    if not lo <= v <= hi:
        raise ParameterError(f"{name}={value!r} must be in [{lo:g}, {hi:g}]" + (f" ({why})" if why else ""))
    return v


def positive_int(name: str, value: Any, minimum: int = 1, maximum: int | None = None, why: str = "") -> int:
    """An integer in [minimum, maximum]; ``why``: what the maximum guards against, said with it."""
    allowed = f">= {minimum}" if maximum is None else f"in [{minimum}, {maximum}]"
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ParameterError(f"{name}={value!r} must be an integer {allowed}")
    if value < minimum or (maximum is not None and value > maximum):
        raise ParameterError(f"{name}={value!r} must be an integer {allowed}" + (f" ({why})" if why else ""))
    return int(value)


#: most segments a filament may have: the convergence studies go to 384; 10^4 asked for
#: gigabytes before failing (a dense Jacobian and a periodic orbit's step matrices grow as N^2)
MAX_SEGMENTS = 1024


def n_segments(value: Any, name: str = "n_segments") -> int:
    """The number of segments: an integer in [4, MAX_SEGMENTS]."""
    return positive_int(name, value, 4, MAX_SEGMENTS,
                        "beyond it memory grows as N^2; 48 resolve the paper's stroke to 0.4 %")


def finite_array(name: str, value: Any, shape: tuple[int, ...] | None = None) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if shape is not None and arr.shape != shape:
        raise ParameterError(f"{name} has shape {arr.shape}; shape {shape} is required")
    if not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise ParameterError(f"{name} has {bad} non-finite entries; all entries must be finite")
    return arr


def direction_deg(name: str, value: Any) -> float:
    """A direction given in degrees (a command line's) as radians in (-pi, pi]: the same
    direction, so that a turn or more in degrees does not read as degrees given as radians
    (:func:`angle`'s warning)."""
    return math.radians(math.remainder(finite(name, value), 360.0))


def angle(name: str, value: Any, *, stacklevel: int = 1) -> float:
    """Return ``value`` (an angle in radians) as float, or raise if it is not finite; warn
    (UserWarning naming ``name``) if its magnitude exceeds 2 pi, likely degrees given where
    radians are taken (``step(90, 8)`` is 90 rad, over 14 turns, not a quarter turn). The
    warning points ``stacklevel`` frames above the function that calls this one (1: its caller)."""
    v = finite(name, value)
    if abs(v) > 2 * math.pi:
        warnings.warn(f"{name}={value!r} is in radians, and its magnitude exceeds 2 pi (more than a full turn): "
                      f"degrees given as radians? (for {value!r} degrees pass math.radians({value!r}) = "
                      f"{math.radians(v):.6g})", UserWarning, stacklevel=2 + stacklevel)
    return v
