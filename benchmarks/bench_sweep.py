"""Sweep benchmarks (not a test): the paper's 101-point kappa_E sweep, worker scaling,
Dask per-point overhead, resume cost.

    .venv/bin/python benchmarks/bench_sweep.py [--quick] [--only full|scaling|dask|resume]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import tempfile
import time

import numpy as np


def machine() -> str:
    try:
        cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    except Exception:
        cpu = platform.processor()
    return f"{cpu}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}, load {os.getloadavg()}"


def _sleep_point(task):
    time.sleep(0.0)
    return {"a": task["values"]["chi"]}


_sleep_point.variables = ["a"]


def main() -> None:
    from flutterswim.sweep import sweep
    from flutterswim.sweep.plot import critical_ratio, plot_sweep

    ap = argparse.ArgumentParser()
    ap.add_argument("--only", default=None)
    # (the committed kappa_E figure comes from the stroke branch: bench_orbits.py)
    ap.add_argument("--figure", default=None)
    ap.add_argument("--n", type=int, default=101)
    ap.add_argument("--scaling-full", action="store_true", help="scaling on the full 0:2:n grid")
    ap.add_argument("--rtol", type=float, default=None, help="override PointSettings.rtol (atol = rtol/100)")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="bench-sweep-")
    res: dict = {"machine": machine()}
    axes = [f"kappa_E_ratio=0:2:{a.n}"]
    st = None if a.rtol is None else {"rtol": a.rtol, "atol": a.rtol / 100}
    res["settings"] = st or "default (PointSettings: n_segments=24, rtol=1e-4, atol=1e-6, t_cap=60 tau, 15 cycles)"

    def cpu_children() -> float:
        ru = resource.getrusage(resource.RUSAGE_CHILDREN)
        return ru.ru_utime + ru.ru_stime
    try:
        if a.only in (None, "full"):
            t0, c0 = time.perf_counter(), cpu_children()
            ds = sweep(axes, out=f"{tmp}/full.zarr", backend="processes", workers=2, progress=False, settings=st)
            res["full_101_2workers_s"] = time.perf_counter() - t0
            res["full_worker_cpu_s"] = cpu_children() - c0
            res["load_after"] = os.getloadavg()
            res["full_core_seconds"] = float(np.nansum(ds["wall_time_s"].values))
            res["full_failed"] = int(ds["failed"].sum())
            sw = ds["limit_cycle"].values.astype(bool)
            x = ds["kappa_E_ratio"].values
            res["first_swimming_ratio"] = float(x[np.argmax(sw)]) if sw.any() else None
            res["critical_ratio_linear"] = critical_ratio(ds)
            adv = np.where(sw, ds["advance_per_cycle_bl"].values, np.nan)
            res["best_advance_ratio"] = float(x[np.nanargmax(adv)])
            res["best_advance_bl"] = float(np.nanmax(adv))
            res["self_intersecting_ratios"] = [float(v) for v in x[ds["self_intersecting"].values == 1]]
            res["orbit_by_continuation"] = [float(v) for v in x[sw & (ds["reached_limit_cycle"].values == 0)]]
            if a.figure:
                plot_sweep(ds, a.figure)
            # resume cost: rerun the finished sweep
            t0 = time.perf_counter()
            sweep(axes, out=f"{tmp}/full.zarr", backend="processes", workers=2, progress=False, settings=st)
            res["resume_finished_101_s"] = time.perf_counter() - t0
            print(json.dumps(res, indent=1), flush=True)
        if a.only in (None, "scaling"):
            sub = axes if a.scaling_full else ["kappa_E_ratio=0.7:2:27"]
            for w in (1, 2):
                t0, c0 = time.perf_counter(), cpu_children()
                sweep(sub, out=f"{tmp}/w{w}.zarr", backend="processes", workers=w, progress=False, settings=st)
                res[f"scaling_27pts_{w}worker_s"] = time.perf_counter() - t0
                res[f"scaling_27pts_{w}worker_cpu_s"] = cpu_children() - c0
                res[f"scaling_27pts_{w}worker_load"] = os.getloadavg()
            res["speedup_1_to_2"] = res["scaling_27pts_1worker_s"] / res["scaling_27pts_2worker_s"]
            # load-independent estimate: greedy 2-worker schedule (submission order, as the pool
            # does) of the per-point times measured with 1 worker, plus the measured parent-side cost
            from flutterswim.sweep import open_sweep

            wt = open_sweep(f"{tmp}/w1.zarr")["wall_time_s"].values
            busy = [0.0, 0.0]
            for w_ in wt:
                i = int(np.argmin(busy))
                busy[i] += w_
            parent = res["scaling_27pts_1worker_s"] - float(np.sum(wt))
            res["scaling_sum_point_s"] = float(np.sum(wt))
            res["scaling_parent_overhead_s"] = parent
            res["speedup_schedule_estimate"] = res["scaling_27pts_1worker_s"] / (max(busy) + parent)
            print(json.dumps(res, indent=1), flush=True)
        if a.only in (None, "dask"):
            from flutterswim.sweep import get_backend
            from flutterswim.sweep.run import _Call

            # the pool's workers never import the main script: the trivial point function is
            # taken from this file imported as a module (its folder is on the path they receive)
            from bench_sweep import _sleep_point

            # executor-level per-point overhead with a trivial point function (no store)
            n = 400
            items = [(k, {"values": {"chi": float(k)}}) for k in range(n)]
            for be in ("serial", "processes", "dask-local"):
                t0 = time.perf_counter()
                with get_backend(be, workers=2) as ex:
                    t1 = time.perf_counter()
                    got = sorted(k for k, _ in ex.imap(_Call(_sleep_point), items))
                    t2 = time.perf_counter()
                assert got == list(range(n))
                res[f"startup_{be}_s"] = t1 - t0
                res[f"overhead_{be}_ms_per_point"] = 1e3 * (t2 - t1) / n
            # store write cost per point (parent side)
            t0 = time.perf_counter()
            sweep({"chi": list(np.arange(200, dtype=float))}, out=f"{tmp}/ovh.zarr", backend="serial",
                  point_fn=_sleep_point, progress=False)
            res["store_serial_sweep_ms_per_point"] = 1e3 * (time.perf_counter() - t0) / 200
            # real points: processes vs dask-local, alternated twice to expose load noise
            sub = ["kappa_E_ratio=0.9:2:12"]
            for rep in range(2):
                for be in ("processes", "dask-local"):
                    t0 = time.perf_counter()
                    sweep(sub, out=f"{tmp}/real_{be}_{rep}.zarr", backend=be, workers=2, progress=False, settings=st)
                    res[f"real12_{be}_run{rep}_s"] = time.perf_counter() - t0
            print(json.dumps(res, indent=1), flush=True)
        if a.only in (None, "resume"):
            # kill-free resume cost model: half the points done, rerun computes the rest only
            sub = ["kappa_E_ratio=0.7:2:14"]
            t0 = time.perf_counter()
            sweep(sub, out=f"{tmp}/res.zarr", backend="processes", workers=2, progress=False, max_points=7)
            t_half = time.perf_counter() - t0
            t0 = time.perf_counter()
            sweep(sub, out=f"{tmp}/res.zarr", backend="processes", workers=2, progress=False)
            res["resume_half_then_rest_s"] = [t_half, time.perf_counter() - t0]
            print(json.dumps(res, indent=1), flush=True)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
