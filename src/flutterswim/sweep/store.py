"""Durable point-by-point sweep store: an ordinary xarray Zarr dataset.

``xarray.open_zarr(path)`` reads it without flutterswim: dimensions are the swept
parameters (grid), or ``point`` (list mode), plus ``branch`` ("up", "down") for
continuation sweeps; every variable and coordinate has ``units`` and ``long_name``; failure
reasons are strings (``reason``); the definition is in the attributes (``sweep_spec`` JSON,
``fingerprint``, ``variables``). Per point: the point function's variables, ``failed``,
``reason``, ``wall_time_s``, ``state`` (final state, for continuation) and ``done``.

Durability:

- the store is built under a temporary name next to ``path`` and renamed into place, so a
  store at ``path`` always holds its definition; it carries the marker file
  :data:`flutterswim._paths.MARKER`, and nothing without that marker is ever replaced;
- only the parent process writes, under an exclusive lock (``.<name>.lock`` next to the
  store; the file is opened close-on-exec and workers are separate programs, so only the
  parent holds it; the file is removed when the run ends, if this run created it);
- each point is written as its own region, ``done`` last (Zarr writes each chunk file
  atomically): a kill between the value writes and ``done`` leaves the point undone, and
  it is recomputed on resume;
- an own store that is incomplete or holds another definition is never recomputed
  silently: :class:`SweepStoreError` / :class:`SweepDefinitionError` say what is wrong.
"""

from __future__ import annotations

import json
import math
import os
import re
import warnings
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from .._cf import cf_attrs
from .._paths import MARKER, check_store_path, has_marker, remove_own_store, set_aside_own_store, write_marker
from .._validate import ParameterError
from ..params import LONG_NAMES, UNITS
from .spec import SweepSpec

__all__ = ["SweepStore", "SweepDefinitionError", "SweepStoreError", "SweepLockedError", "FORMAT", "variable_attrs",
           "store_dims"]

FORMAT = "flutterswim-sweep/2"
#: Per-point bookkeeping variables (besides the point function's own).
BOOKKEEPING = ("done", "failed", "reason", "wall_time_s", "state")
#: Flags of the stroke (its periodic orbit), with their long names.
STROKE_FLAGS = {"stable": "the stroke is a stable periodic orbit",
                "self_intersecting": "the stroke's shapes cross themselves"}
FLAGS = ("straight", "unstable", "swimming", "limit_cycle_reached", "saturated", "capped", "limit_cycle",
         "bent_equilibrium", "not_periodic", "reached_limit_cycle", "stable",
         "self_intersecting", "towards_field", "reciprocal")


# a file zarr writes under a temporary name and renames into place ("0.<uuid hex>.partial");
# a kill between the two leaves it behind
_PARTIAL = re.compile(r"^[^/]+\.[0-9a-f]{32}\.partial$")
_CHUNK = re.compile(r"^[0-9]+$")


def _store_arrays(path: Path) -> set[str] | None:
    """The arrays the store's root metadata lists (its consolidated listing), None if unreadable."""
    try:
        meta = json.loads((path / "zarr.json").read_text())
        names = meta["consolidated_metadata"]["metadata"]
        return {k for k in names if "/" not in k}
    except (OSError, ValueError, KeyError, TypeError):
        return None


