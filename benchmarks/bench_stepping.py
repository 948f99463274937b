"""Benchmark (issue 10): the paper job with the default compiled NDF and the compiled
Rosenbrock-W integrators against baselines, back to back in one run.

The job: paper preset, N = 48, default tolerances (rtol 1e-4, atol 1e-6), straight filament
tilted by 0.01 degree, 35 tau of physical time (through onset to 15 settled cycles, as in
wave 1), then ``describe`` of the last 15 cycles. Timed: the simulation (one core, warm) and
``describe`` separately. Baselines: scipy BDF given our analytic (W-)Jacobian on the same
semi-discretisation, the wave-1 default (``ros34pw2-wave1``), a calibration workload (200 LU
of a 300-square matrix). Errors: the TIME error alone at N = 48 against a time-converged run
at the same N (ndf at rtol 1e-10, checked against ros34pw2 at rtol 1e-8, an independent
method), and the total error against the wave-1 converged reference (N = 128, rtol 1e-6:
period 0.376888 s, advance 0.392807 mm, benchmarks/RESULTS.md). Per step: the integrator's
own wall time (``stats.wall_time``, without packaging the result) over accepted steps.

Usage: OPENBLAS_NUM_THREADS=1 python benchmarks/bench_stepping.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time

import numpy as np

import flutterswim as fs
from flutterswim.analysis.descriptors import describe

REF_PERIOD_S, REF_ADVANCE_MM = 0.376888, 0.392807


def job(method: str, n: int = 48, rtol: float = 1e-4) -> dict:
    P = fs.PAPER
    t0 = time.perf_counter()
    r = fs.simulate(P, 35 * P.tau, n_segments=n, method=method, rtol=rtol, atol=rtol * 1e-2)
    wall = time.perf_counter() - t0
    t1 = time.perf_counter()
    d = describe(r, n_last=15)
    wd = time.perf_counter() - t1
    st = r.stats
    return {"method": method, "n": n, "rtol": rtol, "sim_s": wall, "describe_s": wd, "steps": st.n_steps,
            "integrator_s": st.wall_time,
            "rejected": st.n_rejected, "lu": st.n_lu, "period_s": d.period_s, "advance_mm": d.advance_per_cycle_mm,
            "us_per_step": 1e6 * wall / max(1, st.n_steps)}


def calibration() -> float:
    rng = np.random.default_rng(0)
    a = rng.normal(size=(300, 300))
    import scipy.linalg as sla

    t0 = time.perf_counter()
    for _ in range(200):
        sla.lu_factor(a)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    print(f"machine: {cpu}; python {platform.python_version()}; numpy {np.__version__}", flush=True)
    for m in ("ndf", "ros34pw2", "ros34pw3"):  # warm-up: compiled kernels from the cache
        job(m, 12)
    ref = job("ndf", 48, 1e-10)
    print("time reference (N=48, ndf rtol 1e-10):", json.dumps(ref), flush=True)
    chk = job("ros34pw2", 48, 1e-8)
    print("independent check (N=48, ros34pw2 rtol 1e-8): period and advance differ by "
          f"{abs(chk['period_s'] / ref['period_s'] - 1):.1e}, {abs(chk['advance_mm'] / ref['advance_mm'] - 1):.1e}",
          flush=True)
    rows: dict[str, list[dict]] = {}
    cal: list[float] = []
    for _ in range(args.repeats):  # interleaved: each repeat runs every method back to back
        cal.append(calibration())
        for m in ("ndf", "ros34pw2", "ros34pw3", "bdf", "ros34pw2-wave1"):
            rows.setdefault(m, []).append(job(m))
    print(f"calibration (200 LU 300x300): min {min(cal):.3f} s, median {statistics.median(cal):.3f} s")
    summary = {}
    for m, rs in rows.items():
        w = [r["sim_s"] for r in rs]
        d = [r["describe_s"] for r in rs]
        r = rs[0]
        summary[m] = min(w)
        print(json.dumps({
            "method": m, "sim_min_s": min(w), "sim_median_s": statistics.median(w),
            "describe_min_s": min(d), "describe_median_s": statistics.median(d),
            "steps": r["steps"], "rejected": r["rejected"], "lu": r["lu"],
            "us_per_step_min": 1e6 * min(w) / r["steps"],
            "integrator_us_per_step_min": 1e6 * min(x["integrator_s"] for x in rs) / r["steps"],
            "time_err_period": abs(r["period_s"] / ref["period_s"] - 1),
            "time_err_advance": abs(r["advance_mm"] / ref["advance_mm"] - 1),
            "total_err_period": abs(r["period_s"] / REF_PERIOD_S - 1),
            "total_err_advance": abs(r["advance_mm"] / REF_ADVANCE_MM - 1)}), flush=True)
    print("space error of N=48 (time-converged run vs N=128 reference): period "
          f"{abs(ref['period_s'] / REF_PERIOD_S - 1):.2e}, advance {abs(ref['advance_mm'] / REF_ADVANCE_MM - 1):.2e}")
    for base in ("bdf", "ros34pw2-wave1", "ros34pw2", "ros34pw3"):
        print(f"ratio {base} / ndf (min over repeats): {summary[base] / summary['ndf']:.2f}x")
    print(f"ratio ndf / calibration: {summary['ndf'] / min(cal):.2f}")
    print(f"load average at the end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
