"""``sweep``: run a parameter sweep on a backend, durably, and return an xarray Dataset."""

from __future__ import annotations

import json
import math
import sys
import tempfile
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from ..params import Groups, Parameters
from .backends import get_backend
from .point import CORE_VARIABLES, DESCRIPTOR_VARIABLES, FLAG_VARIABLES, VARIABLES, run_point, timed
from .spec import PointSettings, SweepSpec
from .store import SweepStore

__all__ = ["sweep", "open_sweep", "to_dataset", "BOOL_VARIABLES"]

BOOL_VARIABLES = FLAG_VARIABLES + ("limit_cycle", "self_intersecting", "towards_field", "reciprocal")


class _Call:
    """Picklable ``timed(fn, task)`` (workers return results, never write)."""

    def __init__(self, fn: Callable):
        self.fn = fn

    def __call__(self, task):
        from .backends import single_blas_thread

        with single_blas_thread():
            return timed(self.fn, task)


def _task(spec: SweepSpec, k: int, initial: np.ndarray | None) -> dict[str, Any]:
    branch, i, values = spec.point(k)
    return {"base": spec.to_dict()["base"], "values": values, "settings": spec.settings.to_dict(),
            "initial": initial, "index": k, "branch": branch}


def _check(result: Any, variables: Sequence[str], required: Sequence[str] | None = None
           ) -> tuple[dict | None, np.ndarray | None, str]:
    """-> (values, final state, failure message or ""). A value is bad if infinite, or NaN
    where it is required (``required``; default: the core variables of :func:`run_point` if
    present, else every returned value)."""
    if isinstance(result, Mapping) and "values" in result:
        values, state = dict(result["values"]), result.get("final_state")
    elif isinstance(result, Mapping):
        values, state = dict(result), None
    else:
        return None, None, f"the point function returned {type(result).__name__}; a dict is required"
    bad = []
    if required is None:
        required = [k for k in CORE_VARIABLES if k in values] or list(values)
    for k, v in values.items():
        try:
            fv = float(v)
        except (TypeError, ValueError):
            bad.append(f"{k}={v!r}")
            continue
        if math.isinf(fv) or (math.isnan(fv) and k in required):
            bad.append(f"{k}={fv}")
    if bad:
        return values, state, "non-finite values: " + ", ".join(bad[:10])
    missing = [k for k in variables if k not in values]
    if len(missing) == len(variables):
        return values, state, "the point function returned none of the sweep variables"
    if state is not None and not np.all(np.isfinite(np.asarray(state, float))):
        return values, state, "non-finite final state"
    return values, state, ""


def sweep(
    axes: Iterable[str] | Mapping[str, Iterable[float]] | SweepSpec,
    base: Parameters | Groups | str = "paper",
    *,
    out: str | None = None,
    backend: str = "processes",
    workers: int | None = None,
    scheduler: str | None = None,
    mode: str = "grid",
    continuation: bool = False,
    settings: PointSettings | Mapping[str, Any] | None = None,
    point_fn: Callable[[dict], Any] | None = None,
    variables: Sequence[str] | None = None,
    progress: bool = True,
    overwrite: bool = False,
    max_points: int | None = None,
):
    """Run a parameter sweep and return an ``xarray.Dataset`` indexed by the swept parameters.

    ``axes``: e.g. ``["kappa_E_ratio=0:2:101"]`` or ``{"chi": [60, 70, 80]}`` (see
    :mod:`flutterswim.sweep.spec`); ``base``: Parameters, Groups or a preset name. Each point
    runs to a converged limit cycle or ``settings.t_cap`` (:class:`PointSettings`) and is
    described over ``settings.n_cycles`` cycles. ``backend``: "processes" (default, all
    cores), "serial", "dask" (with ``scheduler``), "dask-local"; the result does not depend
    on it. ``out``: Zarr store written point by point; rerunning the same call resumes
    (finished points are not recomputed), a different definition is refused. ``continuation``:
    each point starts from the previous one's final state, up the axis and back down (adds a
    ``branch`` dimension). ``point_fn(task) -> dict`` replaces the simulation (tests, custom
    measurements; it must be picklable for parallel backends; give its ``variables`` and
    optionally ``required``, the variables that must be finite, as attributes).
    ``max_points``: stop after computing that many points (the rest stay undone).
    A failing point (exception, non-finite values) is recorded with its message and never
    stops the sweep.
    """
    spec = axes if isinstance(axes, SweepSpec) else SweepSpec.build(
        axes, base, mode=mode, continuation=continuation, settings=settings)
    fn = point_fn or run_point
    variables = list(variables or getattr(fn, "variables", None) or VARIABLES)
    n_state = 2 * spec.settings.n_segments + 3
    tmp = None
    if out is None:
        tmp = tempfile.TemporaryDirectory(prefix="flutterswim-sweep-")
        out = f"{tmp.name}/sweep.zarr"
    try:
        store = SweepStore.open(out, spec, variables, n_state, overwrite=overwrite)
        try:
            _run(store, spec, fn, variables, backend=backend, workers=workers, scheduler=scheduler,
                 progress=progress, max_points=max_points)
            ds = to_dataset(store)
        finally:
            store.close()
        if tmp is not None:
            ds = ds.load()
    finally:
        if tmp is not None:
            tmp.cleanup()
    return ds


