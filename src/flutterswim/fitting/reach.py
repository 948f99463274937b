"""What the model reached during a fit, and whether the data are beyond it.

A fit records every trial point: the descriptors of those with a stroke, and how many had
none. It stops after MAX_FAILED_IN_A_ROW failed points in a row or MAX_FAILED_POINTS in all
(failed and successful points interleave when the optimiser presses against the edge of the
region with a stroke: each failure costs orbit solves that fail slowly).

Which descriptors can be out of reach: the period never (tau scales it and nothing else);
the advance and the lateral excursion only from above, since both vanish at the onset of
swimming (the stroke grows from zero amplitude at the Hopf point), so any smaller value is
reached near it. A measured advance or lateral is *out of reach* when, less Z_MARGIN of its
SEMs, it exceeds the largest value the model reached by more than a finer model could add
(MAX_REFINEMENT_CHANGE: the largest change from N to 2N segments the model accepts).
"""

from __future__ import annotations

import math
import time

import numpy as np

from .model import MAX_REFINEMENT_CHANGE

__all__ = ["Reach", "Stuck", "beyond_resolution", "MAX_FAILED_IN_A_ROW", "MAX_FAILED_POINTS", "Z_MARGIN"]

#: trial points in a row without a stable stroke after which a fit stops
MAX_FAILED_IN_A_ROW = 6
#: trial points in all without a stable stroke after which a fit stops
MAX_FAILED_POINTS = 2 * MAX_FAILED_IN_A_ROW
#: SEMs by which a measured value must exceed the model's reach to be called out of reach
Z_MARGIN = 3.0

_NAMES = ("period", "advance", "lateral")
_UNITS = ("s", "mm", "mm")


class Stuck(Exception):
    """Too many trial points without a stroke: stop at the best point so far (``x``)."""

    def __init__(self, x, message):
        super().__init__(message)
        self.x = x


class Reach:
    """Trial points of one fit: the best with a stroke, the range of each descriptor over all
    with a stroke, and the failures (in a row and in all)."""

    def __init__(self, seconds: float = math.inf):
        self.in_a_row, self.failed, self.best_x, self.best = 0, 0, None, math.inf
        self.lo, self.hi, self.n_strokes = np.full(3, np.inf), np.full(3, -np.inf), 0
        self.seconds, self.deadline, self.timed_out = seconds, time.perf_counter() + seconds, False

    def record(self, x, r, y) -> None:
        """Note trial point ``x`` with weighted residuals ``r`` and descriptors ``y`` (None: no
        stroke); raise :class:`Stuck` when the failures reach a limit and a stroke was found, or
        when the fit has run for longer than ``seconds`` (``timed_out``)."""
        if self.best_x is not None and time.perf_counter() > self.deadline:
            self.timed_out = True
            raise Stuck(self.best_x, "stopped at the fit's time limit without converging")
        if y is not None:
            self.in_a_row, self.n_strokes = 0, self.n_strokes + 1
            self.lo, self.hi = np.minimum(self.lo, y), np.maximum(self.hi, y)
            if float(np.sum(r ** 2)) < self.best:
                self.best_x, self.best = np.array(x, float), float(np.sum(r ** 2))
            return
        self.in_a_row += 1
        self.failed += 1
        if self.best_x is None:
            return
        if self.in_a_row >= MAX_FAILED_IN_A_ROW:
            raise Stuck(self.best_x, f"stopped: the last {self.in_a_row} points the fit tried have no stable stroke "
                        "(the model fails there); the data are outside what the model can reproduce near the best "
                        "point found")
        if self.failed >= MAX_FAILED_POINTS:
            raise Stuck(self.best_x, f"stopped: {self.failed} of the points the fit tried have no stable stroke "
                        "(the model fails there); the data are outside what the model can reproduce near the best "
                        "point found")

    def beyond(self, mean, sem) -> str | None:
        """Why the data are beyond what the model reached (the descriptors out of reach,
        measured vs the model's range), or None."""
        if self.n_strokes == 0 or sem is None:
            return None
        out = []
        for k in (1, 2):  # the period is never out of reach; advance and lateral only from above
            if mean[k] - Z_MARGIN * sem[k] > self.hi[k] * (1.0 + MAX_REFINEMENT_CHANGE):
                out.append(f"{_NAMES[k]} {mean[k]:.4g} +- {sem[k]:.2g} {_UNITS[k]} measured, the model's "
                           f"{self.lo[k]:.4g} to {self.hi[k]:.4g} {_UNITS[k]}"
                           + units_hint(mean[k], self.lo[k], self.hi[k]))
        if not out:
            return None
        return ("; ".join(out) + f" over the {self.n_strokes} strokes the fit computed ({self.failed} trial points "
                "had none); more segments would not change this")


def units_hint(measured: float, lo: float, hi: float) -> str:
    """A hint when ``measured`` is about 10, 100 or 1000 times the model's largest ``hi`` (within
    a factor 2) and ``measured`` / 10^k lies within [lo / 2, 2 hi]: a column in um or cm taken
    for mm (a review: lateral in um was refused without a word on units). A value beyond the
    model's reach by some other factor gets none (a wider test named a units mix-up for nearly
    every refused value)."""
    import math

    if not (measured > 0 and hi > 0):
        return ""
    decades = math.log10(measured / hi)
    k = round(decades)
    if 1 <= k <= 3 and abs(decades - k) < math.log10(2.0) and lo / 2.0 <= measured / 10.0 ** k <= 2.0 * hi:
        return f" ({10 ** k:g} times the model's: is the column in other units than mm?)"
    return ""


#: how many times the last unresolved stroke's change from N to 2N segments (plus 3 SEM) a
#: descriptor may miss by and still be blamed on the resolution (Richardson's error is a third
#: of the change at order 2; twice the change is a generous bound for strokes not yet in it)
RESOLUTION_MISS_FACTOR = 2.0


def beyond_resolution(res, change: float) -> str | None:
    """The descriptors a fit's best point (``res``: a FitResult) misses by more than the
    unresolved strokes' change with resolution could explain (``change``: relative, N to 2N
    segments), in words, or None."""
    if not change > 0 or not np.all(np.isfinite(res.sem)):
        return None
    meas, mod, sem = (np.ravel(a) for a in (res.measured, res.model, res.sem))
    allowed = RESOLUTION_MISS_FACTOR * change * np.abs(mod) + Z_MARGIN * sem
    units = _UNITS * (meas.size // 3)
    out = [f"{n} {m:.4g} {u} measured, {y:.4g} {u} in the model ({y / m:.3g} times)"
           for n, m, y, u, a in zip(res._descriptor_names(), meas, mod, units, allowed) if abs(y - m) > a]
    if not out:
        return None
    return "; ".join(out) + (f", misses beyond {RESOLUTION_MISS_FACTOR:g} x the {100 * change:.3g} % by which the "
                             "unresolved strokes there change with resolution")
