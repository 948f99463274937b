"""``flutterswim reproduce``: wall time of a fresh --quick run (target < 5 min on 2 cores), of a
rerun with every target up to date, and with ``--full`` of one fresh --full run (target
< 60 min). Each fresh run writes into a new temporary folder.

    python benchmarks/bench_reproduce.py [--repeats 3] [--full]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def run(out: Path, mode: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "flutterswim", "reproduce", "--out", str(out), f"--{mode}", "--quiet"],
                   check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--full", action="store_true", help="also one --full run")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        fresh = [run(Path(tmp) / f"q{k}", "quick") for k in range(args.repeats)]
        rerun = [run(Path(tmp) / "q0", "quick") for _ in range(args.repeats)]
        print(f"--quick, fresh: min {min(fresh):.1f} s, median {statistics.median(fresh):.1f} s (target < 300 s)")
        print(f"--quick, rerun up to date: min {min(rerun):.2f} s, median {statistics.median(rerun):.2f} s")
        if args.full:
            full = run(Path(tmp) / "f", "full")
            print(f"--full, fresh: {full:.1f} s (target < 3600 s)")
    print(f"load average {os.getloadavg()[0]:.2f}, {os.cpu_count()} logical CPUs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