def foreign_entries(path: str | os.PathLike) -> list[str]:
    """Entries inside one of our stores that the store itself does not write (relative paths,
    sorted): a sweep store holds its root ``zarr.json``, the marker, and one folder per array
    (those the root metadata lists; if unreadable, folders holding a ``zarr.json``), each with
    its ``zarr.json`` and a ``c/`` tree of chunk files named by their integer indices; zarr's
    temporary ``*.<hex>.partial`` files are its own too. Anything else, or any symbolic link,
    is the user's (notes, figures put into the folder) and is never deleted."""
    root = Path(os.fspath(path))
    arrays = _store_arrays(root)
    foreign: list[str] = []

    def own_file(e: os.DirEntry, names: tuple[str, ...]) -> bool:
        return e.is_file(follow_symlinks=False) and (e.name in names or _PARTIAL.match(e.name) is not None)

    def chunks(d: Path) -> None:
        for e in os.scandir(d):
            if e.is_symlink() or not (_CHUNK.match(e.name) or (e.is_file() and _PARTIAL.match(e.name))):
                foreign.append(os.path.relpath(e.path, root))
            elif e.is_dir(follow_symlinks=False):
                chunks(Path(e.path))

    for e in os.scandir(root):
        if own_file(e, ("zarr.json", MARKER)):
            continue
        is_array = e.is_dir(follow_symlinks=False) and (
            e.name in arrays if arrays is not None else (Path(e.path) / "zarr.json").is_file())
        if not is_array:
            foreign.append(e.name)
            continue
        for a in os.scandir(e.path):
            if own_file(a, ("zarr.json",)):
                continue
            if a.name == "c" and a.is_dir(follow_symlinks=False):
                chunks(Path(a.path))
            else:
                foreign.append(os.path.relpath(a.path, root))
    return sorted(foreign)


def _refuse_foreign(path: Path) -> None:
    foreign = foreign_entries(path)
    if foreign:
        shown = ", ".join(repr(f) for f in foreign[:3]) + (f" and {len(foreign) - 3} more" if len(foreign) > 3 else "")
        raise ParameterError(f"out={str(path)!r} is a flutterswim sweep store that also holds files it did not "
                             f"write ({shown}); --overwrite never deletes them: move them out of the store, or give "
                             "a new store name")


class SweepDefinitionError(ParameterError):
    """The store holds a different sweep than the one requested."""


class SweepStoreError(ParameterError):
    """The path holds an own store that is incomplete or inconsistent."""


class SweepLockedError(SweepDefinitionError):
    """Another live sweep process holds the store's lock."""


def variable_attrs(name: str, time_unit: str) -> dict[str, str]:
    """CF-style ``units`` and ``long_name`` of a sweep variable (by name convention); a
    quantity in tau or l gets units "1" and its scale in ``scaled_units`` (:mod:`flutterswim._cf`)."""
    return cf_attrs(_variable_attrs(name, time_unit))


