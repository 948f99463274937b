"""Sweep definition: swept axes, base parameters, per-point settings, and grid parsing.

An axis is written ``name=lo:hi:n`` (n >= 2 equally spaced values, ends included),
``name=v1,v2,...`` (a list) or ``name=v`` (one value). Names: the physical parameters
(``l, a, b, B, tau, kappa_E, mu``), the groups (``eta_par, eta_perp, chi``) and
``kappa_E_ratio`` (kappa_E over the base kappa_E, e.g. the paper's kappa_E/kappa_E_fit).
Several axes form a grid (outer product, ``mode="grid"``) or are zipped point by point
(``mode="list"``, equal lengths).
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from dataclasses import asdict, dataclass, field
from typing import Any, Iterable, Mapping

import numpy as np

from .._validate import ParameterError, finite, positive, positive_int, tolerance, tolerances_reachable
from .._validate import n_segments as segments_checked
from ..defaults import ATOL, MAX_SWEEP_POINTS, N_CYCLES, RTOL, SWEEP_FRAMES_PER_TAU, SWEEP_N_SEGMENTS
from ..params import Groups, Parameters, preset

__all__ = ["Axis", "PointSettings", "SweepSpec", "parse_axis", "PHYSICAL", "GROUPS", "AXIS_NAMES"]

PHYSICAL = ("l", "a", "b", "B", "tau", "kappa_E", "mu")
GROUPS = ("eta_par", "eta_perp", "chi")
AXIS_NAMES = PHYSICAL + GROUPS + ("kappa_E_ratio",)


@dataclass(frozen=True)
class Axis:
    name: str
    values: tuple[float, ...]

    def __post_init__(self) -> None:
        if self.name not in AXIS_NAMES:
            raise ParameterError(f"sweep axis {self.name!r} is unknown; choose one of {list(AXIS_NAMES)}")
        vals = tuple(float(v) for v in self.values)
        if not vals:
            raise ParameterError(f"sweep axis {self.name!r} has no values; at least one is required")
        bad = [v for v in vals if not math.isfinite(v)]
        if bad:
            raise ParameterError(f"sweep axis {self.name!r} has non-finite values {bad}; finite values are required")
        object.__setattr__(self, "values", vals)


def parse_axis(text: str) -> Axis:
    """``"kappa_E_ratio=0:2:101"`` -> Axis (see module doc for the forms)."""
    if "=" not in text:
        raise ParameterError(
            f"sweep axis {text!r} has no '='; write name=lo:hi:n, name=v1,v2,... or name=v"
        )
    name, _, rhs = text.partition("=")
    name, rhs = name.strip(), rhs.strip()
    too_many = 0
    try:
        if ":" in rhs:
            parts = rhs.split(":")
            if len(parts) != 3:
                raise ValueError
            lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
            if not (math.isfinite(lo) and math.isfinite(hi)):  # before linspace (which warns)
                raise ParameterError(f"sweep axis {text!r} has a non-finite end; a range lo:hi:n needs "
                                     "finite lo and hi")
            if n < 2:  # lo:hi:1 would silently drop hi
                raise ParameterError(f"sweep axis {text!r} has n={n}; a range lo:hi:n needs n >= 2 "
                                     f"(write {name}={parts[0]} for one value)")
            if n > MAX_SWEEP_POINTS:  # before anything is allocated
                too_many = n
                raise ValueError
            vals = np.linspace(lo, hi, n)
            # round to suppress linspace noise so the definition is reproducible as text
            vals = [float(f"{v:.12g}") for v in vals]
        else:
            parts = rhs.split(",")
            if len(parts) > 1 and not parts[-1].strip():
                parts = parts[:-1]  # (a trailing comma: "chi=60,70,")
            if any(not v.strip() for v in parts):  # "1,,2" ran 2 points without a word
                raise ParameterError(f"sweep axis {text!r} has an empty value; write name=v1,v2,...")
            vals = [float(v) for v in parts]
    except ParameterError:
        raise
    except ValueError:
        if too_many:
            raise ParameterError(f"sweep axis {text!r} has {too_many} values; at most {MAX_SWEEP_POINTS} points "
                                 "are allowed in a sweep (flutterswim.defaults.MAX_SWEEP_POINTS)") from None
        raise ParameterError(
            f"sweep axis {text!r} is not understood; write name=lo:hi:n (n >= 2 integer), "
            "name=v1,v2,... or name=v"
        ) from None
    return Axis(name, tuple(vals))


@dataclass(frozen=True)
class PointSettings:
    """How one point is run: simulate in chunks of ``chunk`` tau up to ``t_cap`` tau, stop at a
    limit cycle once ``n_cycles`` cycles on it are available (they are averaged), or when the
    straight state has damped out. ``straight_tol``: oscillation half-range of the shape angle
    [rad] under which a decaying state is called straight; ``swim_tol``: above which cycles
    are analysed; ``rate_tol``: growth rate of the oscillation amplitude [1/tau] beyond which
    it counts as growing or decaying (``unstable``: limit cycle, growing, or a large
    non-decaying oscillation). A swimming point whose amplitude stays within ``rate_tol``
    over ``saturated_chunks`` chunks (at least ``n_cycles`` cycles) but never meets the
    limit-cycle test stops early and is flagged ``saturated`` (stationary, not periodic)."""

    n_cycles: int = N_CYCLES
    t_cap: float = 60.0
    chunk: float = 5.0
    n_segments: int = SWEEP_N_SEGMENTS
    rtol: float = RTOL
    atol: float = ATOL
    frames_per_tau: int = SWEEP_FRAMES_PER_TAU
    straight_tol: float = 1e-2
    swim_tol: float = 0.05
    damped_tol: float = 1e-6
    rate_tol: float = 2e-3
    saturated_chunks: int = 3
    initial_angle_deg: float = 0.01

    def __post_init__(self) -> None:
        # the checks of flutterswim.simulate, up front (not at every point)
        for k in ("t_cap", "chunk", "rtol", "atol", "straight_tol", "swim_tol", "damped_tol", "rate_tol"):
            object.__setattr__(self, k, (tolerance if k in ("rtol", "atol") else positive)(k, getattr(self, k)))
        tolerances_reachable(self.rtol, self.atol)  # (every point failed, and the store blocked a rerun)
        for k in ("n_cycles", "n_segments", "frames_per_tau", "saturated_chunks"):
            v = getattr(self, k)
            if isinstance(v, float) and v.is_integer():
                v = int(v)
            object.__setattr__(self, k, segments_checked(v) if k == "n_segments" else positive_int(k, v))
        object.__setattr__(self, "initial_angle_deg", finite("initial_angle_deg", self.initial_angle_deg))
        if not -90.0 <= self.initial_angle_deg <= 90.0:
            raise ParameterError(f"initial_angle_deg={self.initial_angle_deg!r} must be in [-90, 90]")

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _base_dict(base: Parameters | Groups) -> dict[str, Any]:
    if isinstance(base, Parameters):
        return {"kind": "Parameters", **base.to_dict()}
    if isinstance(base, Groups):
        return {"kind": "Groups", **base.to_dict()}
    raise ParameterError(f"base={base!r} must be flutterswim.Parameters or flutterswim.Groups")


def base_from_dict(d: Mapping[str, Any]) -> Parameters | Groups:
    d = dict(d)
    kind = d.pop("kind")
    return Parameters(**d) if kind == "Parameters" else Groups(**d)


def point_params(base: Parameters | Groups, values: Mapping[str, float]) -> Parameters | Groups:
    """The parameter set of one point: ``base`` with the swept ``values`` applied.

    With a physical base, ``chi`` sets kappa_E = chi / l; ``eta_par``/``eta_perp`` turn the
    point into dimensionless :class:`Groups` (times then in tau). ``kappa_E_ratio`` multiplies
    the base kappa_E (or chi)."""
    phys = {k: v for k, v in values.items() if k in PHYSICAL}
    grp = {k: v for k, v in values.items() if k in GROUPS}
    ratio = values.get("kappa_E_ratio")
    if isinstance(base, Groups):
        if phys:
            raise ParameterError(
                f"axes {sorted(phys)} are physical but the base is dimensionless Groups; sweep "
                "eta_par, eta_perp, chi or kappa_E_ratio, or use a physical base"
            )
        g = base.replace(**grp) if grp else base
        return g.replace(chi=base.chi * ratio) if ratio is not None else g
    p = base.replace(**phys) if phys else base
    if ratio is not None:
        p = p.replace(kappa_E=base.kappa_E * ratio)
    if "chi" in grp:
        p = p.replace(kappa_E=grp.pop("chi") / p.l)
    if grp:
        return p.groups.replace(**grp)
    return p


@dataclass(frozen=True)
class SweepSpec:
    """A sweep: base parameters, axes, ``mode`` ("grid" or "list"), per-point settings, and
    ``continuation`` (each point starts from the previous one's final state, up then down;
    1-d sweeps only)."""

    base: Parameters | Groups
    axes: tuple[Axis, ...]
    mode: str = "grid"
    settings: PointSettings = field(default_factory=PointSettings)
    continuation: bool = False
    preset_name: str | None = None
    #: a continuation store made before stop 46 with an axis not in increasing order: its "up"
    #: branch ran in the order given (read and resumed so; new sweeps run up in increasing value)
    legacy_up_order: bool = False

    def __post_init__(self) -> None:
        _base_dict(self.base)
        axes = tuple(self.axes)
        if not axes:
            raise ParameterError("a sweep needs at least one axis (e.g. kappa_E_ratio=0:2:101)")
        names = [a.name for a in axes]
        if len(set(names)) != len(names):
            raise ParameterError(f"sweep axes {names} repeat a name; each parameter may be swept once")
        if "kappa_E_ratio" in names and ("kappa_E" in names or "chi" in names):
            raise ParameterError("kappa_E_ratio cannot be swept together with kappa_E or chi")
        if self.mode not in ("grid", "list"):
            raise ParameterError(f"mode={self.mode!r} is unknown; choose 'grid' or 'list'")
        if self.mode == "grid":
            # a grid's axis is a coordinate of the store: a repeated value would label two rows
            # alike (xarray's sel then returns both)
            for a in axes:
                seen = sorted({v for v in a.values if a.values.count(v) > 1})
                if seen:
                    raise ParameterError(f"sweep axis {a.name!r} repeats the values {seen}; a grid's values must "
                                         "differ (mode='list' pairs values and may repeat them)")
        if self.mode == "list" and len({len(a.values) for a in axes}) > 1:
            raise ParameterError(
                f"mode='list' zips the axes, which need equal lengths; got "
                f"{ {a.name: len(a.values) for a in axes} }"
            )
        if self.continuation and len(axes) != 1:
            raise ParameterError("continuation needs exactly one swept axis")
        n = math.prod(len(a.values) for a in axes) if self.mode == "grid" else len(axes[0].values)
        n *= 2 if self.continuation else 1
        if n > MAX_SWEEP_POINTS:
            raise ParameterError(f"the sweep has {n} points; at most {MAX_SWEEP_POINTS} are allowed "
                                 "(flutterswim.defaults.MAX_SWEEP_POINTS); split it into several sweeps")
        object.__setattr__(self, "axes", axes)
        _units_warnings(self.base, axes)
        # every point's parameters, with the checks a point makes, before any store is created
        for i in range(self.n_values):
            values = self.values(i)
            try:
                point_params(self.base, values)
            except ParameterError as exc:
                raise ParameterError(f"sweep point {values}: {exc}") from None

    @classmethod
    def build(cls, axes: Iterable[str | Axis] | Mapping[str, Iterable[float]], base: Any = "paper",
              **kw: Any) -> "SweepSpec":
        """Axes as strings (``"kappa_E_ratio=0:2:101"``), Axis objects or {name: values}; base
        as Parameters, Groups or a preset name."""
        preset_name = None
        if isinstance(base, str):
            preset_name, base = base, preset(base)
        if isinstance(axes, Mapping):
            ax = tuple(Axis(k, tuple(np.atleast_1d(np.asarray(v, float)))) for k, v in axes.items())
        else:
            ax = tuple(a if isinstance(a, Axis) else parse_axis(a) for a in axes)
        settings = kw.pop("settings", None)
        if settings is None:
            settings = PointSettings()
        elif isinstance(settings, Mapping):
            known = set(PointSettings.__dataclass_fields__)
            unknown = sorted(set(settings) - known)
            if unknown:
                raise ParameterError(f"sweep settings {unknown} are unknown; choose from {sorted(known)}")
            settings = PointSettings(**settings)
        return cls(base=base, axes=ax, settings=settings, preset_name=preset_name, **kw)

    # ------------------------------------------------------------------ geometry
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        if self.mode == "list":
            return (len(self.axes[0].values),)
        return tuple(len(a.values) for a in self.axes)

    @property
    def n_values(self) -> int:
        return int(np.prod(self.shape))

    @property
    def branches(self) -> tuple[str, ...]:
        return ("up", "down") if self.continuation else ("single",)

    @property
    def n_points(self) -> int:
        return self.n_values * len(self.branches)

    def values(self, i: int) -> dict[str, float]:
        """Swept values of flat value index i (row-major over the grid)."""
        if self.mode == "list":
            return {a.name: a.values[i] for a in self.axes}
        idx = np.unravel_index(i, self.shape)
        return {a.name: a.values[int(j)] for a, j in zip(self.axes, idx)}

    def point(self, k: int) -> tuple[str, int, dict[str, float]]:
        """Point k of the store -> (branch, value index, swept values). With continuation,
        points 0..n-1 go up the axis (in increasing value, whatever the order given) and
        n..2n-1 come back down (a descending axis had run "up" from its largest value: the
        branches' labels, "increasing" and "decreasing", read backwards)."""
        n = self.n_values
        if not self.continuation:
            return "single", k, self.values(k)
        order = (np.arange(n) if self.legacy_up_order else
                 np.argsort(np.asarray(self.axes[0].values, float), kind="stable"))
        if k < n:
            i = int(order[k])
            return "up", i, self.values(i)
        i = int(order[2 * n - 1 - k])
        return "down", i, self.values(i)

    def params(self, k: int) -> Parameters | Groups:
        return point_params(self.base, self.point(k)[2])

    # ------------------------------------------------------------------ identity
    def to_dict(self) -> dict[str, Any]:
        d = {
            "base": _base_dict(self.base),
            "axes": [{"name": a.name, "values": list(a.values)} for a in self.axes],
            "mode": self.mode,
            "settings": self.settings.to_dict(),
            "continuation": bool(self.continuation),
        }
        if self.continuation and not self.legacy_up_order and np.any(np.diff(np.asarray(self.axes[0].values, float)) < 0):
            # (an axis not given in increasing order: "up" runs in increasing value since stop 46,
            # where a store made before ran it in the order given; this key makes such a store a
            # different sweep, refused on resume, not mis-assigned)
            d["up"] = "increasing"
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "SweepSpec":
        return cls(
            base=base_from_dict(d["base"]),
            axes=tuple(Axis(a["name"], tuple(a["values"])) for a in d["axes"]),
            mode=d["mode"], settings=PointSettings(**d["settings"]),
            continuation=bool(d["continuation"]),
            legacy_up_order=bool(d["continuation"]) and "up" not in d
            and bool(np.any(np.diff(np.asarray(d["axes"][0]["values"], float)) < 0)),
        )

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))

    @property
    def fingerprint(self) -> str:
        return hashlib.sha256(self.to_json().encode()).hexdigest()[:16]

    def diff(self, other: "SweepSpec | Mapping[str, Any]") -> list[str]:
        """Human-readable differences between this definition and ``other``."""
        a = _flatten(self.to_dict())
        b = _flatten(other.to_dict() if isinstance(other, SweepSpec) else dict(other))
        out = []
        for k in sorted(set(a) | set(b)):
            if a.get(k) != b.get(k):
                va, vb = a.get(k, "<absent>"), b.get(k, "<absent>")
                sa, sb = _short(va), _short(vb)
                out.append(f"{k}: stored {sb}, requested {sa}")
        return out


