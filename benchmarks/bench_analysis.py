"""Analysis cost (issue 10): ``describe`` of the paper job's last 15 cycles, and cycle detection
against the run's length (log-log slope: 1 is linear).

The runs: paper preset, N = 48, default tolerances and frames (50 per tau), from the 0.01 degree
tilt, for 35 tau (the paper job) and 70, 140, 280 tau. Timed warm, one core, min and median of
``--repeats``.

Usage: OPENBLAS_NUM_THREADS=1 python benchmarks/bench_analysis.py [--repeats 20]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np

import flutterswim as fs
from flutterswim.analysis.cycles import detect_cycles
from flutterswim.analysis.descriptors import describe


def timed(f, repeats: int) -> tuple[float, float]:
    f()
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return min(ts), statistics.median(ts)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=20)
    args = ap.parse_args()
    P = fs.PAPER
    out: dict = {}
    r = fs.simulate(P, 35 * P.tau, n_segments=48)
    mn, md = timed(lambda: describe(r, n_last=15), args.repeats)
    d = describe(r, n_last=15)
    out["describe_15_cycles"] = {"min_s": mn, "median_s": md, "frames": int(r.t.size), "cycles": d.n_cycles_detected}
    print(f"describe, 15 of {d.n_cycles_detected} cycles, {r.t.size} frames: min {1e3 * mn:.1f} ms, "
          f"median {1e3 * md:.1f} ms", flush=True)
    lengths = (35.0, 70.0, 140.0, 280.0)
    det = []
    for L in lengths:
        rr = fs.simulate(P, L * P.tau, n_segments=48)
        mn, md = timed(lambda rr=rr: detect_cycles(rr), max(3, args.repeats // 4))
        det.append(mn)
        print(f"detect_cycles, {L:g} tau ({rr.t.size} frames, {detect_cycles(rr).n_cycles} cycles): "
              f"min {1e3 * mn:.1f} ms, median {1e3 * md:.1f} ms", flush=True)
    slope = float(np.polyfit(np.log(lengths), np.log(det), 1)[0])
    print(f"detect_cycles cost against run length: log-log slope {slope:.2f}")
    out["detect_cycles"] = {"t_tau": lengths, "min_s": det, "slope": slope}
    out["load_average"] = os.getloadavg()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