def _variable_attrs(name: str, time_unit: str) -> dict[str, str]:
    tu = time_unit
    phys = tu == "s"
    words = name.replace("_", " ")
    if name in STROKE_FLAGS:  # (a flag is 0/1: a point without a stroke stores 0)
        return {"units": "1", "long_name": f"{STROKE_FLAGS[name]} (1 yes, 0 no or no stroke)"}
    if name in FLAGS:
        return {"units": "1", "long_name": f"{words} (1 yes, 0 no)"}
    table = {
        "t_simulated": ("tau", "simulated time"),
        "time_to_limit_cycle_s": (tu, "time to the limit cycle: first time every later cycle's period and "
                                      "end-angle peak-to-peak are within 1% of the periodic orbit's"),
        "growth_rate_linear_per_s": ("1/s" if phys else "1/tau", "growth rate of the straight state, linear "
                                     "theory of the discrete model"),
        "angular_frequency_linear_per_s": ("rad/s" if phys else "rad/tau", "angular frequency of the leading "
                                           "mode of the straight state, linear theory"),
        "growth_rate_measured_per_s": ("1/s" if phys else "1/tau", "growth rate of the oscillation envelope "
                                       "measured from the run (small-amplitude part)"),
        "lateral_leading_mm": ("mm" if phys else "1e-3 l", "lateral peak-to-peak excursion of the leading end"),
        "lateral_trailing_mm": ("mm" if phys else "1e-3 l", "lateral peak-to-peak excursion of the trailing end"),
        # speeds: length per time ("_s" here is "per second", not a time)
        "speed_mm_s": ("mm/s" if phys else "1e-3 l/tau", "swimming speed"),
        "speed_bl_s": ("1/s" if phys else "1/tau", "swimming speed in body lengths per unit time"),
        "max_multiplier": ("1", "largest modulus of the non-trivial Floquet multipliers"),
        "oscillation_amplitude": ("rad", "half-range of the body-frame tangent angle over the last chunk"),
        "amplitude_growth_rate": ("1/tau", "growth rate of the oscillation amplitude over the last chunk"),
        "n_chunks": ("1", "number of simulated chunks"),
        "cycle_amplitude": ("1", "section amplitude of the stroke in body lengths"),
        "cycle_amplitude_std": ("1", "cycle-to-cycle std of the section amplitude in body lengths"),
        "n_cycles_used": ("1", "cycles averaged"), "n_cycles_detected": ("1", "cycles detected"),
        "nonreciprocity": ("1", "signed stroke area in the plane of the first two shape modes"),
        "nonreciprocity_std": ("1", "cycle-to-cycle std of the nonreciprocity"),
        "self_intersection_fraction": ("1", "fraction of frames in which the filament crosses itself"),
        "done": ("1", "point computed and stored (1 yes, 0 no)"),
        "failed": ("1", "point failed (1 yes, 0 no)"),
        "reason": ("1", "why the point ended as it did: its failure (see failed), or what it settled into"),
        "wall_time_s": ("s", "wall-clock time of the point"),
        "state": ("1", "final integrator state, dimensionless (r0/l, theta, kappa l), for continuation"),
    }
    if name in table:
        u, ln = table[name]
        return {"units": u, "long_name": ln}
    if name.endswith("_mm"):
        return {"units": "mm" if phys else "1e-3 l", "long_name": words[:-3]}
    if name.endswith("_bl"):
        return {"units": "1", "long_name": f"{words[:-3]} in body lengths"}
    if name.endswith("_per_s"):
        return {"units": "1/s" if phys else "1/tau", "long_name": words[:-6]}
    if name.endswith("_hz"):
        return {"units": "Hz" if phys else "1/tau", "long_name": words[:-3]}
    if name.endswith("_deg"):
        return {"units": "degree", "long_name": words[:-4]}
    if name.endswith("_s"):
        return {"units": tu, "long_name": words[:-2]}
    return {"units": "1", "long_name": words}


def store_dims(spec: SweepSpec) -> tuple[list[str], tuple[int, ...], dict[str, Any]]:
    """(dims, shape, coords) of the dataset of ``spec``."""
    if spec.mode == "grid":
        dims = list(spec.names)
        shape = spec.shape
        coords: dict[str, Any] = {a.name: (a.name, np.array(a.values, float),
                                           {"units": UNITS[a.name], "long_name": LONG_NAMES[a.name]})
                                  for a in spec.axes}
    else:
        dims, shape = ["point"], (spec.n_values,)
        coords = {a.name: ("point", np.array(a.values, float),
                           {"units": UNITS[a.name], "long_name": LONG_NAMES[a.name]}) for a in spec.axes}
        coords["point"] = ("point", np.arange(spec.n_values), {"units": "1", "long_name": "point number"})
    if spec.continuation:
        dims = ["branch"] + dims
        shape = (2,) + tuple(shape)
        coords["branch"] = ("branch", np.array(["up", "down"], dtype=object),  # variable-length strings
                            {"units": "1", "long_name": "continuation branch (up: increasing, down: decreasing)"})
    return dims, tuple(shape), coords


def _time_unit(spec: SweepSpec) -> str:
    from ..params import Parameters

    return "s" if isinstance(spec.base, Parameters) else "tau"


_LOCK_SIGNATURE = "flutterswim sweep lock\n"


def _acquire(path: Path):
    """Exclusive advisory lock next to the store: one writer at a time (:func:`.._lock.acquire`)."""
    from .._lock import acquire

    return acquire(path, kind="sweep", noun="store", error=SweepLockedError,
                   then="rerun the same command to resume")