#: SI units of the physical parameters a sweep may take, and the other unit a value typed a
#: thousand (B: a million) times off is likely in (tau=375 for 0.375 s swept a straight state)
_SI_UNITS = {"l": ("m", "mm", 1e3), "a": ("m", "mm", 1e3), "b": ("m", "mm", 1e3), "tau": ("s", "ms", 1e3),
             "mu": ("Pa s", "mPa s", 1e3), "B": ("N m^2", "N mm^2", 1e6), "kappa_E": ("1/m", "1/mm", 1e-3)}


def _units_warnings(base: Any, axes: tuple) -> None:
    """A warning for a swept physical parameter whose values all lie within a factor 3 of a
    thousand (B: a million) times the base's: values in mm, ms or mPa s typed for SI (a sweep
    spanning decades, water to glycerol, is left alone)."""
    if not isinstance(base, Parameters):
        return
    for a in axes:
        if a.name not in _SI_UNITS:
            continue
        unit, other, factor = _SI_UNITS[a.name]
        ref = abs(float(getattr(base, a.name)))
        vals = [v for v in a.values if v != 0]
        odd = [v for v in vals if ref > 0 and abs(math.log10(abs(v) / ref) - math.log10(factor)) < 0.48]
        if odd and len(odd) == len(vals):
            warnings.warn(f"sweep axis {a.name}: {odd[0]:g} {unit} is about {factor:g} times the base's {ref:g} {unit}; "
                          f"values are in SI ({unit}): was it typed in {other}?", UserWarning, stacklevel=4)


def _flatten(d: Any, prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    if isinstance(d, Mapping):
        for k, v in d.items():
            out.update(_flatten(v, f"{prefix}{k}."))
    elif isinstance(d, list) and d and isinstance(d[0], Mapping):
        for i, v in enumerate(d):
            out.update(_flatten(v, f"{prefix}{i}."))
    else:
        out[prefix[:-1]] = d
    return out


def _short(v: Any) -> str:
    if isinstance(v, list) and len(v) > 6:
        return f"[{v[0]!r}, {v[1]!r}, ..., {v[-1]!r}] ({len(v)} values)"
    return repr(v)
