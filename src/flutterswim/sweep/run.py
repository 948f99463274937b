"""``sweep``: run a parameter sweep on a backend, durably, and return an xarray Dataset."""

from __future__ import annotations

import json
import math
import sys
import tempfile
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from ..params import Groups, Parameters
from .._validate import ParameterError
from .backends import WorkerLost, check_backend, get_backend
from .point import CORE_VARIABLES, FLAG_VARIABLES, VARIABLES, run_point, timed
from .spec import PointSettings, SweepSpec
from .store import SweepStore

__all__ = ["sweep", "open_sweep", "to_dataset", "BOOL_VARIABLES", "SweepInterrupted"]

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


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C during a sweep; the message says how many points are saved and how to resume."""


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
    retry_failed: bool = False,
):
    """Run a parameter sweep and return an ``xarray.Dataset`` indexed by the swept parameters.

    ``axes``: e.g. ``["kappa_E_ratio=0:2:101"]`` or ``{"chi": [60, 70, 80]}`` (see
    :mod:`flutterswim.sweep.spec`); ``base``: Parameters, Groups or a preset name. Each point
    runs to a converged limit cycle or ``settings.t_cap`` (:class:`PointSettings`) and is
    described over ``settings.n_cycles`` cycles. ``backend``: "processes" (default, all
    cores), "serial", "dask" (with ``scheduler``), "dask-local"; the result does not depend
    on it. ``out``: Zarr store written point by point (an ordinary xarray dataset, see
    :mod:`.store`); rerunning the same call resumes (finished points are not recomputed), a
    different definition is refused; ``overwrite=True`` replaces only a flutterswim store.
    ``continuation``: each point starts from the previous one's final state, up the axis and
    back down (adds a ``branch`` dimension). ``point_fn(task) -> dict`` replaces the
    simulation (tests, custom measurements; for the "processes" backend it must live in an
    importable module, not in the main script; give its ``variables`` and optionally
    ``required``, the variables that must be finite, as attributes). ``max_points``: stop
    after computing that many points (the rest stay undone). ``retry_failed``: on a rerun,
    compute again the points recorded as failed (a transient failure: memory, a lost
    connection); by default a rerun keeps them.

    Everything is checked before any point runs (definition, settings, grid size, output
    path). A failing point (exception, non-finite values) is recorded with its message and
    never stops the sweep; a point whose worker process died is left undone (the next run
    recomputes it). Failures are summarised on stderr. Ctrl-C raises
    :class:`SweepInterrupted` saying how many points are saved.
    """
    spec = axes if isinstance(axes, SweepSpec) else SweepSpec.build(
        axes, base, mode=mode, continuation=continuation, settings=settings)
    fn = point_fn or run_point
    variables = list(variables or getattr(fn, "variables", None) or VARIABLES)
    if backend not in ("serial",) and getattr(fn, "__module__", None) == "__main__" and backend == "processes":
        raise ParameterError(
            f"point_fn={getattr(fn, '__name__', fn)!r} is defined in the main script; the worker processes "
            "never run your script (so that scripts without an if __name__ == '__main__' guard work), so "
            "they cannot import it. Move it into a module, or use backend='serial' (or 'dask-local' from a script "
            "guarded by if __name__ == '__main__': dask's workers run the script again)")
    check_backend(backend, workers=workers, scheduler=scheduler)  # before the store is touched
    if max_points is not None:
        from .._validate import positive_int

        max_points = positive_int("max_points", max_points)
    n_state = 2 * spec.settings.n_segments + 3
    tmp = None
    if out is None:
        tmp = tempfile.TemporaryDirectory(prefix="flutterswim-sweep-")
        out = f"{tmp.name}/sweep.zarr"
    try:
        from .store import code_identity

        store = SweepStore.open(out, spec, variables, n_state, overwrite=overwrite, code=code_identity(fn))
        try:
            _run(store, spec, fn, variables, backend=backend, workers=workers, scheduler=scheduler,
                 progress=progress, max_points=max_points, temporary=tmp is not None, retry_failed=retry_failed)
            ds = to_dataset(store)
        except BaseException as exc:
            # the backend did not start (no scheduler answered, ...) before any point was saved:
            # the store this run created holds nothing, and is not left behind; a store
            # overwrite=True set aside is put back (under the lock)
            empty = store.created and not store.done_mask().any()
            had_old = store.replaced is not None
            try:
                store.settle_replaced(keep_new=not empty)
            except (OSError, ParameterError):
                pass
            if empty and isinstance(exc, SweepInterrupted):  # (it said "0 of 6 saved in ...; rerun to resume")
                raise SweepInterrupted("interrupted before any point was saved: nothing was written"
                                       + ("; the store that was there is kept" if had_old else "")) from None
            raise
        else:
            store.settle_replaced(keep_new=True)
        finally:
            store.close()
        if tmp is not None:
            ds = ds.load()
    finally:
        if tmp is not None:
            tmp.cleanup()
    return ds


def _run(store: SweepStore, spec: SweepSpec, fn, variables, *, backend, workers, scheduler, progress,
         max_points, temporary=False, retry_failed=False) -> None:
    done = store.done_mask()
    if retry_failed:  # failed points count as not done: computed again, in order
        done = done & ~store.read()["failed"]
    todo = [k for k in range(spec.n_points) if not done[k]]
    if max_points is not None:
        todo = todo[: int(max_points)]
    bar = None
    call = _Call(fn)
    counts = {"failed": 0, "lost": 0, "saved": int(done.sum())}

    def record(k, out):
        if isinstance(out, WorkerLost):
            # not done: the next run recomputes it
            store.write_point(k, None, failed=True, message=out.message, wall_time=math.nan, done=False)
            counts["lost"] += 1
        else:
            result, err, wall = out
            values = state = None
            if not err:
                values, state, err = _check(result, variables, getattr(fn, "required", None))
            # the reason: a failure's, else what the point settled into and why (run_point's
            # "reason": a capped point said nothing about why it was capped)
            why = err or (str(result.get("reason", "")) if isinstance(result, Mapping) else "")
            store.write_point(k, None if err else values, failed=bool(err), message=why, wall_time=wall,
                              state=None if err else state)
            counts["failed"] += bool(err)
            counts["saved"] += 1
            if store.replaced is not None:  # the new store holds a point: the old one overwrite set aside goes
                store.settle_replaced(keep_new=True)
        if bar is not None:
            bar.update(1)
            if counts["failed"] or counts["lost"]:
                bar.set_postfix(failed=counts["failed"] + counts["lost"])

    try:
        if not todo:
            return
        with get_backend(backend, workers=workers, scheduler=scheduler) as ex:
            if progress:
                from tqdm.auto import tqdm

                bar = tqdm(total=spec.n_points, initial=int(done.sum()), desc="sweep", unit="pt", smoothing=0.1)
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
    except KeyboardInterrupt:
        if bar is not None:
            bar.close()
            bar = None
        where = "in a temporary store (discarded)" if temporary else f"in {str(store.path)!r}"
        resume = "" if temporary else "; rerun the same command to resume"
        raise SweepInterrupted(f"interrupted: {counts['saved']} of {spec.n_points} points are saved "
                               f"{where}{resume}") from None
    except OSError as exc:
        if temporary:
            raise
        # (a full disk said only "[Errno 28] No space left on device": not what was kept)
        raise OSError(exc.errno, f"{exc.strerror or exc}: {counts['saved']} of {spec.n_points} points are saved in "
                                 f"{str(store.path)!r}; rerun the same command to resume (after freeing space)") from exc
    finally:
        if bar is not None:
            bar.close()
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
    """Failure reasons on ``file`` (always, progress bar or not)."""
    data = store.read()
    # a point lost with its worker is not a failed one: it is not saved, and a plain rerun
    # computes it (it had been counted among the failed, which a rerun keeps)
    failed = np.nonzero(data["failed"] & data["done"])[0]
    gone = np.nonzero(data["failed"] & ~data["done"])[0]
    n = store.spec.n_points
    for bad, head in ((failed, f"sweep: {failed.size} of {n} points failed (a rerun keeps them; retry_failed / "
                               "--retry-failed computes them again):"),
                      (gone, f"sweep: {gone.size} of {n} points not saved, lost with their worker (a rerun of the "
                             "same command computes them):")):
        if not bad.size:
            continue
        print(head, file=file)
        for k in bad[:20]:
            print(f"  point {k} {store.spec.point(int(k))[2]}: {data['message'][k]}", file=file)
        if bad.size > 20:
            print(f"  ... and {bad.size - 20} more" + (" (see the 'reason' variable)" if bad is failed else ""),
                  file=file)


def open_sweep(path: str):
    """The Dataset of a sweep store (finished or not) without running anything (the store is
    also readable with plain ``xarray.open_zarr(path)``)."""
    import zarr

    from .._paths import has_marker
    from .store import FORMAT, SweepStoreError

    p = Path(path)
    if not p.exists():
        raise ParameterError(f"store={str(path)!r} does not exist")
    if not (p.is_dir() and has_marker(p)):
        raise ParameterError(f"store={str(path)!r} is not a flutterswim sweep store")
    try:
        g = zarr.open_group(str(p), mode="r")
        attrs = dict(g.attrs)
        if attrs.get("format") != FORMAT:
            raise SweepStoreError(f"store={str(path)!r} has the format {attrs.get('format')!r}; this version "
                                  f"reads {FORMAT!r}")
        spec = SweepSpec.from_dict(json.loads(attrs["sweep_spec"]))
        store = SweepStore(p, g, spec, json.loads(attrs["variables"]))
    except ParameterError:
        raise
    except Exception as exc:  # noqa: BLE001 - damaged store
        raise ParameterError(f"store={str(path)!r} cannot be read ({type(exc).__name__}: {exc})") from None
    return to_dataset(store)


def to_dataset(store: SweepStore):
    """xarray Dataset of the store: dims = swept axes (grid) or ``point`` (list), plus
    ``branch`` ("up", "down") with continuation; flags as booleans, undone points NaN."""
    import xarray as xr

    spec = store.spec
    with xr.open_zarr(str(store.path), consolidated=True, chunks=None) as raw:
        ds = raw.drop_vars("state").load()
    done = ds["done"].values == 1
    for name in store.variables:
        v = np.where(done, ds[name].values, np.nan)
        attrs = ds[name].attrs
        if name in BOOL_VARIABLES:
            v = np.where(np.isfinite(v), v, 0.0) > 0.5
        ds[name] = (ds[name].dims, v, attrs)
    failed = (ds["failed"].values == 1) & done
    ds["done"] = (ds["done"].dims, done, ds["done"].attrs)
    ds["failed"] = (ds["failed"].dims, failed, ds["failed"].attrs)
    reasons = np.array([str(r) for r in ds["reason"].values.ravel()], dtype=object).reshape(done.shape)
    ds["reason"] = (ds["reason"].dims, np.where(done, reasons, "").astype(str), ds["reason"].attrs)
    b = spec.base
    data = store.read()
    for k in ("spec", "n_state", "variables", "swept"):
        ds.attrs.pop(k, None)
    ds.attrs.update({
        "sweep_spec": spec.to_json(), "fingerprint": spec.fingerprint,
        "base_kappa_E": float(b.kappa_E) if isinstance(b, Parameters) else float("nan"),
        "base_chi": float(b.chi),
        "n_failed": int(failed.sum()), "n_done": int(done.sum()), "n_points": int(spec.n_points),
        "failed_points": json.dumps([
            {"point": int(k), "values": spec.point(int(k))[2], "reason": data["message"][k]}
            for k in np.nonzero(data["failed"] & data["done"])[0]
        ]),
    })
    return ds
