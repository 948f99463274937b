"""Periodic orbits as CF variables: the stroke descriptors of each orbit along a dimension
``orbit``, with units and long names, and its largest Floquet multipliers. Used by a branch's
dataset (:meth:`Branch.to_dataset`) and for one orbit (``flutterswim reproduce``'s
``paper_orbit.nc``)."""

from __future__ import annotations

import numpy as np

__all__ = ["N_MULTIPLIERS", "orbits_dataset"]

#: Floquet multipliers written per orbit (the largest moduli)
N_MULTIPLIERS = 6


def _half_open_degrees(radians: np.ndarray) -> np.ndarray:
    """Degrees in (-180, 180]: a stroke swimming against the field (along -x up to round-off)
    reads 180, not -180 or 180 by the sign of a round-off in its lateral drift."""
    d = np.degrees(radians)
    return np.where(d <= -180.0 + 1e-6, 180.0, d)  # (exactly 180: -179.9999999 + 360 left the range)


def orbits_dataset(orbs, *, si: bool, orbit_long_name: str = "orbit number"):
    """The descriptors of the :class:`PeriodicOrbit` s ``orbs`` along ``orbit`` (0, 1, ...):
    lengths and times in m and s when ``si`` (physical parameters), else in l and tau; every
    variable with ``units`` and ``long_name`` (apply :func:`flutterswim._cf.cf_dataset` before
    writing). ``leading_end`` is a flag (0: s=0, 1: s=l)."""
    import xarray as xr

    tu, lu = ("s", "m") if si else ("tau", "l")

    def col(key):
        return np.array([getattr(o, key) for o in orbs], dtype=float)

    data = {
        "period": (col("period"), tu, "period of the stroke"),
        "advance": (col("advance"), lu, "net advance per cycle (its magnitude; its direction: swim_direction)"),
        "swim_direction": (_half_open_degrees(col("swim_direction")), "degree",
                           "direction of the net advance per cycle, anticlockwise from the field (x axis), "
                           "in (-180, 180]"),
        "leading_end": (np.array([o.leading_end == "s=l" for o in orbs], dtype="i1"), "1",
                        "the end of the filament that leads along swim_direction (lateral_leading is "
                        "its excursion)"),
        "speed": (col("speed"), f"{lu} {tu}-1", "mean swimming speed"),
        "lateral_leading": (col("lateral_leading"), lu, "lateral peak-to-peak excursion of the leading end"),
        "lateral_trailing": (col("lateral_trailing"), lu, "lateral peak-to-peak excursion of the trailing end"),
        "amplitude": (col("amplitude"), "1",
                      "2 |first Fourier coefficient of the shape (theta, kappa l)| / sqrt(2N+1): RMS over the "
                      "2N+1 shape components of the first harmonic's amplitude (its scale independent of N; its value near the Hopf point converges with N at order 2)"),
        "nonreciprocity": (col("nonreciprocity"), "1", "signed area of the stroke in the first two shape modes"),
        "self_intersecting": (col("self_intersecting").astype("i1"), "1", "filament crosses itself during the stroke (0/1)"),
        "stable": (col("stable").astype("i1"), "1", "orbit stable: all non-trivial Floquet multipliers inside the unit circle (0/1)"),
        "max_multiplier": (np.array([o.max_multiplier for o in orbs]), "1", "largest modulus of the non-trivial Floquet multipliers"),
        "trivial_multiplier_error": (col("trivial_multiplier_error"), "1", "|trivial Floquet multiplier - 1| (accuracy gauge)"),
        "step_error": (col("step_error"), "1", "relative change of period or advance when the steps per period are "
                       "doubled, or the step screen's estimate of it (NaN: not checked, an orbit from a neighbour or "
                       "with steps given)"),
        "steps_per_period": (col("steps").astype("i4"), "1", "Radau steps per period the orbit was solved with"),
        "residual": (col("residual"), "1", "max-norm residual of the closing condition"),
        "n_newton": (col("n_newton").astype("i4"), "1", "Newton iterations"),
    }
    mults = np.array([o.multipliers[:N_MULTIPLIERS] for o in orbs]) if orbs else np.zeros((0, N_MULTIPLIERS))
    ds = xr.Dataset(
        {k: (("orbit",), v, {"units": u, "long_name": ln}) for k, (v, u, ln) in data.items()},
        coords={"orbit": (("orbit",), np.arange(len(orbs), dtype="i4"), {"units": "1", "long_name": orbit_long_name})},
    )
    ds["multiplier_real"] = (("orbit", "multiplier"), mults.real, {"units": "1", "long_name": "Floquet multipliers (largest moduli), real part"})
    ds["multiplier_imag"] = (("orbit", "multiplier"), mults.imag, {"units": "1", "long_name": "Floquet multipliers (largest moduli), imaginary part"})
    flags = {"leading_end": "s_equals_0 s_equals_l", "self_intersecting": "no yes", "stable": "unstable stable"}
    for k, meanings in flags.items():
        ds[k].attrs.update({"flag_values": np.array([0, 1], dtype="i1"), "flag_meanings": meanings})
    return ds.assign_coords(multiplier=("multiplier", np.arange(N_MULTIPLIERS), {"units": "1", "long_name": "rank by modulus"}))
