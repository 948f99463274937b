"""CLI: ``flutterswim branch PARAM=FROM:TO --out branch.nc`` (continuation of the stroke from
the Hopf point) and ``flutterswim plot-branch branch.nc``."""

from __future__ import annotations

__all__ = ["register"]


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "branch", help="stroke branch by continuation of periodic orbits from the Hopf point",
        description="Continue the stroke as a periodic orbit from the Hopf point of the straight "
                    "state to the far end of the range, and save it as NetCDF.")
    p.add_argument("range", help="parameter range like kappa_E_ratio=0.6:2 (also chi, eta_perp, kappa_E, tau, ...)")
    p.add_argument("--preset", default="paper", help="parameter preset (default: paper)")
    p.add_argument("--out", default="branch.nc", help="NetCDF of the branch (default branch.nc)")
    p.add_argument("--points", type=int, default=100, help="orbits along the branch (at least; default 100)")
    p.add_argument("--segments", type=int, default=None, help="segments N (default: the sweeps' resolution, 24)")
    p.add_argument("--steps", type=int, default=None, help="Radau steps per period, unchecked (default: 32, doubled along the branch where "
                   "doubling them would change the period or advance)")
    p.add_argument("--look-beyond", type=float, default=None,
                   help="follow the branch this fraction of the range past its end, for a fold that turns it "
                        "back into the range (default 0.2; 0: stop at the end)")
    p.add_argument("--plot", default=None, help="also draw the branch to this figure (.png, .pdf, .svg)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_branch)

    q = subparsers.add_parser("plot-branch", help="figure of a branch NetCDF (advance, period, lateral excursions)")
    q.add_argument("branch")
    q.add_argument("--out", default=None, help="PNG (default: next to the NetCDF)")
    q.set_defaults(func=_cmd_plot)


def _parse_range(text: str) -> tuple[str, float, float]:
    import math

    from .._validate import ParameterError

    name, sep, rng = text.partition("=")
    parts = rng.split(":")
    if not sep or len(parts) != 2:
        raise ParameterError(f"range={text!r} must look like NAME=FROM:TO, e.g. kappa_E_ratio=0.6:2")
    try:
        lo, hi = float(parts[0]), float(parts[1])
    except ValueError:
        raise ParameterError(f"range={text!r}: FROM and TO must be numbers") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ParameterError(f"range={text!r}: FROM and TO must be finite numbers")
    if lo == hi:
        raise ParameterError(f"range={text!r}: FROM and TO are equal; give a range, e.g. kappa_E_ratio=0.6:2")
    # the branch always starts at the Hopf point and runs the way it exists: the range bounds it
    # either way round (2:0.6 was refused as 'no stroke branch above the Hopf point 0.683', which
    # lies inside it)
    return name.strip(), min(lo, hi), max(lo, hi)


def _cmd_branch(args) -> int:
    from .. import defaults
    from .._paths import check_output_file
    from .._validate import ParameterError, positive_int, within
    from .._validate import n_segments as segments_checked
    from ..params import preset
    from .continuation import MAX_LOOK_BEYOND, MAX_POINTS, continue_orbits, short_of
    from .linear import hopf_bracket, hopf_point
    from .parameter import Axis

    name, lo, hi = _parse_range(args.range)
    if args.look_beyond is not None:
        within("--look-beyond", args.look_beyond, 0.0, MAX_LOOK_BEYOND, "times the range")
    if positive_int("--points", args.points, minimum=2) > MAX_POINTS:
        raise ParameterError(f"--points={args.points} is too many; at most {MAX_POINTS} orbits along a branch")
    params = preset(args.preset)
    axis = Axis(params, name)  # validates the name before any work
    for v in (lo, hi):  # and both ends (tau=-1:1 was continued from the Hopf point to 1)
        try:
            axis.at(v)
        except ParameterError as exc:
            raise ParameterError(f"range={args.range!r}: {name}={v:g} is not allowed ({exc})") from None
    from .continuation import BRANCH_TITLE

    out = check_output_file(args.out, (".nc",), kind=BRANCH_TITLE)
    if args.plot:
        check_output_file(args.plot, (".png", ".pdf", ".svg"), what="plot")
    n = defaults.SWEEP_N_SEGMENTS if args.segments is None else args.segments
    steps = args.steps  # None: from BRANCH_STEPS, doubled where the step screen asks
    # the Hopf point in the range typed, else between the base value and the range's nearer end
    # (kappa_E_ratio -2:-1 is the mirror branch from -0.68, not the one from +0.68), else near
    # the base value; continue towards the end of the range where the straight state is unstable
    n = segments_checked(n)
    base = axis.value()
    # a range on the other side of zero (negative fields) is looked at from the base value's
    # mirror: kappa_E_ratio=-0.3:-0.1 lies beyond the mirror branch's Hopf point -0.68, not
    # beyond +0.68 (the only one between it and the base value)
    ref = -base if 0.5 * (lo + hi) * base < 0 else base
    near = lo if abs(lo - ref) <= abs(hi - ref) else hi
    # (of two in the range, -1:1.2 holding the mirror branch's too, the one nearer the base value)
    bracket = (hopf_bracket(axis, n, lo, hi, prefer=base)
               or (None if near == ref else hopf_bracket(axis, n, ref, near)))
    hp = hopf_point(params, name, n_segments=n, bracket=bracket, start=ref)
    from .continuation import branch_side, unreachable
    from .normal_form import normal_form

    nf = normal_form(hp)
    side = branch_side(nf)
    to = hi if side > 0 else lo
    why = unreachable(nf, hp.value, to, name, mirror=not axis.positive)
    if why:  # (continue_orbits would name the Hopf point it finds from the base value)
        raise ParameterError(f"range={args.range!r} holds no stroke branch: {why}")
    extra = {} if args.look_beyond is None else {"look_beyond": args.look_beyond}
    import warnings

    from ..cli import as_typed

    with warnings.catch_warnings(record=True) as caught:  # the API's words, "(steps=)", said as typed
        br = continue_orbits(params, name, to, n_points=args.points, n_segments=n, steps=steps,
                             progress=not args.quiet, **extra)
    for w in caught:
        warnings.warn(as_typed(args, str(w.message)), w.category, stacklevel=1)
    ds = br.to_dataset()
    ds.attrs["n_inaccurate_orbits_comment"] = as_typed(args, ds.attrs["n_inaccurate_orbits_comment"])
    ds.attrs["range_start" if side > 0 else "range_end"] = lo if side > 0 else hi
    ds.attrs["range_start_units" if side > 0 else "range_end_units"] = axis.units
    from .._paths import write_netcdf

    write_netcdf(ds, out)
    if not min(lo, hi) <= hp.value <= max(lo, hi):  # (after the run: an error stands alone)
        import sys

        print(f"flutterswim branch: note: no Hopf point in {name}={lo:g}:{hi:g}; the branch starts at the "
              f"nearest one, {name}={hp.value:.6g}, outside the range", file=sys.stderr)
    if not axis.positive and min(lo, hi) < -hp.value < max(lo, hi):
        import sys

        # (a field reversed mirrors every stroke: one branch per sign of the field, one per run)
        far = lo if -hp.value < 0 else hi
        print(f"flutterswim branch: note: {name}={lo:g}:{hi:g} also holds the mirror branch from {name}="
              f"{-hp.value:.6g} (the field reversed: the same strokes mirrored, swimming the other way); "
              f"continue it with {name}={-hp.value:.6g}:{far:g}", file=sys.stderr)
    print(f"{out}: {len(br.values)} orbits from the Hopf point {name}={br.hopf_value:.6g} to {short_of(br.values[-1], to)} "
          f"({ds.attrs['bifurcation']}, l1={br.lyapunov_coefficient:.3g}) in {br.wall_time:.1f} s; {br.message}"
          + ("" if ds.attrs["multiplier_crossings"] == "none" else f"; stability changes at {ds.attrs['multiplier_crossings']}"))
    if args.plot:
        from .plot import plot_branch

        plot_branch(ds, args.plot, x_range=(min(lo, hi), max(lo, hi)))
        print(f"figure: {args.plot}")
    if br.values[-1] != to:  # the last corrector lands exactly on `to` when the range is reached
        import sys

        print(f"flutterswim branch: the branch stopped short of {name}={to:g} ({br.message}); the partial "
              f"branch ({len(br.values)} orbits up to {name}={short_of(br.values[-1], to)}) is saved in {out}", file=sys.stderr)
        return 1
    return 0


def _cmd_plot(args) -> int:
    from pathlib import Path

    from .._paths import check_output_file
    from .._validate import ParameterError
    from .plot import plot_branch

    src = Path(args.branch)
    if not src.is_file():
        raise ParameterError(f"branch={str(src)!r} is not a file")
    out = check_output_file(args.out or src.with_suffix(".png"), (".png", ".pdf", ".svg"))
    import xarray as xr

    try:
        ds = xr.open_dataset(src, engine="h5netcdf")
    except Exception as exc:  # noqa: BLE001 - any reader failure is a bad input file
        raise ParameterError(f"branch={str(src)!r} is not a readable NetCDF file ({exc.__class__.__name__})") from None
    if "parameter" not in ds.attrs or ds.attrs["parameter"] not in ds.coords:
        raise ParameterError(f"branch={str(src)!r} is not a flutterswim branch (no 'parameter' attribute)")
    plot_branch(ds, out)  # the range from the file's range_start/range_end and the branch itself
    print(f"figure: {out}")
    return 0
