"""The result of a simulation: labelled arrays, units, metadata, NetCDF round trip."""

from __future__ import annotations

import json
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from .integrators import SolverStats
from .params import UNITS, Groups, Parameters
from ._json import dumps

__all__ = ["SimulationResult", "load"]


#: the NetCDF title of a simulated run (simulate replaces only these)
RUN_TITLE = "flutterswim simulation of an active filament"


@dataclass(frozen=True)
class SimulationResult:
    """Time series of the filament.

    Arrays are in SI units when ``params`` is physical (``units == "SI"``: s, m, 1/m,
    N, N m) and in the paper's scaled units otherwise (length l, time tau, force B/l^2).
    ``dimensionless()`` always gives the scaled version.

    t (T,); s (P,) joint arc-length, P = N + 1; x, y, kappa (T, P); s_mid (N,);
    theta (T, N) at segment midpoints; r0 (T, 2) the s = 0 end; field_angle and
    field_strength (T,); A, V, M (T, P) internal forces and moment, or None.
    """

    t: np.ndarray
    s: np.ndarray
    s_mid: np.ndarray
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    kappa: np.ndarray
    r0: np.ndarray
    field_angle: np.ndarray
    field_strength: np.ndarray
    groups: Groups
    params: Parameters | None
    stats: SolverStats
    status: str
    message: str
    state_final: np.ndarray
    t_final: float
    settings: dict = field(default_factory=dict)
    A: np.ndarray | None = None
    V: np.ndarray | None = None
    M: np.ndarray | None = None
    units: str = "SI"

    # --- scales -------------------------------------------------------------
    @property
    def n_segments(self) -> int:
        return self.s_mid.size

    @property
    def length(self) -> float:
        return self.params.l if (self.params is not None and self.units == "SI") else 1.0

    @property
    def time_scale(self) -> float:
        return self.params.tau if (self.params is not None and self.units == "SI") else 1.0

    @property
    def force_scale(self) -> float:
        return self.params.force_scale if (self.params is not None and self.units == "SI") else 1.0

    @property
    def ok(self) -> bool:
        return self.status != "failed"

    def dimensionless(self) -> "SimulationResult":
        """The same run in scaled units (length l, time tau, force B/l^2)."""
        if self.units == "dimensionless":
            return self
        L, T, F = self.length, self.time_scale, self.force_scale
        opt = {k: (None if getattr(self, k) is None else getattr(self, k) / F) for k in ("A", "V")}
        return replace(
            self, t=self.t / T, s=self.s / L, s_mid=self.s_mid / L, x=self.x / L, y=self.y / L,
            kappa=self.kappa * L, r0=self.r0 / L, t_final=self.t_final / T,
            M=None if self.M is None else self.M / (F * L), units="dimensionless", **opt,
        )

    def final_state(self):
        """An :class:`~flutterswim.initial.InitialState` to continue from the last state."""
        from .initial import InitialState

        return InitialState.from_state(self.state_final, self.n_segments)

    def tip(self, end: int = -1) -> tuple[np.ndarray, np.ndarray]:
        """Coordinates (x, y) (T,) of the s = l end (``end=-1``) or the s = 0 end (``0``)."""
        return self.x[:, end], self.y[:, end]

    # --- labelled arrays and files --------------------------------------------
    def to_xarray(self):
        """A CF-style xarray.Dataset: coordinates t, s, s_mid; every variable and coordinate
        with ``units`` and ``long_name``; the parameters and groups as numeric attributes
        (``parameter_<name>`` with ``parameter_<name>_units``, ``group_<name>``) and as JSON."""
        xr = _xarray()

        from . import __version__
        from ._cf import cf_dataset

        si = self.units == "SI"
        lu = "m" if si else "l"
        tu = "s" if si else "tau"
        fu = "N" if si else "B/l^2"
        data = {
            "x": (("t", "s"), self.x, {"units": lu, "long_name": "centreline x coordinate"}),
            "y": (("t", "s"), self.y, {"units": lu, "long_name": "centreline y coordinate"}),
            "theta": (("t", "s_mid"), self.theta, {"units": "rad", "long_name": "tangent angle to the x axis"}),
            "kappa": (("t", "s"), self.kappa, {"units": f"1/{lu}", "long_name": "spontaneous curvature"}),
            "r0_x": (("t",), self.r0[:, 0], {"units": lu, "long_name": "x coordinate of the s=0 end"}),
            "r0_y": (("t",), self.r0[:, 1], {"units": lu, "long_name": "y coordinate of the s=0 end"}),
            "field_angle": (("t",), self.field_angle,
                            {"units": "rad", "long_name": "direction of the electric field to the x axis"}),
            "field_strength": (("t",), self.field_strength,
                               {"units": "1", "long_name": "field strength as a multiple of kappa_E"}),
            # the integrator's own state: always in the scaled units, whatever self.units says
            "state_final": (("state",), self.state_final, {
                "units": "1", "long_name": "final integrator state, dimensionless: r0/l (2), theta [rad] "
                "(N), kappa l (N+1)"}),
        }
        for name, unit, long in (("A", fu, "internal force, tangential component A"),
                                 ("V", fu, "internal force, normal component V"),
                                 ("M", f"{fu} {lu}", "bending moment")):
            arr = getattr(self, name)
            if arr is not None:
                data[name] = (("t", "s"), arr, {"units": unit, "long_name": long})
        ds = xr.Dataset(
            data,
            coords={
                "t": ("t", self.t, {"units": tu, "long_name": "time", "standard_name": "time"}
                      if si else {"units": tu, "long_name": "time"}),
                "s": ("s", self.s, {"units": lu, "long_name": "arc length at the joints"}),
                "s_mid": ("s_mid", self.s_mid, {"units": lu, "long_name": "arc length at segment midpoints"}),
            },
        )
        attrs = {
            "Conventions": "CF-1.10",
            "title": RUN_TITLE,
            "source": f"flutterswim {__version__}",
            "flutterswim_version": __version__,
            "units": self.units,
            "status": self.status,
            "message": self.message,
            "t_final": float(self.t_final),
            "t_final_units": tu,
            "groups": dumps(self.groups.to_dict()),
            "params": dumps(self.params.to_dict() if self.params is not None else None),
            "stats": dumps(self.stats.to_dict()),
            "settings": dumps(self.settings),
        }
        for k, v in self.groups.to_dict().items():
            attrs[f"group_{k}"] = float(v)
            attrs[f"group_{k}_units"] = "1"
        if self.params is not None:
            for k, v in self.params.to_dict().items():
                attrs[f"parameter_{k}"] = float(v)
                attrs[f"parameter_{k}_units"] = UNITS[k]
        ds.attrs.update(attrs)
        return cf_dataset(ds)

    def save(self, path: str | Path) -> Path:
        """Write the run to NetCDF (h5netcdf engine), atomically (a temporary file in the same
        folder renamed onto ``path``). Returns the path."""
        from ._paths import check_output_file, write_netcdf

        path = check_output_file(path, (".nc", ".nc4", ".h5", ".hdf5"), what="path", kind=RUN_TITLE)
        return write_netcdf(self.to_xarray(), path)

    @classmethod
    def from_xarray(cls, ds) -> "SimulationResult":
        a = ds.attrs
        params = json.loads(a["params"])
        opt = {k: (ds[k].values if k in ds else None) for k in ("A", "V", "M")}
        names = {f.name for f in fields(SolverStats)}
        stats = SolverStats(**{k: v for k, v in json.loads(a["stats"]).items() if k in names})
        r0 = ds["r0"].values if "r0" in ds else np.stack([ds["r0_x"].values, ds["r0_y"].values], axis=1)
        return cls(
            t=ds["t"].values, s=ds["s"].values, s_mid=ds["s_mid"].values, x=ds["x"].values,
            y=ds["y"].values, theta=ds["theta"].values, kappa=ds["kappa"].values,
            r0=r0, field_angle=ds["field_angle"].values,
            field_strength=ds["field_strength"].values, groups=Groups(**json.loads(a["groups"])),
            params=None if params is None else Parameters(**params), stats=stats,
            status=str(a["status"]), message=str(a["message"]), state_final=ds["state_final"].values,
            t_final=float(a["t_final"]), settings=json.loads(a["settings"]), units=str(a["units"]),
            **opt,
        )


