"""Periodic-orbit benchmarks (not a test): the stroke branch of the paper's Fig. 4b by
continuation, one orbit from a neighbouring one, and the kappa_E figure from the branch.

    .venv/bin/python benchmarks/bench_orbits.py [--repeat 3] [--figure benchmarks/sweep_kappa_E.png]

Each timing is repeated and reported as min and median, next to a fixed calibration
workload (LU of a 300 x 300 matrix, 200 times) measured in the same run, so that the
ratios carry over between machines. Default resolution: the sweeps' (N = 24), 32 Radau
steps per period (periodic_orbit's and the branches' default).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np
from bench_sweep import machine  # same folder: the one description of the machine


def calibration() -> float:
    import scipy.linalg as sla

    rng = np.random.default_rng(0)
    a = rng.normal(size=(300, 300)) + 300 * np.eye(300)
    t = time.perf_counter()
    for _ in range(200):
        sla.lu_factor(a)
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--figure", default=None, help="write the kappa_E branch figure here")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()

    import flutterswim as fs
    from flutterswim.orbits import continue_orbits, periodic_orbit
    from flutterswim.simulate import single_blas_thread

    out: dict = {"machine": machine()}
    with single_blas_thread():
        cal = [calibration() for _ in range(args.repeat)]
    out["calibration_s"] = {"min": min(cal), "median": statistics.median(cal)}

    # one orbit from a neighbouring one (kappa_E 1-3 % apart), N = 24 and N = 48; the
    # neighbour is periodic_orbit's result (it carries its warm start); one call first
    # (0.5 % apart) loads the compiled kernels and is not counted
    for n in (24, 48):
        base = periodic_orbit(fs.PAPER, n_segments=n)
        periodic_orbit(fs.PAPER.replace(kappa_E=fs.PAPER.kappa_E * 1.005), base, n_segments=n)
        ts, its = [], []
        for k in range(max(3, args.repeat)):
            p = fs.PAPER.replace(kappa_E=fs.PAPER.kappa_E * (1.0 + 0.01 * (k % 3 + 1)))
            t = time.perf_counter()
            o = periodic_orbit(p, base, n_segments=n)
            ts.append(time.perf_counter() - t)
            its.append(o.n_newton)
        t = time.perf_counter()
        periodic_orbit(fs.PAPER.replace(kappa_E=fs.PAPER.kappa_E * 1.02), base.compact(), n_segments=n)
        out[f"orbit_from_neighbour_N{n}_s"] = {"min": min(ts), "median": statistics.median(ts),
                                               "passes": its, "all_s": ts,
                                               "without_warm_start_s": time.perf_counter() - t}

    # the branch from the Hopf point to kappa_E ratio 2, at least 100 orbits
    ts = []
    br = None
    for _ in range(args.repeat):
        t = time.perf_counter()
        br = continue_orbits(fs.PAPER, "kappa_E_ratio", 2.0, n_points=100)
        ts.append(time.perf_counter() - t)
    ds = br.to_dataset()
    out["branch_to_2_s"] = {"min": min(ts), "median": statistics.median(ts), "orbits": int(ds.sizes["orbit"]),
                            "hopf_kappa_E_ratio": ds.attrs["hopf_kappa_E_ratio"],
                            "lyapunov_coefficient": ds.attrs["lyapunov_coefficient"],
                            "max_trivial_multiplier_error": float(ds.trivial_multiplier_error.max()),
                            "max_residual": float(ds.residual.max()),
                            "steps_per_period": {int(k): int(c) for k, c in
                                                 zip(*np.unique(ds.steps_per_period.values, return_counts=True))},
                            "max_step_error": float(ds.step_error.max())}
    out["ratios_to_calibration"] = {k: v["median"] / out["calibration_s"]["median"]
                                    for k, v in out.items() if isinstance(v, dict) and "median" in v and k != "calibration_s"}
    if args.figure:
        from flutterswim.orbits.plot import plot_branch

        plot_branch(ds, args.figure, x_range=(0.0, 2.0))
        ds.to_netcdf(os.path.splitext(args.figure)[0] + ".nc", engine="h5netcdf")
        out["figure"] = args.figure
    text = json.dumps(out, indent=2)
    print(text)
    if args.json:
        with open(args.json, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