def _settle_remnants(path: Path) -> None:
    """Stores that ``overwrite`` set aside (``.<name>.replaced-<pid>``) and a killed run left (under
    the lock: no run is using them): put back where no store is, else deleted (the store there
    replaced it, as asked)."""
    for old in sorted(path.parent.glob(f".{path.name}.replaced-*")):
        if not (old.is_dir() and has_marker(old)):
            continue
        if not path.exists():
            os.replace(old, path)
        else:
            remove_own_store(old, kind="sweep")


def code_identity(fn) -> dict:
    """What computes a sweep's points: the flutterswim version, the point function's name and a
    hash of its source (None where it has none to read), and a hash of the package's sources."""
    import functools
    import hashlib
    import inspect

    from .. import __version__

    # a partial or a callable object: its function or class, with its arguments or state (two
    # partials of one function, or two objects of one class, had passed as the same function)
    target, state = fn, ""
    if isinstance(fn, functools.partial):
        target, state = fn.func, repr((fn.args, sorted(fn.keywords.items())))
    elif callable(fn) and not (inspect.isfunction(fn) or inspect.ismethod(fn) or inspect.isbuiltin(fn)):
        target, state = type(fn), repr(sorted(vars(fn).items())) if hasattr(fn, "__dict__") else repr(fn)
    try:
        src = None if " at 0x" in state else hashlib.sha256(
            (inspect.getsource(target) + state).encode()).hexdigest()[:16]  # (an address differs each run)
    except (OSError, TypeError):
        src = None
    h = hashlib.sha256()
    root = Path(__file__).resolve().parents[1]
    for f in sorted(root.rglob("*.py")):
        h.update(str(f.relative_to(root)).encode())
        h.update(f.read_bytes())
    return {"flutterswim": __version__,
            "point_fn": f"{getattr(target, '__module__', '?')}:{getattr(target, '__qualname__', type(target).__name__)}",
            "point_fn_source": src, "package_source": h.hexdigest()[:16]}


def _same_code(path: Path, attrs: dict, code: dict | None) -> None:
    """Refuse to resume a store whose points were computed by another version of flutterswim or
    another point function (a resume had mixed both: the periods jumped 5 % at the point where
    the new code took over, without a word); warn where only the package's sources differ (an
    edit that may not touch the points). A store made before stop 47 records no code."""
    if code is None or "code" not in attrs:
        return
    try:
        stored = json.loads(attrs["code"])
    except (TypeError, ValueError):
        return
    what = {"flutterswim": "flutterswim version", "point_fn": "point function",
            "point_fn_source": "point function's source (hash)"}
    diffs = [f"{what[k]}: stored {stored.get(k)!r}, now {code.get(k)!r}" for k in what if stored.get(k) != code.get(k)]
    if diffs:
        raise SweepDefinitionError(
            f"the store {str(path)!r} was computed by other code ({'; '.join(diffs)}): resuming would mix points "
            "of both in one store. Use another --out path, or overwrite=True (--overwrite) to compute every point "
            "again")
    if stored.get("package_source") != code.get("package_source"):
        warnings.warn(f"the store {str(path)!r} was begun by flutterswim of other sources (hash "
                      f"{stored.get('package_source')}, now {code.get('package_source')}; same version): if the "
                      "edit changed what a point computes, its points before and after differ (overwrite=True, "
                      "--overwrite, computes them all again)", UserWarning, stacklevel=4)


