"""The numeric data of Table 1, of the representative run's periodic orbit and of Fig. 3e as
CF datasets: every variable with ``units`` and ``long_name`` (written by
:func:`.io.write_netcdf`), words (where the data came from, a fit's message) as global
attributes."""

from __future__ import annotations


import numpy as np

from ..params import LONG_NAMES, UNITS

__all__ = ["table1_dataset", "orbit_dataset", "read_orbit", "trials_dataset", "fit_dataset", "DESCRIPTORS"]

#: Fig. 3e's descriptors: (name, unit, long name), in the order of the trials' and the fit's columns
DESCRIPTORS = (("period", "s", "period of the stroke"), ("advance", "mm", "advance per cycle"),
               ("lateral", "mm", "lateral peak-to-peak excursion of the trailing tip"))


def _v(dims, values, units, long_name):
    return (dims, np.asarray(values), {"units": units, "long_name": long_name})


def table1_dataset(params, readings: dict):
    """Table 1 (``params``, SI) with the drag coefficients and groups for each reading of b in
    ln(2l/b) (``readings``: name -> Parameters), along ``b_drag``, the b each reading puts there."""
    import xarray as xr

    rs = list(readings.values())
    data = {k: _v((), v, UNITS[k], LONG_NAMES[k]) for k, v in params.to_dict().items()}
    data |= {
        "mu_par": _v(("b_drag",), [r.mu_par for r in rs], "Pa s", "tangential resistive coefficient 4 pi mu / (2 ln(2l/b) - 1)"),
        "mu_perp": _v(("b_drag",), [r.mu_perp for r in rs], "Pa s", "normal resistive coefficient 4 pi mu / ln(2l/b)"),
        "eta_par": _v(("b_drag",), [r.groups.eta_par for r in rs], "1", "tangential drag group mu_par l^4 / (B tau)"),
        "eta_perp": _v(("b_drag",), [r.groups.eta_perp for r in rs], "1", "normal drag group mu_perp l^4 / (B tau)"),
        "chi": _v((), params.chi, "1", "activity group chi = kappa_E l"),
        "force_scale": _v((), params.force_scale, "N", "force scale B / l^2"),
    }
    coords = {"b_drag": _v(("b_drag",), [r.b for r in rs], "m", "b in ln(2l/b) of the resistive coefficients")}
    return xr.Dataset(data, coords=coords, attrs={
        "title": "flutterswim reproduce: Table 1, model parameters and derived groups",
        "b_drag_readings": "; ".join(readings)})


def orbit_dataset(orb):
    """One periodic orbit's descriptors and largest Floquet multipliers (no ``orbit`` dimension)."""
    from ..orbits.dataset import orbits_dataset

    ds = orbits_dataset([orb], si=orb.units == "SI").isel(orbit=0, drop=True)
    ds.attrs = {"title": "flutterswim reproduce: periodic orbit of the representative run's parameters",
                "n_segments": orb.n_segments, "steps_per_period": orb.steps}
    return ds


def read_orbit(path) -> dict:
    """An :func:`orbit_dataset` file's scalar descriptors as numbers (its units: m, s), with
    ``leading_end`` "s=0" or "s=l" as :class:`~flutterswim.orbits.PeriodicOrbit` says it."""
    import xarray as xr

    with xr.open_dataset(path, engine="h5netcdf") as ds:
        out = {k: ds[k].item() for k in ds.data_vars if ds[k].ndim == 0}
    out["leading_end"] = "s=l" if out["leading_end"] == 1 else "s=0"
    return out


def trials_dataset(summary):
    """Fig. 3e's data from trials: per voltage the number of trials, mean and SEM of each descriptor."""
    import xarray as xr

    data = {"n_trials": _v(("voltage",), summary.n.astype("i4"), "1", "number of trials")}
    for k, (name, unit, ln) in enumerate(DESCRIPTORS):
        data[f"{name}_mean"] = _v(("voltage",), summary.mean[:, k], unit, f"{ln}, mean over the trials")
        data[f"{name}_sem"] = _v(("voltage",), summary.sem[:, k], unit,
                                 f"{ln}, standard error of the mean (NaN: a single trial)")
    coords = {"voltage": _v(("voltage",), summary.voltage_V, "V", "voltage applied")}
    return xr.Dataset(data, coords=coords, attrs={
        "title": "flutterswim reproduce: Fig. 3e, descriptors against voltage", "data_source": "trials"})


def fit_dataset(truth: dict, res):
    """Fig. 3e's stand-in: the fit of (B, tau, kappa_E) to synthetic descriptors (``res``, a
    :class:`~flutterswim.fitting.FitResult`) and the values they were made from (``truth``, SI)."""
    import xarray as xr

    from .._json import dumps

    names = list(truth)
    got = {"B": res.B, "tau": res.tau, "kappa_E": res.kappa_E}
    data = {}
    for k, s in zip(names, res.sigma_rel):
        data[f"{k}_true"] = _v((), truth[k], UNITS[k], f"{LONG_NAMES[k]}, the synthetic data's (paper preset)")
        data[f"{k}_fitted"] = _v((), got[k], UNITS[k], f"{LONG_NAMES[k]}, fitted")
        data[f"{k}_sigma_rel"] = _v((), s, "1", f"{LONG_NAMES[k]}, relative 1-sigma of the fit")
    for i, a in enumerate(names):
        for j in range(i + 1, len(names)):
            data[f"correlation_{a}_{names[j]}"] = _v((), res.correlation[i, j], "1", f"correlation of {a} and {names[j]}")
    for k, (name, unit, ln) in enumerate(DESCRIPTORS):
        for key, what in (("measured", "synthetic data"), ("sem", "standard error given"), ("model", "fitted model")):
            data[f"{name}_{key}"] = _v((), getattr(res, key)[k], unit, f"{ln}, {what}")
    data["cost"] = _v((), res.cost, "1", f"cost at the fit ({res.cost_kind})")
    data["paper_cost"] = _v((), res.paper_cost, "1", "the paper's cost C = sum (c_e / c_n - 1)^2 at the fit")
    data["model_evaluations"] = _v((), np.int32(res.n_model_evaluations), "1", "model evaluations")
    data["condition_number"] = _v((), res.card.condition_number, "1", "condition number of the sensitivities")
    return xr.Dataset(data, attrs={
        "title": "flutterswim reproduce: Fig. 3e stand-in, fit to synthetic descriptors", "data_source": "synthetic",
        "status": "converged" if res.converged else "failed", "message": res.message,
        "identifiability": res.card.describe(), "settings": dumps(res.settings, sort_keys=True)})
