"""Initial states of the filament, in dimensionless units (lengths in l)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ._validate import ParameterError, finite, finite_array

__all__ = ["InitialState"]


@dataclass(frozen=True)
class InitialState:
    """theta(s) and kappa(s) on s in [0, 1] (a number, a callable of s, or samples on a
    uniform grid including both ends) and the position of the s = 0 end in body lengths.
    kappa is per body length (kappa l)."""

    theta: "float | np.ndarray | Callable[[np.ndarray], np.ndarray]" = 0.0
    kappa: "float | np.ndarray | Callable[[np.ndarray], np.ndarray]" = 0.0
    position: tuple[float, float] = (0.0, 0.0)

    @classmethod
    def straight(cls, angle_deg: float = 0.01, position: tuple[float, float] = (0.0, 0.0)) -> "InitialState":
        """Straight, stress-free filament at ``angle_deg`` degrees to e1 (the paper: 0.01)."""
        return cls(theta=math.radians(finite("angle_deg", angle_deg)), kappa=0.0, position=position)

    @classmethod
    def from_state(cls, y: np.ndarray, n: int) -> "InitialState":
        """Continue from a discrete state vector y = [x0, y0, theta (N), kappa (N+1)]."""
        y = np.asarray(y, dtype=float)
        return cls(theta=y[2 : n + 2].copy(), kappa=y[n + 2 :].copy(), position=(y[0], y[1]))

    def state(self, n: int) -> np.ndarray:
        """Discrete state vector for N = n segments."""
        s_mid = (np.arange(n) + 0.5) / n
        s_nodes = np.arange(n + 1) / n
        theta = _sample("theta", self.theta, s_mid)
        kappa = _sample("kappa", self.kappa, s_nodes)
        pos = finite_array("position", self.position, (2,))
        return np.concatenate((pos, theta, kappa))

    def describe(self) -> str:
        def d(v):
            if callable(v):
                return getattr(v, "__name__", "callable")
            arr = np.asarray(v)
            return f"{float(arr):.10g}" if arr.ndim == 0 else f"array[{arr.size}]"

        return f"theta={d(self.theta)}; kappa={d(self.kappa)}; position={tuple(self.position)}"


def _sample(name: str, value, s: np.ndarray) -> np.ndarray:
    """Values at the points s: a number, a callable of s, samples already at s, or samples on
    a uniform grid over [0, 1] including both ends (linearly interpolated)."""
    if callable(value):
        out = np.broadcast_to(np.asarray(value(s), dtype=float), s.shape).copy()
        return finite_array(name, out)
    arr = finite_array(name, value)
    if arr.ndim == 0:
        return np.full(s.shape, float(arr))
    if arr.ndim != 1 or arr.size < 2:
        raise ParameterError(f"{name} has shape {arr.shape}; give a number, a callable of s or a 1-D array")
    if arr.size == s.size:
        return arr.copy()
    return np.interp(s, np.linspace(0.0, 1.0, arr.size), arr)
