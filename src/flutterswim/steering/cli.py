"""CLI: ``flutterswim steer --preset paper --path square --side 10 --out steer.nc --metrics steer.json``."""

from __future__ import annotations

import math
import sys
from .._json import dumps

__all__ = ["register"]


#: the steer animation's speed, times real time (an 81 s circle in 10 s)
STEER_VIDEO_SPEED = 8.0

def register(subparsers) -> None:
    p = subparsers.add_parser("steer", help="follow a path by turning the field (closed or open loop)",
                              description="Path following on the full model: the field is turned by a controller "
                                          "that observes the swimmer at 50 fps with tracking noise and a one-frame "
                                          "delay (or by a pre-planned schedule with --open-loop).")
    p.add_argument("--preset", default="paper", help="parameter preset (default: paper)")
    p.add_argument("--path", choices=("square", "circle", "figure8", "waypoints"), default="square",
                   help="path to follow (default: square)")
    p.add_argument("--side", default=None, help="square side: body lengths, or with a unit (37mm, 3.7cm, 2bl); default 10")
    p.add_argument("--radius", default=None, help="circle radius: body lengths or with a unit (default 2)")
    p.add_argument("--size", default=None, help="figure-eight length: body lengths or with a unit (default 14: its tightest bend, 1.46 body lengths, is wider than the controller's turn, 1.39)")
    p.add_argument("--waypoints", default=None, help="CSV of x, y [body lengths, or the unit a header names: x_mm,y_mm] for --path waypoints")
    p.add_argument("--open-loop", action="store_true", help="pre-planned field schedule instead of feedback")
    p.add_argument("--noise-px", type=float, default=0.2,
                   help="tracking noise of the observed position, standard deviation [px] (default 0.2)")
    scale = p.add_mutually_exclusive_group()
    scale.add_argument("--um-per-px", type=float, default=14.0,
                       help="the observing camera's pixel size [um per px] (default 14)")
    scale.add_argument("--px-per-mm", type=float, default=None,
                       help="the same scale as track takes it [pixels per mm]: 1000 / --um-per-px")
    p.add_argument("--segments", type=int, default=24, help="segments of the filament (default 24)")
    p.add_argument("--seed", type=int, default=0, help="seed of the tracking noise (default 0)")
    p.add_argument("--out", default="steer.nc", help="NetCDF of the run (default steer.nc)")
    p.add_argument("--metrics", default="steer.json", help="JSON of the path-following metrics (default steer.json)")
    p.add_argument("--plot", default=None, help="figure of the path, the trajectory and the commanded field")
    p.add_argument("--animate", default=None, help="animation (.mp4 or .gif) with the rotating field arrow, at 8 "
                   "times real speed (at most 600 frames; the time stamps are the run's)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_steer)


def _units() -> dict:
    """Length units of the steering CLI: body lengths (None) and the analysis' units, plus cm."""
    from ..analysis.track import UNIT_SCALE

    return {"bl": None, "cm": 1e-2, **UNIT_SCALE}


def length(name: str, text, body_length: float) -> float:
    """A length in metres from ``text``: a number of body lengths, or a number with a unit
    (bl, m, cm, mm, um)."""
    import math
    import re

    from .._validate import ParameterError

    units = _units()
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*([a-zµ]*)\s*", str(text))
    unit = (m.group(2) or "bl") if m else None
    try:
        value = float(m.group(1)) if m else math.nan
    except ValueError:
        value = math.nan
    if unit not in units or not (math.isfinite(value) and value > 0):
        raise ParameterError(f"{name}={text!r} must be a length > 0: a number of body lengths, or with a unit "
                             f"({', '.join(units)})")
    return value * (body_length if units[unit] is None else units[unit])


#: the option that sets the size of each path, and its default
SIZE_OPTION = {"square": ("side", "10"), "circle": ("radius", "2"), "figure8": ("size", "14"),
               "waypoints": ("waypoints", None)}


def _check_path_options(args) -> None:
    """Refuse a size option of another path (``--path square --radius 2`` ignored --radius)."""
    from .._validate import ParameterError

    own = SIZE_OPTION[args.path][0]
    for path, (opt, _) in SIZE_OPTION.items():
        value = getattr(args, opt)
        if opt != own and value is not None:
            size = f"--{own} sets the {args.path}'s size" if args.path != "waypoints" else "--waypoints gives its points"
            raise ParameterError(f"--{opt}={value!r} is for --path {path}, not --path {args.path}: {size}")


def _old_steered(path) -> bool:
    """A steered run written before steered runs had their own title (a run's, with the
    steering attributes): steer's own, replaced as before."""
    from pathlib import Path

    from .._paths import is_ours, netcdf_attrs, netcdf_title
    from ..result import RUN_TITLE

    p = Path(path)
    return p.is_file() and is_ours(p) and netcdf_title(p) == RUN_TITLE and "steering_path" in netcdf_attrs(p)


#: the kind of result steer's metrics JSON names in its ``generator`` (not replaced by another's)
METRICS_KIND = "steer metrics"


def _cmd_steer(args) -> int:

    from .. import __version__
    from .._paths import atomic_write_text, check_output_file
    from .._validate import ParameterError, non_negative, positive, positive_int
    from ..params import preset
    from . import path as paths
    from .reduced import identify
    from .steer import ARRIVAL_BL, steer

    _check_path_options(args)
    from .steer import STEER_TITLE

    out = check_output_file(args.out, (".nc",), kind=STEER_TITLE if not _old_steered(args.out) else None)
    met = check_output_file(args.metrics, (".json",), what="--metrics", kind=METRICS_KIND)
    if args.plot:
        check_output_file(args.plot, (".png", ".pdf", ".svg"), what="--plot")
    if args.animate:
        check_output_file(args.animate, (".mp4", ".gif"), what="--animate")
    non_negative("--noise-px", args.noise_px)
    positive("--um-per-px", args.um_per_px)
    if args.px_per_mm is not None:
        args.um_per_px = 1000.0 / positive("--px-per-mm", args.px_per_mm)
    # the reduced model is identified from the paper's stroke as a periodic orbit: at 4 segments
    # Newton shooting does not find it (a failure after ~20 s); 5 and more do
    positive_int("--segments", args.segments, minimum=5)
    positive_int("--seed", args.seed, minimum=0)  # numpy's generator takes seeds >= 0
    params = preset(args.preset)
    L = params.l
    if args.path == "square":
        side = length("--side", SIZE_OPTION[args.path][1] if args.side is None else args.side, L)
        factory = lambda p, h: paths.square(side, p, h)  # noqa: E731
    elif args.path == "circle":
        r = length("--radius", SIZE_OPTION[args.path][1] if args.radius is None else args.radius, L)
        factory = lambda p, h: paths.circle(r, p, h)  # noqa: E731
    elif args.path == "figure8":
        size = length("--size", SIZE_OPTION[args.path][1] if args.size is None else args.size, L)
        factory = lambda p, h: paths.figure8(size, p, h)  # noqa: E731
    else:
        if not args.waypoints:
            raise ParameterError("--path waypoints needs --waypoints FILE.csv")
        factory = lambda p, h: paths.waypoints_csv(args.waypoints, L, p)  # noqa: E731
    probe = factory((0.0, 0.0), 0.0)  # a bad path (e.g. a waypoints CSV) is refused before computing
    # too long a path is refused after the periodic orbit (~5 s: the swimmer's speed), not after
    # the reduced model's identification (--radius 1e9 was refused after ~50 s)
    from ..orbits import periodic_orbit
    from .steer import check_duration

    orbit = periodic_orbit(params, n_segments=args.segments)
    check_duration(probe, orbit.speed, orbit.period, what=f"--path {args.path}")
    reduced = identify(params, n_segments=args.segments, orbit=orbit)
    import warnings

    with warnings.catch_warnings():  # (said below, as the run's failure)
        warnings.filterwarnings("ignore", message=r".*(were not swum|end was not reached)")
        res = steer(params, factory, reduced, closed_loop=not args.open_loop, noise_px=args.noise_px,
                    um_per_px=args.um_per_px, n_segments=args.segments, seed=args.seed, progress=not args.quiet)
    from .._cf import cf_dataset
    from .._paths import write_netcdf
    from .steer import steer_dataset

    write_netcdf(cf_dataset(steer_dataset(res, reduced)), out)  # the run, with its path and control settings
    m = {"generator": f"flutterswim {__version__} {METRICS_KIND}", **res.metrics}  # signed: a rerun may replace it
    m["reduced_model"] = {"U_mm_s": reduced.U * 1e3, "period_s": reduced.period, "k_per_s": reduced.k,
                          "omega_max_rad_s": reduced.omega_max, "r_min_mm": reduced.r_min * 1e3}
    atomic_write_text(met, dumps(m, indent=2))
    print(f"{out}: {res.path.name}, {'closed' if res.closed_loop else 'open'} loop: cross-track RMS "
          f"{m['cross_track_rms_bl']:.3f} body lengths (max {m['cross_track_max_bl']:.3f}), corner overshoot "
          f"{m['corner_overshoot_bl']:.3f}, trapped: {m['trapped']}, "
          f"{'completed' if m['completed'] else 'not completed'} ({100 * m['path_covered_fraction']:.0f} % of "
          f"the path covered); metrics in {met}"
          + ("" if m.get("path_feasible", True) else
             f" (the path bends down to a radius of {m['path_min_radius_bl']:.2f} body lengths, tighter than the "
             f"controller turns, {m['controller_min_radius_bl']:.2f}: not followed there)"))
    if args.plot:
        from .plot import plot_steer

        plot_steer(res, args.plot)
        print(f"figure: {args.plot}")
    if args.animate:
        from ..plotting.animation import animate

        animate(res.run, args.animate, speed=STEER_VIDEO_SPEED, max_frames=600, progress=not args.quiet)
        print(f"animation: {args.animate} ({STEER_VIDEO_SPEED:g} x real speed)")
    if m["trapped"]:
        print(trapped_reason(m), file=sys.stderr)
        return 1
    if not m["completed"]:
        short = (f"swam {m['path_covered_fraction']:.2f} of its {m['laps']:g} laps" if res.path.closed else
                 f"{100 * m['path_covered_fraction']:.0f} % covered, {m['end_miss_bl']:.2f} body lengths from its end at "
                 f"the closest, {ARRIVAL_BL:g} needed")
        print(f"failed: the swimmer did not {'swim the laps of' if res.path.closed else 'reach the end of'} the path "
              f"({short}) in up to three times the time its length takes; a path "
              "starting behind the swimmer or across its heading, bends tighter than it turns (path_feasible) "
              "or too much tracking noise can do this", file=sys.stderr)
        return 1
    return 0


def trapped_reason(m: dict) -> str:
    """The one line that says why a steering run failed: the swimmer was trapped."""
    at = m.get("trapped_at_s")
    when = f" at t = {at:.3g} s" if isinstance(at, float) and math.isfinite(at) else ""
    return (f"failed: the swimmer stopped{when}, trapped in a bent equilibrium (mean speed "
            f"{m['mean_speed_mm_s']:.3g} mm/s, swimming freely {m['reduced_model']['U_mm_s']:.3g} mm/s); a sudden "
            "turn of the field can do this: give the path gentler turns")
