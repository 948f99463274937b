"""The ``flutterswim`` command line: a thin layer over the Python API."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

PLOTS = ("ghosts", "swimmer", "kymograph", "descriptors", "summary")


def _simulate(args: argparse.Namespace) -> int:
    from .limit_cycle import run_to_limit_cycle
    from .params import preset
    from .simulate import simulate

    params = preset(args.preset)
    if args.kappa_E_ratio is not None:
        params = params.replace(kappa_E=params.kappa_E * args.kappa_E_ratio)
    opts = dict(n_segments=args.segments, rtol=args.rtol, atol=args.atol, progress=not args.quiet)
    if args.t_end is not None:
        run = simulate(params, args.t_end, **opts)
    else:
        run = run_to_limit_cycle(params, n_cycles=args.cycles, **opts)
    path = run.save(args.out)
    print(f"{run.status}: {run.message}; {run.t[-1]:.3f} s simulated, "
          f"{run.stats.n_steps} steps in {run.stats.wall_time:.2f} s; wrote {path}")
    return 0 if run.ok else 1


def _describe(args: argparse.Namespace) -> int:
    from .analysis.descriptors import describe
    from .result import load

    d = describe(load(args.run), n_last=args.last).to_dict()
    if args.json:
        print(json.dumps(d, indent=2))
    else:
        width = max(len(k) for k in d)
        for k, v in d.items():
            print(f"{k:<{width}}  {v:.6g}" if isinstance(v, float) else f"{k:<{width}}  {v}")
    return 0


def _plot(args: argparse.Namespace) -> int:
    from .plotting import figures
    from .result import load

    run = load(args.run)
    func = {"ghosts": figures.plot_ghosts, "swimmer": figures.plot_swimmer,
            "kymograph": figures.plot_kymographs, "descriptors": figures.plot_descriptors,
            "summary": figures.plot_summary}[args.kind]
    out = args.out or str(Path(args.run).with_suffix("")) + f"_{args.kind}.png"
    func(run, out)
    print(f"wrote {out}")
    return 0


def _animate(args: argparse.Namespace) -> int:
    from .plotting.animation import animate
    from .result import load

    animate(load(args.run), args.out, fps=args.fps)
    print(f"wrote {args.out}")
    return 0


def _stability(args: argparse.Namespace) -> int:
    from .stability import stability_figures

    res = stability_figures(args.out, step=args.step)
    print(f"wrote stability figures to {args.out}")
    return 0 if res is not None else 1


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="flutterswim", description="Soft filaments that swim by flutter.")
    sub = ap.add_subparsers(dest="command", required=True)

    p = sub.add_parser("simulate", help="simulate a preset to a settled stroke (or to --t-end) and save NetCDF")
    p.add_argument("--preset", default="paper")
    p.add_argument("--kappa-E-ratio", type=float, default=None, help="scale the preset's kappa_E")
    p.add_argument("--cycles", type=int, default=15, help="settled cycles to simulate")
    p.add_argument("--t-end", type=float, default=None, help="simulate to this time [s] instead")
    p.add_argument("--segments", type=int, default=48)
    p.add_argument("--rtol", type=float, default=1e-4)
    p.add_argument("--atol", type=float, default=1e-6)
    p.add_argument("--out", default="run.nc")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_simulate)

    p = sub.add_parser("describe", help="stroke descriptors of a saved run")
    p.add_argument("run")
    p.add_argument("--last", type=int, default=15, help="average over the last N cycles")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=_describe)

    p = sub.add_parser("plot", help="figures of a saved run")
    p.add_argument("run")
    p.add_argument("--kind", choices=PLOTS, default="ghosts")
    p.add_argument("--out", default=None)
    p.set_defaults(func=_plot)

    p = sub.add_parser("animate", help="MP4 or GIF of a saved run")
    p.add_argument("run")
    p.add_argument("out")
    p.add_argument("--fps", type=int, default=25)
    p.set_defaults(func=_animate)

    p = sub.add_parser("stability", help="stability map, neutral curve, bifurcation plots and eigenmodes")
    p.add_argument("--out", default="out/stability")
    p.add_argument("--step", type=float, default=0.1, help="map grid step in eta_perp and chi")
    p.set_defaults(func=_stability)

    _register_extensions(sub)
    return ap


#: Subpackages that add subcommands: each module has ``register(subparsers)``.
EXTENSIONS = (
    "flutterswim.sweep.cli",
    "flutterswim.orbits.cli",
    "flutterswim.tracking.cli",
    "flutterswim.steering.cli",
    "flutterswim.fitting.cli",
    "flutterswim.reproduce.cli",
)


def _register_extensions(sub) -> None:
    import importlib

    for name in EXTENSIONS:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            # the subpackage is absent, or an optional extra it needs is not installed
            absent = exc.name is not None and name.startswith(exc.name)
            extra_missing = exc.name is not None and exc.name.split(".")[0] != "flutterswim"
            if not (absent or extra_missing):
                raise
            continue
        module.register(sub)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    from ._validate import ParameterError

    try:
        return int(args.func(args) or 0)
    except ParameterError as exc:
        print(f"flutterswim {args.command}: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