_REQUIRED = ("t", "s", "s_mid", "x", "y", "theta", "kappa", "field_angle", "field_strength", "state_final")


def _xarray():
    """xarray, or a ModuleNotFoundError that says which extra brings it (with h5netcdf)."""
    try:
        import xarray
    except ModuleNotFoundError as exc:
        raise ModuleNotFoundError("runs are saved and loaded as NetCDF through xarray and h5netcdf: "
                                  "pip install 'flutterswim[io]'", name=exc.name) from None
    return xarray


def load(path: str | Path) -> SimulationResult:
    """Read a run written by :meth:`SimulationResult.save`. A missing, empty, truncated or
    foreign file raises ParameterError naming the file and what is wrong."""
    xr = _xarray()

    from ._validate import ParameterError

    p = Path(path)
    if not p.exists():
        raise ParameterError(f"run={str(p)!r} does not exist")
    if p.is_dir():
        raise ParameterError(f"run={str(p)!r} is a directory; a NetCDF file written by flutterswim is required")
    if p.stat().st_size == 0:
        raise ParameterError(f"run={str(p)!r} is empty; a NetCDF file written by flutterswim is required")
    try:
        with open(p, "rb") as f:
            head = f.read(8)
    except OSError as exc:
        raise ParameterError(f"run={str(p)!r} cannot be read: {exc.strerror}") from None
    if head != b"\x89HDF\r\n\x1a\n":
        raise ParameterError(f"run={str(p)!r} is not a NetCDF-4 (HDF5) file; a run saved by flutterswim "
                             "(flutterswim simulate, SimulationResult.save) is required")
    try:
        with xr.open_dataset(p, engine="h5netcdf") as ds:
            missing = [k for k in _REQUIRED if k not in ds.variables]
            if "r0" not in ds.variables and not {"r0_x", "r0_y"} <= set(ds.variables):
                missing.append("r0_x/r0_y")
            missing += [k for k in ("params", "groups", "stats", "settings", "status", "t_final", "units")
                        if k not in ds.attrs]
            if missing:
                raise ParameterError(f"run={str(p)!r} is a NetCDF file but not a flutterswim run (missing "
                                     f"{', '.join(missing[:6])})")
            return SimulationResult.from_xarray(ds.load())
    except ParameterError:
        raise
    except Exception as exc:  # noqa: BLE001 - truncated or corrupt files fail in many ways
        raise ParameterError(f"run={str(p)!r} cannot be read as a flutterswim run (truncated or corrupt "
                             f"file?): {type(exc).__name__}: {' '.join(str(exc).split())[:200]}") from None