def _run(store: SweepStore, spec: SweepSpec, fn, variables, *, backend, workers, scheduler, progress,
         max_points) -> None:
    done = store.done_mask()
    todo = [k for k in range(spec.n_points) if not done[k]]
    if max_points is not None:
        todo = todo[: int(max_points)]
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=spec.n_points, initial=int(done.sum()), desc="sweep", unit="pt", smoothing=0.1)
    call = _Call(fn)
    n_failed = 0

    def record(k, out):
        nonlocal n_failed
        result, err, wall = out
        values = state = None
        if not err:
            values, state, err = _check(result, variables, getattr(fn, "required", None))
        store.write_point(k, None if err else values, failed=bool(err), message=err, wall_time=wall,
                          state=None if err else state)
        n_failed += bool(err)
        if bar is not None:
            bar.update(1)
            if n_failed:
                bar.set_postfix(failed=n_failed)

    try:
        if not todo:
            return
        with get_backend(backend, workers=workers, scheduler=scheduler) as ex:
            if not spec.continuation:
                items = ((k, _task(spec, k, None)) for k in todo)
                for k, out in ex.imap(call, items):
                    record(k, out)
            else:
                # a chain: each point starts from its predecessor's final state
                for k in todo:
                    init = _continue_from(store, k)
                    for kk, out in ex.imap(call, [(k, _task(spec, k, init))]):
                        record(kk, out)
    finally:
        if bar is not None:
            bar.close()
    if progress:
        _summary(store, file=sys.stderr)


def _continue_from(store: SweepStore, k: int) -> np.ndarray | None:
    """Initial state of continuation point k: the final state of point k-1, unless that point
    failed or damped out to the straight state (then the default perturbed straight state, as
    an exactly straight filament would need unbounded time to show an instability)."""
    if k == 0 or store.failed(k - 1):
        return None
    j = store.variables.index("straight") if "straight" in store.variables else None
    if j is not None and store.value(k - 1, j) > 0.5:
        return None
    return store.state(k - 1)


def _summary(store: SweepStore, file=None) -> None:
    data = store.read()
    bad = np.nonzero(data["failed"] & data["done"])[0]
    if bad.size:
        print(f"sweep: {bad.size} of {store.spec.n_points} points failed:", file=file)
        for k in bad[:20]:
            print(f"  point {k} {store.spec.point(int(k))[2]}: {data['message'][k]}", file=file)
        if bad.size > 20:
            print(f"  ... and {bad.size - 20} more (see the 'reason' variable)", file=file)


def open_sweep(path: str):
    """The Dataset of a sweep store (finished or not) without running anything."""
    import zarr

    g = zarr.open_group(str(path), mode="r")
    spec = SweepSpec.from_dict(g.attrs["spec"])
    store = SweepStore(path, g, spec, list(g.attrs["variables"]))
    return to_dataset(store)


def to_dataset(store: SweepStore):
    """xarray Dataset of the store: dims = swept axes (grid) or ``point`` (list), plus
    ``branch`` ("up", "down") with continuation."""
    import xarray as xr

    spec = store.spec
    data = store.read()
    n = spec.n_values
    nb = len(spec.branches)
    # point order -> (branch, value index)
    order = np.empty((nb, n), dtype=int)
    for k in range(spec.n_points):
        b, i, _ = spec.point(k)
        order[spec.branches.index(b), i] = k

    if spec.mode == "grid":
        dims = list(spec.names)
        coords: dict[str, Any] = {a.name: np.array(a.values) for a in spec.axes}
        shape = spec.shape
    else:
        dims = ["point"]
        coords = {a.name: ("point", np.array(a.values)) for a in spec.axes}
        coords["point"] = np.arange(n)
        shape = (n,)
    if spec.continuation:
        dims = ["branch"] + dims
        coords["branch"] = list(spec.branches)
        full = (nb,) + shape
        take = order.reshape(full)
    else:
        full = shape
        take = order[0].reshape(shape)

    variables = store.variables
    ds_vars: dict[str, Any] = {}
    done = data["done"][take]
    failed = data["failed"][take] & done
    for j, name in enumerate(variables):
        v = data["values"][:, j][take]
        if name in BOOL_VARIABLES:
            v = np.where(np.isfinite(v), v, 0.0) > 0.5
        ds_vars[name] = (dims, v)
    ds_vars["done"] = (dims, done)
    ds_vars["failed"] = (dims, failed)
    msgs = np.array(data["message"], dtype=object)[take]
    ds_vars["reason"] = (dims, msgs.astype(str))
    ds_vars["wall_time_s"] = (dims, data["wall_time"][take])
    ds = xr.Dataset(ds_vars, coords=coords)
    b = spec.base
    units_t = "s" if isinstance(b, Parameters) else "tau"
    ds.attrs.update({
        "sweep_spec": spec.to_json(), "fingerprint": spec.fingerprint, "time_unit": units_t,
        "base_kappa_E": float(b.kappa_E) if isinstance(b, Parameters) else float("nan"),
        "base_chi": float(b.chi),
        "n_failed": int(failed.sum()), "n_done": int(done.sum()), "n_points": int(spec.n_points),
        "failed_points": json.dumps([
            {"point": int(k), "values": spec.point(int(k))[2], "reason": data["message"][k]}
            for k in np.nonzero(data["failed"] & data["done"])[0]
        ]),
    })
    for name in DESCRIPTOR_VARIABLES:
        if name.endswith("_s") and name in ds and units_t == "tau":
            ds[name].attrs["note"] = "time in tau (dimensionless sweep)"
    return ds
