"""Design map (issue 10): two parameters on a 64 x 64 grid, each point to a settled stroke with
its descriptors, on 2 cores.

Axes: the activity kappa_E / kappa_E(paper) (0.5 to 2) and the viscosity mu / mu(paper)
(0.5 to 2, logarithmic), paper preset otherwise, N = 24 (the sweeps' resolution,
``flutterswim.defaults.SWEEP_N_SEGMENTS``), field along e1.

Every stroke on the map is a periodic orbit (Newton shooting, stable Floquet multipliers), not
a time-stepped state that merely looks periodic. Each row (one viscosity) runs from the
strongest activity down:
- the stroke of the previous point is the guess, and its flow (stages, step matrices,
  monodromy, parameter sensitivity) the warm start, of shooting at this point (natural
  continuation along the row: first-order predictor, chord steps, one exact pass);
- if there is no previous stroke, or shooting fails, or the orbit found is unstable, the point
  goes to the settle engine (:func:`flutterswim.settle.settle`: time stepping from the
  neighbour's state, or from the paper's tilt, until the oscillation is steady, then Newton
  shooting on it); its outcome is recorded (``limit_cycle``, ``straight``, ``bent_equilibrium``,
  ``not_periodic``, ...);
- a point whose straight state is linearly stable and where no stroke continues from the
  neighbour is ``straight`` (linear theory, :func:`flutterswim.orbits.leading_pair`).
Going down in activity, a stroke that survives below the Hopf curve shows a subcritical region
(bistability); the figure says the direction.

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
STEPS = 32  # Radau steps per period, as the branches (orbits.continuation.BRANCH_STEPS)
FIELDS = ("period_s", "advance_per_cycle_mm", "advance_along_field_mm", "speed_mm_s", "lateral_trailing_mm", "lateral_leading_mm",
          "nonreciprocity", "self_intersecting", "max_multiplier")
OUTCOMES = ("straight", "orbit", "not_periodic", "bent_equilibrium", "failed")


def _record(out: dict, i: int, orb) -> None:
    vals = {"period_s": orb.period, "advance_per_cycle_mm": orb.advance * 1e3,
            "advance_along_field_mm": orb.advance * math.cos(orb.swim_direction) * 1e3, "speed_mm_s": orb.speed * 1e3,
            "lateral_trailing_mm": orb.lateral_trailing * 1e3, "lateral_leading_mm": orb.lateral_leading * 1e3,
            "nonreciprocity": orb.nonreciprocity, "self_intersecting": float(orb.self_intersecting),
            "max_multiplier": orb.max_multiplier}
    for k in FIELDS:
        out[k][i] = float(vals[k])


def row(args: tuple[float, np.ndarray]) -> dict:
    """One row (viscosity factor), activity from the highest value down."""
    mu_f, ratios = args
    import flutterswim as fs
    from flutterswim._validate import ParameterError
    from flutterswim.initial import InitialState
    from flutterswim.orbits import OrbitNotFound, leading_pair
    from flutterswim.orbits.periodic import orbit_from_flow, solve_orbit
    from flutterswim.orbits.system import ShapeSystem
    from flutterswim.settle import settle

    P = fs.PAPER
    t0 = time.perf_counter()
    out = {k: [math.nan] * len(ratios) for k in FIELDS}
    out["outcome"] = ["straight"] * len(ratios)
    out["how"] = [""] * len(ratios)
    prev = None  # (u0, T, flow) of the previous point's stroke
    state = None  # the previous point's final simulated state
    for i in np.argsort(ratios)[::-1]:
        p = P.replace(mu=P.mu * mu_f, kappa_E=P.kappa_E * ratios[i])
        sysm = ShapeSystem.of(p, N_SEG)
        orb = None
        if prev is not None:
            # from the previous stroke of the row: with its flow's parameter sensitivity and
            # monodromy, a first-order predictor and chord steps (one exact pass, the last);
            # without them (a stroke from the settle engine), Newton from it
            try:
                u, T, fl, res, it = solve_orbit(sysm, prev[0], prev[1], steps=STEPS, warm=prev[2], max_newton=10,
                                                sensitivity=True)
                cand = orbit_from_flow(p, sysm, fl, res, it, STEPS)
                if cand.stable:
                    orb, prev = cand, (u, T, fl)
                    out["how"][i] = "continued"
            except (OrbitNotFound, FloatingPointError, np.linalg.LinAlgError):
                pass  # (StepFailure is a FloatingPointError)
        if orb is None:
            prev = None
            try:
                lam = leading_pair(p.groups, N_SEG)
            except ParameterError:
                lam = complex(-1.0, 0.0)
            if lam.real <= 0:
                state = None  # linearly stable and no stroke continues here: straight
                continue
            init = InitialState.straight() if state is None else InitialState.from_state(state, N_SEG)
            try:
                st = settle(p, initial=init, n_segments=N_SEG, n_cycles=3, frames_per_tau=25, steps=STEPS)
            except (ParameterError, RuntimeError, FloatingPointError) as exc:
                out["outcome"][i] = "failed"
                out.setdefault("errors", []).append(f"ratio {ratios[i]:.4g}: {exc}")
                state = None
                continue
            state = np.asarray(st.run.state_final, float)
            out["how"][i] = "settled"
            if st.outcome != "limit_cycle" or st.orbit is None:
                out["outcome"][i] = st.outcome if st.outcome in OUTCOMES else "not_periodic"
                continue
            orb = st.orbit
            prev = (orb.u0, orb.period_dimensionless, None)
        out["outcome"][i] = "orbit"
        _record(out, i, orb)
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
    panels = (("advance_along_field_mm", "advance per cycle along the field [mm]"), ("speed_mm_s", "speed [mm/s]"),
              ("period_s", "period [s]"), ("lateral_trailing_mm", "trailing end lateral peak-to-peak [mm]"),
              ("nonreciprocity", "nonreciprocity (stroke area)"))
    for ax, (key, label) in zip(axes.flat, panels):
        z = np.array([r[key] for r in rows], float)
        z = np.where(oc == OUTCOMES.index("orbit"), z, np.nan)
        if key == "advance_along_field_mm":  # signed: towards the field (red) or against it (blue)
            v = float(np.nanmax(np.abs(z)))
            m = ax.pcolormesh(x, y, z, shading="nearest", cmap="RdBu_r", vmin=-v, vmax=v)
        else:
            m = ax.pcolormesh(x, y, z, shading="nearest")
        fig.colorbar(m, ax=ax, label=label)
    ax = axes.flat[5]
    from matplotlib.colors import ListedColormap

    m = ax.pcolormesh(x, y, oc, shading="nearest",
                      cmap=ListedColormap(["0.85", "tab:green", "tab:orange", "tab:purple", "tab:red"]),
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
    fig.suptitle(f"Design map, {len(x)} x {len(y)} points, N = {N_SEG}: every stroke a stable periodic orbit (Newton "
                 f"shooting),\nrows continued from high to low activity; white: no stroke; "
                 f"{res['wall_s']:.0f} s on {res['workers']} cores ({n} points)")
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
    how = [h for r in res["rows"] for h in r["how"]]
    print(f"{args.size}x{args.size} map on {args.workers} workers: {res['wall_s']:.1f} s; outcomes {counts}; "
          f"{how.count('continued')} continued, {how.count('settled')} settled; load average {os.getloadavg()}",
          flush=True)
    res["counts"] = counts
    res["load_average"] = os.getloadavg()
    suffix = "" if args.size == 64 else f"_{args.size}"
    tmp = HERE / f"design_map{suffix}.json.tmp"
    tmp.write_text(json.dumps(res))
    os.replace(tmp, HERE / f"design_map{suffix}.json")
    plot(res, HERE / f"design_map{suffix}.png")


if __name__ == "__main__":
    main()