def concatenate(parts: "list[SimulationResult]") -> SimulationResult:
    """Join consecutive runs (each continuing from the previous final state) into one.

    The first frame of each later part repeats the last frame of the one before and is
    dropped. Solver statistics are summed."""
    if not parts:
        raise ValueError("concatenate needs at least one result")
    first, last = parts[0], parts[-1]
    arrays = {}
    for name in ("t", "x", "y", "theta", "kappa", "r0", "field_angle", "field_strength", "A", "V", "M"):
        if getattr(first, name) is None:
            continue
        chunks = [getattr(first, name)] + [getattr(p, name)[1:] for p in parts[1:]]
        arrays[name] = np.concatenate(chunks, axis=0)
    st = [p.stats for p in parts]
    stats = SolverStats(
        first.stats.method, first.stats.order, *(sum(getattr(s, k) for s in st)
        for k in ("n_steps", "n_rejected", "n_rhs", "n_jac", "n_lu")), sum(s.wall_time for s in st),
    )
    settings = {**first.settings, "t_end": last.settings.get("t_end"), "parts": len(parts)}
    fields = [p.settings.get("field") for p in parts]
    if any(f != fields[0] for f in fields):
        # (a steered run's settings had said "direction=constant(0)", its first part's, while its
        # field turned by 400 degrees)
        settings["field"] = (f"changes between the {len(parts)} joined runs (field_angle and field_strength hold it "
                             f"frame by frame); the first: {fields[0]}; the last: {fields[-1]}")
    return replace(first, **arrays, stats=stats, status=last.status, message=last.message,
                   state_final=last.state_final, t_final=last.t_final, settings=settings)
