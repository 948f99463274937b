"""Steering by rotating the field (the paper's figure "Control of the swimmer trajectory").

The field direction turns at a constant rate once the stroke is established; the swimmer's
axis follows it and the mean trajectory is a circle of radius about U / Omega.

    python examples/steering_circle.py [--out out] [--rate 0.1] [--turns 1] [--small]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

import flutterswim as fs
from flutterswim._paths import atomic_path, check_files_in, check_output_dir, figure_metadata


def run(rate: float, turns: float, start: float, n_segments: int, frames: int):
    def direction(t: float) -> float:
        return rate * max(0.0, t - start)

    direction.__name__ = f"turn_at_{rate:g}_rad_per_s_after_{start:g}_s"
    t_end = start + turns * 2 * math.pi / rate
    return fs.simulate(fs.PAPER, t_end, field=fs.Field(direction=direction), n_segments=n_segments,
                       n_frames=frames, rtol=1e-4, atol=1e-6)


def figure(run, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    mm = 1e3
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(5.5, 7), gridspec_kw={"height_ratios": [3, 1]})
    for k in np.linspace(0, run.t.size - 1, 16).astype(int):
        ax.plot(run.x[k] * mm, run.y[k] * mm, color=plt.cm.Greens(0.3 + 0.7 * k / run.t.size), lw=1)
    ax.plot(run.x.mean(axis=1) * mm, run.y.mean(axis=1) * mm, color="gold", lw=2, label="centroid")
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(loc="best", frameon=False)
    ax2.plot(run.t, np.degrees(run.field_angle), color="tab:red")
    ax2.set_xlabel("t (s)")
    ax2.set_ylabel("field direction (deg)")
    fig.tight_layout()
    with atomic_path(path) as tmp:  # signed, so that a rerun may replace it
        fig.savefig(tmp, dpi=150, **figure_metadata(".png"))
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out")
    ap.add_argument("--rate", type=float, default=0.1, help="field rotation rate [rad/s]")
    ap.add_argument("--turns", type=float, default=1.0)
    ap.add_argument("--small", action="store_true", help="coarse and short (for the test suite)")
    args = ap.parse_args(argv)
    try:  # before computing: a folder inside an existing one, files of ours or new
        out = check_output_dir(args.out, what="--out")
        check_files_in(out, ("steering_run.nc", "steering_circle.png"), what="--out")
    except fs.ParameterError as exc:
        print(f"steering_circle.py: {exc}", file=sys.stderr)
        return 2
    out.mkdir(exist_ok=True)  # (its parent exists: check_output_dir)
    if args.small:
        res = run(args.rate, args.turns, start=8.0, n_segments=16, frames=600)
    else:
        res = run(args.rate, args.turns, start=8.0, n_segments=40, frames=3000)
    res.save(out / "steering_run.nc")
    figure(res, out / "steering_circle.png")
    heading = np.degrees(np.arctan2(np.sin(res.theta[-1]).mean(), np.cos(res.theta[-1]).mean()))
    print(f"final field direction {np.degrees(res.field_angle[-1]) % 360:.1f} deg, "
          f"body axis {heading % 360:.1f} deg; wrote {out / 'steering_circle.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
