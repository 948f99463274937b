"""Benchmark of the linear stability capability (not a timed test).

Run: .venv/bin/python benchmarks/bench_stability.py [--quick]
Prints a Markdown section for benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import time

import numpy as np

FULL_MAP = """
import time, resource, numpy as np
from flutterswim.stability import stability_map
stability_map(eta_perp=np.linspace(1, 350, 4), chi=np.linspace(-130, 130, 4))  # JIT cache load
t = time.perf_counter(); m = stability_map(step={step}); dt = time.perf_counter() - t
ok = m.iterations[1:] >= 0
print(dt, m.omega.shape[0], m.omega.shape[1], int((~ok).sum()), float(m.iterations[1:][ok].mean()),
      resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
np.save({out!r}, m.omega[::50, ::50])
"""


def cpu_model() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="coarser map (step 0.5) for a fast run")
    args = ap.parse_args()
    from flutterswim.stability import leading_eigenvalue, neutral_curve, stability_map
    from flutterswim.stability import _kernels
    from flutterswim.stability.newton import _newton_numpy

    step = 0.5 if args.quick else 0.1
    rows = []
    # 1. full map in a fresh process (wall time and peak RSS)
    out = "/tmp/_bench_map_sub.npy"
    res = subprocess.run([sys.executable, "-c", FULL_MAP.format(step=step, out=out)],
                         capture_output=True, text=True, check=True)
    dt, ne, nc, nfail, mean_it, rss = res.stdout.split()
    dt, ne, nc, nfail, mean_it, rss = float(dt), int(ne), int(nc), int(nfail), float(mean_it), float(rss)
    npts = ne * nc
    rows.append(("full map %dx%d (numba, %d threads)" % (ne, nc, os.cpu_count()), f"{dt:.2f} s",
                 "< 30 s", f"peak RSS {rss:.0f} MB (< 4 GB); {nfail} failed points beyond eta=0; "
                 f"mean {mean_it:.2f} Newton steps/point"))

    # 2. neutral curve
    neutral_curve(np.linspace(1, 350, 5))
    t = time.perf_counter()
    nc_ = neutral_curve(step=0.1)
    dtn = time.perf_counter() - t
    rows.append((f"neutral curve, {nc_.eta_perp.size} eta_perp values", f"{dtn:.3f} s", "< 2 s",
                 f"{int(np.isnan(nc_.chi_cr[1:]).sum())} NaN beyond eta=0"))

    # 3. one leading eigenvalue from scratch
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-130, 130, 60), rng.uniform(0.5, 350, 60)])
    leading_eigenvalue(10.0, 10.0)
    ts = []
    for chi, eta in pts:
        t = time.perf_counter()
        leading_eigenvalue(chi, eta)
        ts.append(time.perf_counter() - t)
    ts = np.array(ts) * 1e3
    rows.append(("leading eigenvalue, no guess (60 random points)", f"median {np.median(ts):.1f} ms",
                 "< 20 ms", f"max {ts.max():.1f} ms"))

    # 4. baseline: plain vectorised numpy Newton (companion eigvals) vs numba, same points/guesses
    m = stability_map(eta_perp=np.arange(0.1, 350.01, 0.7), chi=np.arange(-130, 130.01, 0.7))
    i = rng.integers(0, m.eta_perp.size, 20000)
    j = rng.integers(1, m.chi.size, 20000)
    ok = np.isfinite(m.omega[i, j]) & np.isfinite(m.omega[i, j - 1]) & (np.abs(m.chi[j]) > 1)
    i, j = i[ok], j[ok]
    chi = m.chi[j]
    eta = m.eta_perp[i]
    guess = m.omega[i, j - 1]  # previous chi value: as in root following
    guess = np.where(np.sign(m.chi[j - 1]) == np.sign(chi), guess, m.omega[i, j])
    t = time.perf_counter()
    w_np, it_np = _newton_numpy(guess, chi, eta, 1e-10, 30)
    t_np = time.perf_counter() - t
    steps_np = it_np[it_np > 0].sum()
    us_iter = t_np / steps_np * 1e6 if steps_np else float("nan")
    w_nb = np.empty_like(guess)
    it_nb = np.empty(guess.shape, dtype=np.int64)
    _kernels._newton_batch(guess[:8], chi[:8], eta[:8], 1e-10, 30, w_nb[:8], it_nb[:8])  # JIT/cache load
    t = time.perf_counter()
    _kernels._newton_batch(guess, chi, eta, 1e-10, 30, w_nb, it_nb)
    t_nb = time.perf_counter() - t
    both = (it_np >= 0) & (it_nb >= 0)
    agree = np.max(np.abs(w_np - w_nb)[both] / np.maximum(1, np.abs(w_nb[both])))
    nfail_b = int((~both).sum())
    per_point_np = t_np / guess.size
    per_point_nb = t_nb / guess.size
    extrap = per_point_np * npts
    rows.append((f"numpy baseline, {guess.size} points (same guesses)",
                 f"{us_iter:.1f} us/point/iter", "-",
                 f"{per_point_np * 1e6:.1f} us/point, {it_np[it_np > 0].mean():.2f} iter; extrapolated "
                 f"full map {extrap:.0f} s"))
    rows.append(("numba Newton, same points", f"{per_point_nb * 1e6:.2f} us/point", "-",
                 f"speed-up {per_point_np / per_point_nb:.0f}x per point; full map by following "
                 f"{dt:.1f} s vs {extrap:.0f} s baseline = {extrap / dt:.0f}x; roots agree to {agree:.1e} "
                 f"where both converge ({nfail_b} points from the crude 0.7-step guesses fail in both)"))

    print("### Linear stability (`flutterswim.stability`)\n")
    print(f"Machine: {cpu_model()}, {os.cpu_count()} cores; Python {platform.python_version()}, "
          f"numpy {np.__version__}, numba {'yes' if _kernels.HAVE_NUMBA else 'no'}.\n")
    print("| task | measured | target | notes |\n|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    main()
