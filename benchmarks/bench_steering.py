"""Steering (issue 13): the reduced model from the full model, turning radius against the
rotation rate next to U/Omega, the trap map, and closed- against open-loop path following.

Writes benchmarks/steering_radius.png, steering_trap.png, steering_square.png and
steering.json (the measured figures), and prints them. About 5 minutes on one core.

Usage: OPENBLAS_NUM_THREADS=1 python benchmarks/bench_steering.py
"""

from __future__ import annotations

import json
import math
import platform
import time
from pathlib import Path

import numpy as np

import flutterswim as fs
from flutterswim.steering.path import circle, square
from flutterswim.steering.plot import plot_steer
from flutterswim.steering.reduced import follows, identify, plot_radius, rotating_run
from flutterswim.steering.steer import steer
from flutterswim.steering.trap import TrapMap, plot_trap, tilt_basin, turn_basin

HERE = Path(__file__).resolve().parent
P = fs.PAPER
L = P.l


def trap(out: dict) -> None:
    tilts = np.array([0.01, 0.5, 1.0, 2.0, 3.0, 3.5, 4.0, 5.0, 7.0, 10.0])
    angles = np.array([5.0, 10.0, 20.0, 30.0, 45.0, 60.0, 90.0, 135.0, 180.0])
    rates = np.array([1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0])
    t1 = time.perf_counter()
    tb = tilt_basin(P, tilts)
    during = turn_basin(P, angles, rates, onset=4 * P.tau)  # turned during onset (4 tau)
    after = turn_basin(P, angles, rates, onset=12.0)  # turned once the stroke is established
    out["trap_map_s"] = time.perf_counter() - t1
    out["tilt_outcomes"] = dict(zip(map(float, tilts), map(str, tb)))
    out["turn_angles_deg"], out["turn_rates_deg_s"] = angles.tolist(), rates.tolist()
    out["turn_during_onset_outcomes"] = during.tolist()
    out["turn_after_onset_outcomes"] = after.tolist()
    plot_trap(TrapMap(tilts, tb, angles, rates, during, after, 4 * P.tau, 12.0), HERE / "steering_trap.png")
    print("trap map", out["trap_map_s"], out["tilt_outcomes"], flush=True)


def main() -> None:
    import argparse

    ap = argparse.ArgumentParser()
    ap.add_argument("--only", choices=("trap",), default=None, help="only the trap map (keeps the other results)")
    only = ap.parse_args().only
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")), "?")
    out: dict = {"machine": f"{cpu}; python {platform.python_version()}"}
    if only == "trap":
        out = {**json.loads((HERE / "steering.json").read_text()), **out}
        trap(out)
        (HERE / "steering.json").write_text(json.dumps(out, indent=1, default=lambda v: None))
        return
    t0 = time.perf_counter()
    red = identify(P, n_segments=24)
    out["identify_s"] = time.perf_counter() - t0
    out["reduced"] = {"U_mm_s": red.U * 1e3, "period_s": red.period, "k_per_s": red.k,
                      "omega_max_rad_s": red.omega_max, "bracket": list(red.omega_max_bracket),
                      "r_min_mm": red.r_min * 1e3, "r_min_bl": red.r_min / L}
    print(json.dumps(out["reduced"]), flush=True)

    fracs = (0.1, 0.2, 0.3, 0.45, 0.7, 0.9, 0.97)
    oms, radii, rows = [], [], []
    for f in fracs:
        om = f * red.omega_max
        ok, d = follows(rotating_run(P, om, turns=0.4, period=red.period), om, red.U, red.period, 12.0)
        rows.append({"omega_over_max": f, "follows": ok, "radius_mm": d.turning_radius * 1e3,
                     "U_over_Omega_mm": red.U / om * 1e3, "rel_err": d.turning_radius * om / red.U - 1,
                     "lag_deg": math.degrees(d.heading_lag), "speed_mm_s": d.speed_turning * 1e3})
        print(rows[-1], flush=True)
        if ok:
            oms.append(om)
            radii.append(d.turning_radius)
    above = 1.05 * red.omega_max
    out["above_step_out_follows"] = bool(follows(rotating_run(P, above, period=red.period), above, red.U,
                                                 red.period, 12.0)[0])
    out["radius_vs_omega"] = rows
    plot_radius(red, oms, radii, HERE / "steering_radius.png", lost=[] if out["above_step_out_follows"] else [above])

    trap(out)

    for name, make in (("square10", lambda p, h: square(10 * L, p, h)), ("circle2", lambda p, h: circle(2 * L, p, h))):
        for closed in (True, False):
            t2 = time.perf_counter()
            r = steer(P, make, red, closed_loop=closed, seed=11)
            key = f"{name}_{'closed' if closed else 'open'}"
            out[key] = {k: v for k, v in r.metrics.items() if not isinstance(v, list)}
            out[key]["reacquire_after_corner_s"] = r.metrics["reacquire_after_corner_s"]
            out[key]["wall_s"] = time.perf_counter() - t2
            print(key, json.dumps(out[key]), flush=True)
            if name == "square10":
                plot_steer(r, HERE / f"steering_square_{'closed' if closed else 'open'}.png")
    (HERE / "steering.json").write_text(json.dumps(out, indent=1, default=lambda v: None))


if __name__ == "__main__":
    main()
