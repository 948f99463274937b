"""Design map (issue 10): two parameters on a 64 x 64 grid, each point to a settled stroke with
its descriptors, on 2 cores.

Axes: the activity kappa_E / kappa_E(paper) (0.5 to 2) and the viscosity mu / mu(paper)
(0.5 to 2, logarithmic), paper preset otherwise, N = 24 (the sweeps' resolution,
``flutterswim.defaults.SWEEP_N_SEGMENTS``), field along e1.

Each point: the straight state's leading eigenvalue (:func:`flutterswim.orbits.leading_pair`)
says whether the filament flutters (growth > 0); if not, the point is ``straight`` (the Hopf
bifurcation is supercritical here, so no stroke coexists). A fluttering point is time-stepped
with the compiled NDF (the default integrator) in chunks of 10 linear periods, each row from
the strongest activity down, each point started from its neighbour's final state (the first
from the paper's 0.01 degree tilt); after each chunk :func:`detect_cycles` judges the chunk's
cycles, and the point is ``settled`` when the last 3 cycles agree in period, amplitude and
shape to 1 % (``limit_cycle``); then :func:`describe` of the last 5 cycles gives the stroke's
descriptors. At most 8 chunks (``unsettled`` after that, descriptors of the last chunk kept).
Periodic-orbit continuation was timed as the alternative: 0.3-0.35 s an orbit from a neighbour
at N = 24 (5 Newton steps) against ~30 ms here, and Newton fails in part of the map.

Rows are spread over 2 worker processes (one BLAS thread each).

Usage: OPENBLAS_NUM_THREADS=1 python benchmarks/bench_design_map.py [--size 64] [--workers 2]
Writes benchmarks/design_map.json and benchmarks/design_map.png.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from multiprocessing import get_context
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
N_SEG = 24
CHUNK_PERIODS = 10
MAX_CHUNKS = 8
FIELDS = ("period_s", "advance_per_cycle_mm", "speed_mm_s", "tip_lateral_p2p_mm", "nonreciprocity",
          "self_intersecting")
OUTCOMES = ("straight", "settled", "unsettled", "failed")


def row(args: tuple[float, np.ndarray]) -> dict:
    """One row (viscosity factor), activity from the highest value down."""
    mu_f, ratios = args
    import flutterswim as fs
    from flutterswim._validate import ParameterError
    from flutterswim.analysis.cycles import detect_cycles
    from flutterswim.analysis.descriptors import describe
    from flutterswim.initial import InitialState
    from flutterswim.orbits import leading_pair

    P = fs.PAPER
    t0 = time.perf_counter()
    out = {k: [math.nan] * len(ratios) for k in FIELDS}
    out["outcome"] = ["straight"] * len(ratios)
    out["chunks"] = [0] * len(ratios)
    out["steps"] = [0] * len(ratios)
    state = None
    for i in np.argsort(ratios)[::-1]:
        p = P.replace(mu=P.mu * mu_f, kappa_E=P.kappa_E * ratios[i])
        try:
            lam = leading_pair(p.groups, N_SEG)
        except ParameterError:
            lam = complex(-1.0, 0.0)
        if lam.real <= 0:
            state = None  # below onset: the next (weaker) points start from the tilt again
            continue
        chunk = CHUNK_PERIODS * 2 * math.pi / lam.imag * p.tau
        init = InitialState.straight() if state is None else InitialState.from_state(state, N_SEG)
        t = 0.0
        try:
            for c in range(MAX_CHUNKS):
                r = fs.simulate(p, t + chunk, t_start=t, initial=init, n_segments=N_SEG)
                out["steps"][i] += r.stats.n_steps
                out["chunks"][i] = c + 1
                t = r.t_final
                state = r.state_final
                init = InitialState.from_state(state, N_SEG)
                try:
                    settled = detect_cycles(r).limit_cycle
                except ParameterError:
                    settled = False
                if settled or c == MAX_CHUNKS - 1:
                    d = describe(r, n_last=5)
                    for k in FIELDS:
                        out[k][i] = float(getattr(d, k))
                    out["outcome"][i] = "settled" if settled else "unsettled"
                    break
        except (ParameterError, RuntimeError, FloatingPointError) as exc:
            out["outcome"][i] = "failed"
            out.setdefault("errors", []).append(f"ratio {ratios[i]:.4g}: {exc}")
            state = None
    out["wall_s"] = time.perf_counter() - t0
    out["mu_factor"] = float(mu_f)
    return out


def run_map(size: int, workers: int) -> dict:
    ratios = np.linspace(0.5, 2.0, size)
    mus = np.geomspace(0.5, 2.0, size)
    t0 = time.perf_counter()
    with get_context("fork").Pool(workers) as pool:
        rows = list(pool.imap(row, [(m, ratios) for m in mus], chunksize=1))
    wall = time.perf_counter() - t0
    return {"size": size, "workers": workers, "wall_s": wall, "ratios": ratios.tolist(), "mu_factors": mus.tolist(),
            "rows": rows}


def plot(res: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x, y = np.array(res["ratios"]), np.array(res["mu_factors"])
    rows = res["rows"]
    oc = np.array([[OUTCOMES.index(o) for o in r["outcome"]] for r in rows])
    fig, axes = plt.subplots(2, 3, figsize=(14, 8), constrained_layout=True)
    panels = (("advance_per_cycle_mm", "advance per cycle [mm]"), ("speed_mm_s", "speed [mm/s]"),
              ("period_s", "period [s]"), ("tip_lateral_p2p_mm", "tip lateral peak-to-peak [mm]"),
              ("nonreciprocity", "nonreciprocity (stroke area)"))
    for ax, (key, label) in zip(axes.flat, panels):
        z = np.array([r[key] for r in rows], float)
        z = np.where(oc == OUTCOMES.index("settled"), z, np.nan)
        m = ax.pcolormesh(x, y, z, shading="nearest")
        fig.colorbar(m, ax=ax, label=label)
    ax = axes.flat[5]
    from matplotlib.colors import ListedColormap

    m = ax.pcolormesh(x, y, oc, shading="nearest", cmap=ListedColormap(["0.85", "tab:green", "tab:orange", "tab:red"]),
                      vmin=-0.5, vmax=len(OUTCOMES) - 0.5)
    cb = fig.colorbar(m, ax=ax, ticks=range(len(OUTCOMES)))
    cb.ax.set_yticklabels(OUTCOMES)
    si = np.array([r["self_intersecting"] for r in rows], float)
    ax.contour(x, y, np.nan_to_num(si), levels=[0.5], colors="k", linewidths=0.8)
    ax.set_title("outcome (black: self-intersecting strokes)")
    for ax in axes.flat:
        ax.set_yscale("log")
        ax.set_xlabel("kappa_E / kappa_E(paper)")
        ax.set_ylabel("mu / mu(paper)")
    n = len(x) * len(y)
    fig.suptitle(f"Design map, {len(x)} x {len(y)} points, N = {N_SEG}: each point time-stepped to a settled stroke "
                 f"(white: straight or not settled); {res['wall_s']:.0f} s on {res['workers']} cores ({n} points)")
    tmp = path.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=100)
    os.replace(tmp, path)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    import flutterswim as fs

    fs.simulate(fs.PAPER, 2 * fs.PAPER.tau, n_segments=N_SEG)  # compiled kernels into the cache before forking
    res = run_map(args.size, args.workers)
    oc = [o for r in res["rows"] for o in r["outcome"]]
    counts = {o: oc.count(o) for o in OUTCOMES}
    steps = sum(sum(r["steps"]) for r in res["rows"])
    print(f"{args.size}x{args.size} map on {args.workers} workers: {res['wall_s']:.1f} s; outcomes {counts}; "
          f"{steps} steps; load average {os.getloadavg()}", flush=True)
    res["counts"] = counts
    res["load_average"] = os.getloadavg()
    suffix = "" if args.size == 64 else f"_{args.size}"
    tmp = HERE / f"design_map{suffix}.json.tmp"
    tmp.write_text(json.dumps(res))
    os.replace(tmp, HERE / f"design_map{suffix}.json")
    plot(res, HERE / f"design_map{suffix}.png")


if __name__ == "__main__":
    main()