class SweepStore:
    def __init__(self, path: str | Path, group, spec: SweepSpec, variables: list[str]):
        self.path, self.group, self.spec, self.variables = Path(path), group, spec, list(variables)
        self._lock = None
        self.created = False  # True: this run created (or replaced) the store at path
        self.replaced: Path | None = None  # the store overwrite set aside (until the new one holds a point)
        self._dims, self._shape, _ = store_dims(spec)
        # flat position of point k in the row-major dataset (continuation: the down branch
        # runs back along the axis)
        # (from spec.point, as index() is: the positions had assumed "up" in the order given, and a
        # descending axis resumed, reported and retried the wrong points)
        self._pos = (np.array([np.ravel_multi_index(self.index(k), self._shape) for k in range(spec.n_points)])
                     if spec.continuation else np.arange(spec.n_points))
        self._arr = {k: group[k] for k in (*self.variables, *BOOKKEEPING)}

    # ------------------------------------------------------------------ open/create
    @classmethod
    def open(cls, path: str | Path, spec: SweepSpec, variables: Sequence[str], n_state: int,
             *, overwrite: bool = False, code: dict | None = None) -> "SweepStore":
        """Open (resume) or create the store and take its writer lock (released by
        :meth:`close` or when the process ends, SIGKILL included)."""
        path = check_store_path(path, overwrite=overwrite, kind="sweep")
        if not has_marker(path) and path.suffix.lower() != ".zarr":  # ours is resumed whatever its name
            raise ParameterError(f"out={str(path)!r}: a new sweep store is a Zarr folder named *.zarr; give a name "
                                 f"such as {path.stem or 'sweep'}.zarr")
        if overwrite and path.is_dir() and has_marker(path):
            _refuse_foreign(path)  # before anything is computed or deleted
        lock = _acquire(path)
        try:
            store = cls._open(path, spec, list(variables), n_state, overwrite=overwrite, code=code)
        except BaseException:
            lock.close()
            raise
        store._lock = lock
        return store

    def close(self) -> None:
        if self._lock is not None:
            self._lock.close()
            self._lock = None

    @classmethod
    def _open(cls, path: Path, spec, variables, n_state, *, overwrite, code=None):
        _settle_remnants(path)
        if path.exists() and has_marker(path):
            if overwrite:
                _refuse_foreign(path)  # again, under the lock
                # set aside, not deleted: the new store's run may not start (a scheduler's address
                # mistyped deleted a finished store and left nothing); deleted once it holds a point
                replaced = set_aside_own_store(path, kind="sweep")
                try:
                    store = cls._create(path, spec, variables, n_state, code)
                except BaseException:
                    os.replace(replaced, path)
                    raise
                store.replaced = replaced
                return store
            else:
                return cls._resume(path, spec, variables, code)
        elif path.is_dir():  # empty directory (checked): replaced by the new store
            path.rmdir()
        return cls._create(path, spec, variables, n_state, code)

    def settle_replaced(self, keep_new: bool) -> None:
        """The store ``overwrite`` set aside: deleted if the new one is kept (it holds points),
        else put back in place of the new, empty one (under the lock)."""
        old, self.replaced = self.replaced, None
        if not keep_new and self.created:
            remove_own_store(self.path, kind="sweep")
        if old is None:
            return
        if keep_new:
            remove_own_store(old, kind="sweep")
        else:
            os.replace(old, self.path)

    @classmethod
    def _resume(cls, path: Path, spec: SweepSpec, variables: list[str], code: dict | None = None) -> "SweepStore":
        import zarr

        hint = (" Nothing was recomputed. Rerun with --overwrite (overwrite=True) to discard it and start "
                "again, or give another --out path.")
        try:
            g = zarr.open_group(str(path), mode="r+")
            attrs = dict(g.attrs)
        except Exception as exc:  # noqa: BLE001 - unreadable metadata
            raise SweepStoreError(f"the store {str(path)!r} is a flutterswim store but its metadata cannot be "
                                  f"read ({type(exc).__name__}: {exc})." + hint) from None
        missing = [k for k in ("format", "sweep_spec", "fingerprint", "variables") if k not in attrs]
        if missing:
            raise SweepStoreError(f"the store {str(path)!r} is a flutterswim store but incomplete: the "
                                  f"attribute(s) {', '.join(missing)} are missing." + hint)
        if attrs["format"] != FORMAT:
            raise SweepStoreError(f"the store {str(path)!r} has the format {attrs['format']!r}; this version "
                                  f"reads {FORMAT!r}." + hint)
        stored_vars = json.loads(attrs["variables"])
        stored_spec = json.loads(attrs["sweep_spec"])
        if stored_spec != json.loads(spec.to_json()) or stored_vars != variables:
            diffs = spec.diff(stored_spec)
            if stored_vars != variables:
                diffs.append("variables: the point function returns a different set of variables")
            asked = json.loads(spec.to_json())
            legacy = "up" in asked and "up" not in stored_spec and asked.get("axes") == stored_spec.get("axes")
            raise SweepDefinitionError(
                f"the store {str(path)!r} holds a different sweep (definition {attrs.get('fingerprint')}, "
                f"requested {spec.fingerprint}); differences: " + "; ".join(diffs[:8]) + ". "
                + ("(It was made by an earlier flutterswim, whose continuation ran 'up' in the axis's order as "
                   "given, not in increasing value: open_sweep reads it as it ran, but it cannot be resumed.) "
                   if legacy else "")
                + "Use another --out path, or overwrite=True (--overwrite) to discard the stored points."
            )
        _same_code(path, attrs, code)
        if attrs["fingerprint"] != spec.fingerprint:
            raise SweepStoreError(f"the store {str(path)!r} is inconsistent: its fingerprint "
                                  f"{attrs['fingerprint']} does not match its definition." + hint)
        names = set(g.array_keys())
        need = [*variables, *BOOKKEEPING]
        # the files themselves, not only the consolidated listing
        absent = [k for k in need if k not in names or not (path / k / "zarr.json").is_file()]
        if absent:
            raise SweepStoreError(f"the store {str(path)!r} is a flutterswim store but incomplete: the "
                                  f"variable(s) {', '.join(absent[:6])} are missing." + hint)
        dims, shape, _ = store_dims(spec)
        bad = [k for k in need if tuple(g[k].shape[: len(shape)]) != shape]
        if bad:
            raise SweepStoreError(f"the store {str(path)!r} is inconsistent: variable(s) {', '.join(bad[:6])} "
                                  f"do not have the grid shape {shape}." + hint)
        return cls(path, g, spec, variables)

    @classmethod
    def _create(cls, path: Path, spec: SweepSpec, variables: list[str], n_state: int,
                code: dict | None = None) -> "SweepStore":
        """Build the store under a temporary name next to ``path``, then rename it into place."""
        import shutil

        import xarray as xr
        import zarr

        dims, shape, coords = store_dims(spec)
        tu = _time_unit(spec)
        chunk = tuple([1] * (len(shape) - 1) + [min(shape[-1], 64)])
        data: dict[str, Any] = {}
        enc: dict[str, Any] = {}
        for name in variables:
            data[name] = (dims, np.full(shape, np.nan), variable_attrs(name, tu))
        data["done"] = (dims, np.zeros(shape, np.int8), variable_attrs("done", tu))
        data["failed"] = (dims, np.zeros(shape, np.int8), variable_attrs("failed", tu))
        data["reason"] = (dims, np.full(shape, "", dtype=object), variable_attrs("reason", tu))
        data["wall_time_s"] = (dims, np.full(shape, np.nan), variable_attrs("wall_time_s", tu))
        ns = max(int(n_state), 1)
        data["state"] = ([*dims, "state"], np.full((*shape, ns), np.nan), variable_attrs("state", tu))
        for name in data:
            enc[name] = {"chunks": chunk + ((ns,) if name == "state" else ())}
        ds = xr.Dataset(data, coords=coords)
        from .. import __version__

        ds.attrs.update({
            "title": "flutterswim parameter sweep", "Conventions": "CF-1.10",
            "source": f"flutterswim {__version__}", "flutterswim_version": __version__, "format": FORMAT,
            # (strings only: a nested attribute is no NetCDF attribute, and open_zarr(...).to_netcdf failed)
            "sweep_spec": spec.to_json(),
            "fingerprint": spec.fingerprint, "variables": json.dumps(variables), "n_state": ns,
            "time_unit": tu,
            "swept": json.dumps(list(spec.names)),
        })
        if code is not None:  # what computed the points (a resume by other code is refused: _same_code)
            ds.attrs["code"] = json.dumps(code, sort_keys=True)
        # the base point as numeric attributes with units (as a run's), beside the JSON
        for k, v in spec.base.to_dict().items():
            ds.attrs[f"base_{k}"] = float(v)
            ds.attrs[f"base_{k}_units"] = UNITS[k]
        tmp = path.parent / f".{path.name}.creating-{os.getpid()}"
        if tmp.exists():
            shutil.rmtree(tmp)
        tmp.mkdir()
        try:
            with warnings.catch_warnings():
                # consolidated metadata lets plain xarray.open_zarr(path) read it without a warning
                warnings.filterwarnings("ignore", message="Consolidated metadata", category=UserWarning)
                ds.to_zarr(str(tmp), mode="w", encoding=enc, consolidated=True, zarr_format=3)
            write_marker(tmp, "sweep", format=FORMAT)  # after consolidation, which lists the files
            os.rename(tmp, path)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        assert (path / MARKER).is_file()
        store = cls(path, zarr.open_group(str(path), mode="r+"), spec, variables)
        store.created = True
        return store

    # ------------------------------------------------------------------ points
    def index(self, k: int) -> tuple[int, ...]:
        """Region (index tuple) of point k in the dataset."""
        branch, i, _ = self.spec.point(k)
        shp = self._shape[1:] if self.spec.continuation else self._shape
        idx = tuple(int(j) for j in np.unravel_index(i, shp))
        return ((self.spec.branches.index(branch),) + idx) if self.spec.continuation else idx

    def _flat(self, name: str) -> np.ndarray:
        """Variable ``name`` as a flat (n_points,) array in point order."""
        a = np.asarray(self._arr[name][...]).reshape(-1)
        return a[self._pos]

    def done_mask(self) -> np.ndarray:
        return self._flat("done") == 1

    def write_point(self, k: int, values: dict[str, float] | None, *, failed: bool, message: str,
                    wall_time: float, state: np.ndarray | None = None, done: bool = True) -> None:
        """Write point k as its own region: values, reason, flags, state, then ``done`` (last)."""
        idx = self.index(k)
        for name in self.variables:
            v = math.nan
            if values is not None:
                try:
                    v = float(values.get(name, math.nan))
                except (TypeError, ValueError):
                    v = math.nan
            self._arr[name][idx] = v
        self._arr["reason"][idx] = str(message)
        self._arr["failed"][idx] = 1 if failed else 0
        self._arr["wall_time_s"][idx] = float(wall_time)
        st = self._arr["state"]
        srow = np.full(st.shape[-1], np.nan)
        if state is not None:
            s = np.asarray(state, float).ravel()[: st.shape[-1]]
            srow[: s.size] = s
        st[idx] = srow
        self._arr["done"][idx] = 1 if done else 0

    def state(self, k: int) -> np.ndarray | None:
        s = np.asarray(self._arr["state"][self.index(k)])
        return None if not np.all(np.isfinite(s)) else s

    def value(self, k: int, j: int) -> float:
        return float(self._arr[self.variables[j]][self.index(k)])

    def failed(self, k: int) -> bool:
        return bool(self._arr["failed"][self.index(k)])

    # ------------------------------------------------------------------ read
    def read(self) -> dict[str, Any]:
        """Flat per-point arrays in point order (k = 0 .. n_points-1)."""
        values = np.stack([self._flat(n).astype(float) for n in self.variables], axis=1) if self.variables \
            else np.empty((self.spec.n_points, 0))
        return {
            "values": values,
            "message": [str(m) for m in self._flat("reason")],
            "failed": self._flat("failed").astype(bool),
            "wall_time": self._flat("wall_time_s").astype(float),
            "done": self.done_mask(),
        }
