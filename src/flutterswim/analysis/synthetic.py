"""Analytically prescribed centrelines for testing and demonstrating the analysis."""

from __future__ import annotations

import math

import numpy as np

from .track import Track

__all__ = ["wave_track", "angle_wave_track", "landau_envelope", "figure_eight", "c_shape"]


def landau_envelope(t: np.ndarray, a0: float, a_final: float, rate: float) -> np.ndarray:
    """Solution of dA/dt = rate A (1 - A^2/a_final^2), A(0) = a0 (exponential growth, then
    saturation)."""
    t = np.asarray(t, float)
    return a_final / np.sqrt(1.0 + (a_final**2 / a0**2 - 1.0) * np.exp(-2.0 * rate * t))


def wave_track(
    *,
    length: float = 1.0,
    n_points: int = 41,
    period: float = 0.4,
    wavelength: float = 0.8,
    amplitude: float = 0.1,
    speed: float = 0.05,
    duration: float = 4.0,
    n_frames: int = 1001,
    kind: str = "travelling",
    phase: float = 0.0,
    noise: float = 0.0,
    jitter: float = 0.0,
    envelope: tuple[float, float] | None = None,
    field_angle: float = 0.0,
    seed: int | None = 0,
) -> Track:
    """Centreline y = A(s) sin(k s - w t + phase) (travelling) or A(s) sin(k s) sin(w t + phase)
    (standing), x = s + speed t, with A(s) = amplitude (0.4 + 0.6 s/l), k = 2 pi/wavelength,
    w = 2 pi/period. The whole picture is then rotated by ``field_angle`` (the field points
    along the swimming direction). ``noise``: std of Gaussian noise on x, y; ``jitter``:
    fraction of the mean frame spacing by which frame times are randomly displaced;
    ``envelope = (a0_fraction, rate)`` multiplies A by a Landau envelope growing from
    a0_fraction at t=0 towards 1 at ``rate`` [1/s].

    Tip (s = l) lateral displacement in the lab frame: peak-to-peak 2 A(l) = 2 * amplitude
    (travelling wave, or standing wave with sin(k l) = +-1); net advancement per period:
    speed * period.
    """
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, duration, n_frames)
    if jitter:
        dt = duration / (n_frames - 1)
        t[1:-1] += rng.uniform(-0.5, 0.5, n_frames - 2) * jitter * dt
    s = np.linspace(0.0, length, n_points)
    k, w = 2 * math.pi / wavelength, 2 * math.pi / period
    A = amplitude * (0.4 + 0.6 * s / length)
    T, S = np.meshgrid(t, s, indexing="ij")
    if kind == "travelling":
        y = A * np.sin(k * S - w * T + phase)
    elif kind == "standing":
        y = A * np.sin(k * S) * np.sin(w * T + phase)
    else:
        raise ValueError(f"kind={kind!r}; use 'travelling' or 'standing'")
    if envelope is not None:
        a0, rate = envelope
        y = y * landau_envelope(t, a0, 1.0, rate)[:, None]
    x = S + speed * T
    if noise:
        x = x + rng.normal(0.0, noise, x.shape)
        y = y + rng.normal(0.0, noise, y.shape)
    c, sn = math.cos(field_angle), math.sin(field_angle)
    X, Y = c * x - sn * y, sn * x + c * y
    return Track(t=t, x=X, y=Y, s=s, field_angle=field_angle, length=length, units="m")


def angle_wave_track(
    *,
    length: float = 1.0,
    n_points: int = 81,
    period: float = 0.4,
    wavelength: float = 0.5,
    angle: float = 0.5,
    speed: float = 0.05,
    duration: float = 2.0,
    n_frames: int = 401,
) -> Track:
    """Inextensible centreline with tangent angle theta(s, t) = angle sin(k s - w t), integrated
    from the s = 0 end placed at (speed t, 0). Large ``angle`` (> ~2 rad) with a short
    wavelength makes the centreline loop over itself."""
    t = np.linspace(0.0, duration, n_frames)
    s = np.linspace(0.0, length, n_points)
    k, w = 2 * math.pi / wavelength, 2 * math.pi / period
    th = angle * np.sin(k * s[None, :] - w * t[:, None])
    ds = np.diff(s)
    cx = 0.5 * (np.cos(th[:, 1:]) + np.cos(th[:, :-1])) * ds
    cy = 0.5 * (np.sin(th[:, 1:]) + np.sin(th[:, :-1])) * ds
    x = np.concatenate([np.zeros((n_frames, 1)), np.cumsum(cx, axis=1)], axis=1) + speed * t[:, None]
    y = np.concatenate([np.zeros((n_frames, 1)), np.cumsum(cy, axis=1)], axis=1)
    return Track(t=t, x=x, y=y, s=s, length=length, units="m")


def figure_eight(n_points: int = 81, size: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """An open figure-eight (lemniscate of Gerono, a little more than one loop): it passes
    through the origin at u = pi and u = 2 pi in different directions, so it crosses itself."""
    u = np.linspace(0.2, 2 * math.pi + 0.1, n_points)
    return size * np.sin(u), size * np.sin(u) * np.cos(u)


def c_shape(n_points: int = 81, radius: float = 1.0, opening: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """An arc of a circle leaving an angular gap ``opening`` [rad]: no self-intersection."""
    u = np.linspace(opening / 2, 2 * math.pi - opening / 2, n_points)
    return radius * np.cos(u), radius * np.sin(u)
