"""CF units of quantities in the paper's scaled units (length l, time tau, force B/l^2).

CF units follow udunits, which knows neither tau nor B and reads "l" as the litre. A quantity
in the scaled units is a pure number, so a written file gives it ``units = "1"``, keeps its scale
in ``scaled_units`` ("tau", "1/tau", "l", "B/l^2 l" ...) and says it in the long name. A global
attribute ``<name>_units`` with a scaled unit becomes ``<name>_units = "1"`` and
``<name>_scaled_units``.
"""

from __future__ import annotations

import re

#: The scales' symbols as whole words of a unit string ("l tau-1", "1e-3 l/tau", "B/l^2").
_SCALE = re.compile(r"(?<![A-Za-z_])(tau|l|B)(?![A-Za-z_])")


def is_scaled(unit) -> bool:
    """True for a unit string written in the paper's scales."""
    return isinstance(unit, str) and _SCALE.search(unit) is not None


def cf_attrs(attrs: dict) -> dict:
    """A copy of ``attrs`` with a scaled ``units`` (and scaled ``<name>_units``) made CF."""
    out = dict(attrs)
    unit = attrs.get("units")
    if is_scaled(unit):
        out["units"] = "1"
        out["scaled_units"] = unit
        if "long_name" in attrs:
            out["long_name"] = f"{attrs['long_name']} (in units of {unit})"
    for key, value in attrs.items():
        if key.endswith("_units") and key != "scaled_units" and not key.endswith("_scaled_units") \
                and is_scaled(value):
            out[key] = "1"
            out[f"{key[:-len('_units')]}_scaled_units"] = value
    return out


def cf_dataset(ds):
    """``ds`` with :func:`cf_attrs` applied to every variable, coordinate and the global
    attributes (in place; returns ``ds``). Every file also says which convention and which
    version of flutterswim wrote it (``Conventions``, ``flutterswim_version``), unless it does."""
    from . import __version__
    for var in ds.variables.values():
        var.attrs = cf_attrs(var.attrs)
    ds.attrs = cf_attrs(ds.attrs)
    ds.attrs.setdefault("Conventions", "CF-1.10")
    ds.attrs.setdefault("flutterswim_version", __version__)
    for name in ds.coords:  # coordinates hold no missing values (CF): no _FillValue written for them
        if ds[name].dtype.kind == "f":
            ds[name].encoding["_FillValue"] = None
    return ds
