"""CLI: ``flutterswim sweep AXIS... --out store.zarr`` and ``flutterswim plot-sweep store.zarr``.

``register(subparsers)`` adds both subcommands to an argparse parser."""

from __future__ import annotations

import sys

from ..defaults import N_SEGMENTS, SWEEP_ADVANCE_ERROR, SWEEP_PERIOD_ERROR
from .spec import PointSettings

__all__ = ["register", "main"]


def register(subparsers) -> None:
    p = subparsers.add_parser("sweep", help="parameter sweep (durable, resumable Zarr store)",
                              description="Run a parameter sweep; rerunning the same command resumes it.")
    p.add_argument("axes", nargs="+", help="axes like kappa_E_ratio=0:2:101, chi=60,70,80, tau=0.3")
    p.add_argument("--preset", default="paper", help="base parameter preset (default: paper)")
    p.add_argument("--out", required=True, help="Zarr store: a new one named *.zarr, or one of ours to resume")
    p.add_argument("--backend", default=None, help="processes (default), serial, dask, dask-local")
    p.add_argument("--scheduler", default=None, help="dask scheduler address tcp://host:port (implies --backend dask)")
    p.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    p.add_argument("--mode", choices=("grid", "list"), default="grid")
    p.add_argument("--continuation", action="store_true", help="start each point from the previous one, up then down")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing flutterswim store at --out (nothing else is ever replaced)")
    p.add_argument("--retry-failed", action="store_true",
                   help="resuming: compute again the points recorded as failed (by default they are kept)")
    p.add_argument("--no-progress", "--quiet", action="store_true", dest="no_progress",
                   help="no progress bar (failures are still listed)")
    st = PointSettings()
    for name, typ, help_ in (
            ("n-cycles", int, f"cycles averaged ({st.n_cycles})"), ("t-cap", float, f"time cap [tau] ({st.t_cap:g})"),
            ("n-segments", int, f"segments ({st.n_segments}; period within {SWEEP_PERIOD_ERROR:g}, advancement "
                                f"within {SWEEP_ADVANCE_ERROR:g} at the paper's point; {N_SEGMENTS} for the "
                                "accuracy of simulate)"),
            ("rtol", float, f"({st.rtol:g})"), ("atol", float, f"({st.atol:g})")):
        alias = {"n-cycles": ["--cycles"], "n-segments": ["--segments"]}.get(name, [])  # (as the other commands)
        p.add_argument(f"--{name}", *alias, type=typ, default=None, help=help_)
    p.add_argument("--plot", default=None, help="also save the sweep figure here (1-d sweeps)")
    p.set_defaults(func=_cmd_sweep)

    q = subparsers.add_parser("plot-sweep", help="figure of a sweep store (advancement and period)")
    q.add_argument("store")
    q.add_argument("--out", default=None, help="figure (.png, .pdf, .svg; default: the store's name with .png, "
                                                "next to it)")
    q.add_argument("--branch", default=None, help="up or down (continuation sweeps)")
    q.set_defaults(func=_cmd_plot)


def _cmd_sweep(args) -> int:
    from .run import sweep

    if args.plot:
        from .._paths import check_output_file

        check_output_file(args.plot, (".png", ".pdf", ".svg"), what="--plot")
        if args.mode == "grid" and len(args.axes) > 1:  # before any point runs
            from .._validate import ParameterError

            raise ParameterError(f"--plot={args.plot!r} draws 1-d sweeps; this grid has {len(args.axes)} axes "
                                 f"({' '.join(args.axes)}): sweep one axis, use --mode list, or leave out --plot")

    settings = {k: v for k, v in (("n_cycles", args.n_cycles), ("t_cap", args.t_cap), ("n_segments", args.n_segments),
                                  ("rtol", args.rtol), ("atol", args.atol)) if v is not None}
    backend = args.backend or ("dask" if args.scheduler else "processes")
    ds = sweep(args.axes, args.preset, out=args.out, backend=backend, workers=args.workers, scheduler=args.scheduler,
               mode=args.mode, continuation=args.continuation, settings=settings or None,
               progress=not args.no_progress, overwrite=args.overwrite, retry_failed=args.retry_failed)
    missing = int(ds.attrs["n_points"]) - int(ds.attrs["n_done"])  # a worker lost with its point: not saved
    print(f"{args.out}: {ds.attrs['n_done']}/{ds.attrs['n_points']} points, {ds.attrs['n_failed']} failed"
          + (f", {missing} not computed (rerun the same command to compute them)" if missing else ""))
    if args.plot:
        from .plot import plot_sweep

        plot_sweep(ds, args.plot)
        print(f"figure: {args.plot}")
    return 1 if ds.attrs["n_failed"] or missing else 0


def _cmd_plot(args) -> int:
    from .._paths import check_output_file
    from .plot import plot_sweep
    from .run import open_sweep

    from pathlib import Path

    ds = open_sweep(args.store)  # a store that is not a sweep's is named first, not the figure's name
    axes = [d for d in ds["done"].dims if d != "branch"]
    if len(axes) != 1:  # (before the figure's path is checked; plot_sweep's words are the API's)
        from .._validate import ParameterError

        raise ParameterError(f"store={args.store!r} is a sweep over {len(axes)} axes ({', '.join(axes)}); plot-sweep "
                             "draws 1-d sweeps (read a grid with xarray.open_zarr, or sweep one axis)")
    out = check_output_file(args.out or Path(args.store).with_suffix(".png"), (".png", ".pdf", ".svg"),
                            what="--out")  # (two stores in one folder: two figures)
    plot_sweep(ds, out, branch=args.branch)
    print(f"figure: {out}")
    return 0


def main(argv=None) -> int:
    """Standalone entry (``python -m flutterswim.sweep.cli sweep ...``): the full command line,
    with its one-line errors and exit codes."""
    from ..cli import main as cli_main

    return cli_main(argv)


if __name__ == "__main__":
    sys.exit(main())
