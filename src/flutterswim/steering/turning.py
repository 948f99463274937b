"""Analysis of a turning run: the cycle-averaged centroid path and heading, the heading lag to
the field, the turning radius by a circle fit, and the speed while turning.

The body oscillates within a stroke by about a third of its length, so everything here uses
the centroid averaged over a sliding window of one period (a moving average removes the
stroke's harmonics exactly for a periodic stroke).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import ParameterError

__all__ = ["Averaged", "cycle_average", "fit_circle", "TurningDescriptors", "describe_turning"]


@dataclass(frozen=True)
class Averaged:
    """Cycle-averaged path: times t (K,), centroid x, y (K,), heading (K,) [rad, unwrapped,
    direction of the averaged velocity], speed (K,), field direction (K,) and the heading lag
    (heading - field) (K,) [rad]. Lengths and times in the run's units."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    field: np.ndarray
    lag: np.ndarray
    period: float


def _moving_average(t: np.ndarray, v: np.ndarray, window: float) -> tuple[np.ndarray, np.ndarray]:
    """Average of v over [t - window/2, t + window/2] (trapezoidal on the samples, with
    linear interpolation at the window ends), on the samples whose window fits."""
    from scipy.integrate import cumulative_trapezoid

    cv = cumulative_trapezoid(v, t, initial=0.0)
    lo, hi = t - window / 2, t + window / 2
    ok = (lo >= t[0]) & (hi <= t[-1])
    ts = t[ok]
    avg = (np.interp(ts + window / 2, t, cv) - np.interp(ts - window / 2, t, cv)) / window
    return ts, avg


def cycle_average(t: np.ndarray, x: np.ndarray, y: np.ndarray, field: np.ndarray, period: float) -> Averaged:
    """From the centroid (x, y) (T,) and field direction (T,) sampled at t, with the stroke
    period. Heading: direction of the averaged displacement over one period."""
    if not period > 0:
        raise ParameterError(f"period={period!r} must be > 0")
    ts, ax = _moving_average(t, x, period)
    _, ay = _moving_average(t, y, period)
    if ts.size < 5:
        raise ParameterError("the run is too short for a cycle average (needs several periods)")
    vx, vy = np.gradient(ax, ts), np.gradient(ay, ts)
    heading = np.unwrap(np.arctan2(vy, vx))
    fld = np.interp(ts, t, np.unwrap(field))
    lag = heading - fld
    return Averaged(ts, ax, ay, heading, np.hypot(vx, vy), fld, lag, period)


def fit_circle(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    """Least-squares circle through points (algebraic Kasa fit refined by Gauss-Newton on the
    geometric distance). Returns (xc, yc, radius, rms distance)."""
    a = np.stack([x, y, np.ones_like(x)], axis=1)
    b = x * x + y * y
    c, *_ = np.linalg.lstsq(a, b, rcond=None)
    xc, yc = c[0] / 2, c[1] / 2
    r = math.sqrt(max(c[2] + xc * xc + yc * yc, 0.0))
    for _ in range(20):
        d = np.hypot(x - xc, y - yc)
        res = d - r
        j = np.stack([-(x - xc) / d, -(y - yc) / d, -np.ones_like(d)], axis=1)
        step, *_ = np.linalg.lstsq(j, -res, rcond=None)
        xc, yc, r = xc + step[0], yc + step[1], r + step[2]
        if np.max(np.abs(step)) < 1e-12 * max(1.0, r):
            break
    d = np.hypot(x - xc, y - yc)
    return float(xc), float(yc), float(abs(r)), float(np.sqrt(np.mean((d - abs(r)) ** 2)))


@dataclass(frozen=True)
class TurningDescriptors:
    """Of the part of a run where the field turns: mean turn rate of the field and of the
    heading [rad per time unit], heading lag to the field (mean and its std) [rad], turning
    radius from a circle fit of the averaged path and its rms residual, speed while turning."""

    field_turn_rate: float
    heading_turn_rate: float
    heading_lag: float
    heading_lag_std: float
    turning_radius: float
    circle_fit_rms: float
    speed_turning: float
    following: bool


def describe_turning(avg: Averaged, t0: float | None = None, t1: float | None = None) -> TurningDescriptors:
    """Turning descriptors of ``avg`` over [t0, t1] (default: where the field turns)."""
    t = avg.t
    m = np.ones_like(t, bool)
    if t0 is not None:
        m &= t >= t0
    if t1 is not None:
        m &= t <= t1
    if np.count_nonzero(m) < 5:
        raise ParameterError("fewer than 5 averaged samples in the turning window")
    tt = t[m]
    frate = float(np.polyfit(tt, avg.field[m], 1)[0])
    hrate = float(np.polyfit(tt, avg.heading[m], 1)[0])
    lag = avg.lag[m]
    xc, yc, r, rms = fit_circle(avg.x[m], avg.y[m])
    following = abs(hrate - frate) < 0.05 * max(abs(frate), 1e-12)
    return TurningDescriptors(frate, hrate, float(np.mean(lag)), float(np.std(lag)), r, rms,
                              float(np.mean(avg.speed[m])), bool(following))


def turning_summary(t: np.ndarray, x: np.ndarray, y: np.ndarray, field: np.ndarray, period: float) -> dict:
    """For describe: turning radius, heading lag and turn rates, speed while turning over the
    part of the run where the field turns (from 4 periods after it starts turning), and the
    speed over the 3 periods before it starts; NaN if the field does not turn by at least 5
    degrees."""
    nan = {"turning_radius": math.nan, "heading_lag": math.nan, "heading_lag_std": math.nan,
           "field_turn_rate": math.nan, "heading_turn_rate": math.nan, "turning_speed": math.nan,
           "circle_fit_rms": math.nan, "speed_before_turning": math.nan}
    f = np.unwrap(field)
    if f.size < 10 or np.ptp(f) < math.radians(5.0) or not period > 0:
        return nan
    moving = np.abs(np.gradient(f, t)) > 1e-9
    if not moving.any():
        return nan
    t_move = float(t[np.argmax(moving)])
    t_start = t_move + 4 * period
    t_stop = t[len(moving) - 1 - np.argmax(moving[::-1])] - period
    try:
        avg = cycle_average(t, x, y, field, period)
        d = describe_turning(avg, t_start, t_stop)
    except ParameterError:
        return nan
    # the averaged speed over the 3 periods before the field starts turning (NaN if the record
    # holds fewer): a swimmer that has stepped out swims far slower while the field turns
    before = (avg.t >= t_move - 3 * period) & (avg.t <= t_move)
    speed_before = float(np.mean(avg.speed[before])) if np.count_nonzero(before) >= 3 else math.nan
    return {"turning_radius": d.turning_radius, "heading_lag": d.heading_lag, "heading_lag_std": d.heading_lag_std,
            "field_turn_rate": d.field_turn_rate, "heading_turn_rate": d.heading_turn_rate,
            "turning_speed": d.speed_turning, "circle_fit_rms": d.circle_fit_rms, "speed_before_turning": speed_before}
