"""``python -m flutterswim.demo``: the paper's representative experiment, end to end.

Simulates the paper preset from a straight filament tilted by 0.01 degree until 15 cycles
of the settled stroke, then writes to ``out/``: ``paper_run.nc`` (the run, reloadable with
``flutterswim.load``), ``paper_swimmer.png`` (shapes over one cycle and the tip
trajectory) and ``paper_descriptors.json``, and prints the period, net advancement per
cycle and mean speed in physical units.
"""

from __future__ import annotations

import argparse
import sys
import time

from . import defaults
from .limit_cycle import run_to_limit_cycle
from .params import preset
from ._json import dumps


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m flutterswim.demo", description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out", help="output folder (default: out)")
    ap.add_argument("--cycles", type=int, default=defaults.N_CYCLES,
                    help=f"settled cycles to simulate and average (default {defaults.N_CYCLES})")
    ap.add_argument("--segments", type=int, default=defaults.N_SEGMENTS,
                    help=f"spatial resolution N (default {defaults.N_SEGMENTS})")
    args = ap.parse_args(argv)
    from ._paths import atomic_write_text, check_files_in, check_output_dir
    from ._validate import ParameterError
    from .analysis.descriptors import describe
    from .plotting.figures import plot_ghosts

    try:
        out = check_output_dir(args.out, what="--out")  # before computing
        check_files_in(out, ("paper_run.nc", "paper_swimmer.png", "paper_descriptors.json"), what="--out")
    except ParameterError as exc:
        print(f"python -m flutterswim.demo: {exc}", file=sys.stderr)
        return 2
    out.mkdir(exist_ok=True)  # (its parent exists: check_output_dir)
    params = preset("paper")
    g = params.groups
    print(f"paper preset: eta_par={g.eta_par:.2f}, eta_perp={g.eta_perp:.2f}, chi={g.chi:.2f}")
    t0 = time.perf_counter()
    run = run_to_limit_cycle(params, n_cycles=args.cycles, n_segments=args.segments, rtol=defaults.RTOL,
                             atol=defaults.ATOL, progress=True)
    wall = time.perf_counter() - t0
    d = describe(run, n_last=args.cycles)
    run.save(out / "paper_run.nc")
    plot_ghosts(run, out / "paper_swimmer.png")
    from . import __version__

    atomic_write_text(out / "paper_descriptors.json",
                      dumps({"generator": f"flutterswim {__version__}", **d.to_dict()}, indent=2))
    print(f"simulated {run.t[-1]:.2f} s of swimming in {wall:.2f} s wall ({run.stats.n_steps} steps); "
          f"limit cycle from t = {d.limit_cycle_time_s:.2f} s")
    print(f"period                  {d.period_s:.4f} s  ({d.frequency_hz:.3f} Hz)")
    print(f"advancement per cycle   {d.advance_per_cycle_mm:.4f} mm  ({d.advance_per_cycle_bl:.4f} body lengths)")
    print(f"mean speed              {d.speed_mm_s:.4f} mm/s  ({d.speed_bl_s:.4f} body lengths/s)")
    print(f"lateral p2p, leading    {d.leading_lateral_p2p_mm:.4f} mm ({d.leading_end} end leads)")
    print(f"lateral p2p, trailing   {d.trailing_lateral_p2p_mm:.4f} mm")
    print(f"swimming direction      {round(d.direction_to_field_deg, 3) + 0.0:.3f} deg from the field "
          f"({'towards' if d.towards_field else 'against'} E, i.e. towards the cathode)")
    print(f"wrote {out / 'paper_run.nc'}, {out / 'paper_swimmer.png'}, {out / 'paper_descriptors.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
