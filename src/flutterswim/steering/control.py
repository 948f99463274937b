"""Closed-loop path following by turning the field, on the full model.

Every camera frame (50 fps) the controller observes the centroid with tracking noise and a
one-frame delay, estimates the cycle-averaged position and heading from the last two periods
of observations, and sets the field direction towards the path's direction (``lookahead``
ahead; 0 by default in :func:`~flutterswim.steering.steer.steer`, whose path is already rounded),
corrected towards the path by atan(-e / correction) (e: signed cross-track error), the turn
rate limited below the step-out rate Omega_max and the field kept within ``lead_max`` of the
heading (a field far from the body axis bends the filament into a trap, a bent equilibrium).
Angles use atan2 of cross and dot products, never arccos.

The heading error is not fed back by default (``heading_gain=0``): the heading estimate is a
cycle average, a period or more late, and with a gain of 1 the command hunted by +-5 degrees
at about 0.5 Hz on every straight leg (slewing at the rate limit, 8 degrees/s of needless turning
on the paper's 10 body-length square). Without it (and without lookahead) the legs are straight
and every path tested is followed more closely (cross-track RMS: square 0.080 against 0.090
body lengths, circle of 2 0.003 against 0.008, figure eight 0.004 against 0.011).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .path import RefPath

__all__ = ["Controller", "wrap"]


def wrap(a: float) -> float:
    """Angle in (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


@dataclass
class Controller:
    """Path-direction guidance with cross-track correction and heading feedback. Lengths in m,
    times in s, angles in rad."""

    path: RefPath
    period: float
    speed: float
    omega_max: float
    lookahead: float
    correction: float
    rate_fraction: float = 0.8
    heading_gain: float = 0.0
    lead_max: float = 0.35
    fps: float = 50.0
    integral_rate: float = 0.2  # 1/s: removes the steady cross-track offset on curved paths
    homing: float = 3.0  # beyond this many ``correction`` lengths off the path, head for it directly
    _obs: deque = field(default_factory=deque, repr=False)
    _integral: float = 0.0
    _near: int = 0
    _turn_sign: float = 0.0
    command: float = 0.0
    heading_estimate: float = 0.0

    def observe(self, t: float, xy: np.ndarray) -> None:
        self._obs.append((t, float(xy[0]), float(xy[1])))
        while self._obs and self._obs[0][0] < t - 2.05 * self.period:
            self._obs.popleft()

    def estimate(self) -> tuple[np.ndarray, float] | None:
        """Cycle-averaged position now (extrapolated by half a period) and heading, or None
        until two periods are observed."""
        if not self._obs or self._obs[-1][0] - self._obs[0][0] < 1.95 * self.period:
            return None
        o = np.array(self._obs)
        t_now = o[-1, 0]
        late = o[:, 0] > t_now - self.period
        early = (~late) & (o[:, 0] > t_now - 2 * self.period)
        p1, p0 = o[late, 1:].mean(axis=0), o[early, 1:].mean(axis=0)
        d = p1 - p0
        heading = math.atan2(d[1], d[0])
        pos = p1 + 0.5 * d  # the late average describes the swimmer half a period ago
        return pos, heading

    def _index_ahead(self, i: int, distance: float) -> int:
        s_ahead = self.path.s[i] + distance
        if self.path.closed:
            s_ahead %= self.path.length
        return min(int(np.searchsorted(self.path.s, s_ahead)), len(self.path.s) - 2)

    def update(self, t: float) -> float:
        """The field direction for the next frame."""
        est = self.estimate()
        if est is None:
            return self.command
        pos, heading = est
        self.heading_estimate = heading
        i, e = self.path.project(pos, near=self._near)
        held, homing = self._integral, abs(e) > self.homing * self.correction
        if homing:
            # far off the path (after a bend tighter than the swimmer can turn): home in on a
            # point of the path ahead of its nearest point, searched over the whole path
            i, e = self.path.project(pos)
            self._near = i
            j = self._index_ahead(i, self.correction)
            d = self.path.points[j] - pos
            desired = math.atan2(d[1], d[0])
            self._integral = 0.0
        else:
            self._near = i
            # the path direction a little ahead (turns start before a corner), corrected towards
            # the path over the distance ``correction`` (Stanley-type guidance)
            j = self._index_ahead(i, self.lookahead)
            tj = self.path.points[j + 1] - self.path.points[j]
            self._integral = max(-self.correction,
                                 min(self.correction, self._integral + e / self.fps * self.integral_rate))
            desired = math.atan2(tj[1], tj[0]) + math.atan2(-(e + self._integral), self.correction)
        err = wrap(desired - heading)
        # a turn of nearly 180 degrees: keep turning the way it started (the sign of a wrapped
        # angle near pi flips with the heading's wobble, and the command would chatter in place)
        if abs(err) > 0.8 * math.pi and self._turn_sign != 0.0:
            err = self._turn_sign * abs(err)
        self._turn_sign = math.copysign(1.0, err) if err != 0.0 else self._turn_sign
        if abs(err * (1.0 + self.heading_gain)) >= self.lead_max and not homing:
            # the field's lead is saturated (a turn under way): the cross-track integral waits
            # (it wound up over a 45 degree turn onto a line and overshot the line after it)
            self._integral = held
        # the field leads the heading by the error (times 1 + heading_gain: 1 by default, no
        # feedback), within lead_max of the heading
        # (not wrapped: beyond 90 degrees of error, err (1 + gain) passes pi, and its wrap would
        # turn the field the other way, away from the path)
        target = heading + max(-self.lead_max, min(self.lead_max, err * (1.0 + self.heading_gain)))
        # turning no faster than the rate limit
        max_step = self.rate_fraction * self.omega_max / self.fps
        self.command += max(-max_step, min(max_step, wrap(target - self.command)))
        return self.command
