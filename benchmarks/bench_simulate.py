"""Benchmark: the paper preset from a 0.01 degree tilt to 15 settled cycles.

Reports, measured in this run:
- wall time of ``run_to_limit_cycle`` (the default integrator) at several resolutions, with the errors
  of the period and of the advancement per cycle against a much finer run of this code;
- the ratio against scipy's ``solve_ivp`` (Radau and BDF, given the same analytic Jacobian as
  ours) on the same semi-discretisation and window, at the tolerance that matches our accuracy;
- peak memory of a run saving 2000 frames of 100 points (in a fresh subprocess).

Usage: OPENBLAS_NUM_THREADS=1 python benchmarks/bench_simulate.py [--quick]
(one BLAS thread: the target is one core, and small matrices gain nothing from threads).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time

import numpy as np

import flutterswim as fs
from flutterswim.analysis.descriptors import describe
from flutterswim.limit_cycle import run_to_limit_cycle
from flutterswim.integrators import DEFAULT_METHOD


def job(n: int, rtol: float) -> dict:
    t0 = time.perf_counter()
    run = run_to_limit_cycle(fs.PAPER, n_cycles=15, n_segments=n, rtol=rtol, atol=rtol * 1e-2)
    wall = time.perf_counter() - t0
    d = describe(run, n_last=15)
    return {"n": n, "rtol": rtol, "wall_s": wall, "sim_s": float(run.t[-1]), "steps": run.stats.n_steps,
            "period_s": d.period_s, "advance_mm": d.advance_per_cycle_mm}


def job_errors(n: int, rtol: float, method: str, ref: dict) -> dict:
    """The same physical time as the reference job with one integrator (run_to_limit_cycle's
    settle engine always uses the default one; it lost its ``method`` argument, and this
    script failed here until stop 36)."""
    t0 = time.perf_counter()
    run = fs.simulate(fs.PAPER, ref["sim_s"], n_segments=n, rtol=rtol, atol=rtol * 1e-2, method=method)
    wall = time.perf_counter() - t0
    d = describe(run, n_last=15)
    return {"method": method, "rtol": rtol, "wall_s": wall,
            "period_err": abs(d.period_s / ref["period_s"] - 1),
            "advance_err": abs(d.advance_per_cycle_mm / ref["advance_mm"] - 1)}


# VmHWM (peak RSS of this process image), not ru_maxrss: Linux carries ru_maxrss across
# exec, so a child of a large parent would report the parent's peak.
MEMORY = """
import flutterswim as fs
r = fs.simulate(fs.PAPER, 40 * fs.PAPER.tau, n_segments=99, n_frames=2000, rtol=1e-4, atol=1e-6)
assert r.x.shape == (2000, 100)
print(next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmHWM")) / 1024)
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="skip the reference run")
    ap.add_argument("--only", choices=("jobs", "baseline", "memory"), default=None)
    args = ap.parse_args()
    cpu = platform.processor() or platform.machine()
    try:
        cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    print(f"machine: {cpu}; python {platform.python_version()}; numpy {np.__version__}")
    job(16, 1e-3)  # warm-up: loads the compiled kernels
    if args.only in (None, "jobs"):
        run_jobs(args.quick)
    if args.only in (None, "baseline"):
        run_baseline()
    if args.only in (None, "memory"):
        run_memory()
    print(f"load average at the end: {os.getloadavg()}")


def run_jobs(quick: bool) -> None:
    configs = [(32, 1e-4), (40, 1e-4), (48, 1e-4)]
    ref = None if quick else job(128, 1e-6)
    print("reference:", json.dumps(ref), flush=True)
    for n, r in configs:
        row = job(n, r)
        if ref is not None:
            row["period_err"] = abs(row["period_s"] / ref["period_s"] - 1)
            row["advance_err"] = abs(row["advance_mm"] / ref["advance_mm"] - 1)
        print(json.dumps(row), flush=True)


def run_baseline(n: int = 40) -> None:
    """The whole job on the same semi-discretisation (N fixed): ours at rtol 1e-4 against
    scipy at the loosest tolerance whose period and advancement errors (temporal only,
    against ours at rtol 1e-8) are no larger."""
    ref = job(n, 1e-8)
    ours = job_errors(n, 1e-4, DEFAULT_METHOD, ref)
    print("baseline reference (same N, rtol 1e-8):", json.dumps(ref), flush=True)
    print("ours:", json.dumps(ours), flush=True)
    for method in ("bdf", "radau"):
        for tol in (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6):
            row = job_errors(n, tol, method, ref)
            print(f"  {method}:", json.dumps(row), flush=True)
            if row["period_err"] <= ours["period_err"] and row["advance_err"] <= ours["advance_err"]:
                print(f"=> {method} matches our accuracy at rtol {tol:g}: {row['wall_s']:.2f} s vs ours "
                      f"{ours['wall_s']:.2f} s, ratio {row['wall_s'] / ours['wall_s']:.1f}x", flush=True)
                break


def run_memory() -> None:
    for attempt in ("first process", "second process"):  # the first may compile (numba cache)
        mem = subprocess.run([sys.executable, "-c", MEMORY], capture_output=True, text=True, check=True)
        print(f"peak RSS, 2000 frames x 100 points, {attempt}: {float(mem.stdout.strip()):.0f} MB")


if __name__ == "__main__":
    main()
