"""CLI: ``flutterswim track INPUT --px-per-mm X --fps 50 --out track.nc [--roi x0,y0,x1,y1]``
and ``flutterswim track-batch FOLDER --px-per-mm X --fps 50 --out trials.csv [--plot fig3e.png]``."""

from __future__ import annotations

import sys
from pathlib import Path

from .._validate import ParameterError, direction_deg, positive, positive_int
from ..defaults import N_CYCLES_MOVIE
from .._json import dumps

__all__ = ["register"]


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "track", help="track a filament in a movie (TIFF stack, folder of frames, MP4/AVI) and save NetCDF",
        description="Segment the filament in every frame, fit a sub-pixel centreline with its tips, keep head "
                    "and tail by continuity, flag failing frames with their reason, and save a CF NetCDF.")
    p.add_argument("input", help="TIFF stack, folder of PNG/TIFF frames, or MP4/AVI movie")
    p.add_argument("--px-per-mm", type=float, required=True, help="image scale [pixels per mm]")
    p.add_argument("--fps", type=float, default=None, help="frame rate [1/s] (default: the movie's own)")
    p.add_argument("--times", default=None,
                   help="text/CSV file of the frames' times, one per frame (a camera's timestamps: dropped or "
                        "uneven frames); a header may name the column t, time, timestamp, elapsed time, ... with its "
                        "unit s, ms or us as a suffix or in brackets (time_ms, Time (ms), t [s]; default s)")
    p.add_argument("--out", default=None, help="NetCDF file (.nc); default track.nc, never one tracked from another input")
    p.add_argument("--roi", default=None, help="region of interest x0,y0,x1,y1 [pixels]")
    p.add_argument("--points", type=int, default=49, help="arc-length samples along the body (default 49)")
    p.add_argument("--start-end", choices=("left", "right", "top", "bottom"), default="left",
                   help="side of the s = 0 end in the first tracked frame (default left)")
    p.add_argument("--field-angle-deg", "--field-angle", type=float, default=0.0, dest="field_angle_deg",
                   help="field direction in the image [deg] from +x towards +y (rows down); default 0")
    p.add_argument("--dark-line", action="store_true",
                   help="the filament is darker than its background (bright field); default: brighter (fluorescence)")
    p.add_argument("--sigma", type=float, default=None,
                   help="the line's blur, Gaussian sigma [px] (default: measured on the first good frame)")
    p.add_argument("--kymograph", default=None, help="also draw the raw-frame kymographs (Fig. 3c) to this PNG")
    p.add_argument("--json", action="store_true", help="print the descriptors (as flutterswim describe --json)")
    p.add_argument("--last", type=int, default=N_CYCLES_MOVIE,
                   help=f"descriptors over the last N cycles (default {N_CYCLES_MOVIE})")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_track)

    q = subparsers.add_parser(
        "track-batch", help="track a folder of trials -> CSV of descriptors per trial (+ Fig. 3e)",
        description="Track every trial (TIFF stack, movie or folder of frames) of FOLDER; voltage and sample "
                    "from a sidecar <trial>.json or the file name (--pattern). Writes the fitting's CSV.")
    q.add_argument("folder")
    q.add_argument("--px-per-mm", type=float, default=None, help="image scale (unless in the sidecars)")
    q.add_argument("--fps", type=float, default=None, help="frame rate (unless in the sidecars or the movies)")
    q.add_argument("--out", default=None, help="CSV file; default trials.csv, never one of another folder's trials")
    q.add_argument("--pattern", default=None,
                   help="regular expression with groups (?P<voltage>) and (?P<sample>), searched in each trial's "
                        "name without its extension (a folder of frames: its name)")
    q.add_argument("--plot", default=None, help="per-voltage mean +- SEM figure (Fig. 3e) to this PNG")
    q.add_argument("--last", type=int, default=N_CYCLES_MOVIE,
                   help=f"descriptors over the last N cycles (default {N_CYCLES_MOVIE})")
    q.add_argument("--dark-line", action="store_true",
                   help="the filaments are darker than their background (unless a sidecar says dark_line)")
    q.add_argument("--field-angle-deg", "--field-angle", type=float, default=None, dest="field_angle_deg",
                   help="field direction in the image [deg] from +x towards +y (rows down), unless a sidecar says "
                        "field_angle_deg; default 0")
    q.add_argument("--start-end", choices=("left", "right", "top", "bottom"), default=None,
                   help="side of the s = 0 end in the first tracked frame, unless a sidecar says start_end; default left")
    q.add_argument("--quiet", action="store_true", help="no progress bar")
    q.set_defaults(func=_cmd_batch)


def _made_from(path: Path) -> list[str]:
    """The inputs a file of ours was made from: a track's input, a batch CSV's trials' folders."""
    if path.suffix.lower() == ".nc":
        from .._paths import netcdf_attrs

        src = netcdf_attrs(path).get("input")
        return [str(src)] if src else []
    import csv

    with open(path, newline="", encoding="utf-8") as f:
        return sorted({str(Path(r["trial"]).parent) for r in csv.DictReader(f) if r.get("trial")})


def _default_out(out: str | None, default: str, source: str) -> str:
    """``out`` if given; else ``default``, unless a file of ours there was made from another
    input (the fixed default name replaced the track of another movie, the CSV of another
    folder's trials, without a word)."""
    if out is not None:
        return out
    from .._paths import is_ours

    p = Path(default)
    if p.is_file() and is_ours(p):
        made = _made_from(p)
        same = [m for m in made if Path(m).resolve() == Path(source).resolve()]
        if made and not same:
            raise ParameterError(f"--out was not given, and the default {default!r} holds the results of "
                                 f"{made[0]!r}, not of {source!r}; give --out, or move that file away")
    return default


def _cmd_track(args) -> int:
    from .._paths import check_output_file
    from .netcdf import save_track
    from .track import failures, track

    positive_int("--last", args.last)  # checked before tracking, as the output paths
    field_angle = direction_deg("--field-angle-deg", args.field_angle_deg)
    from .netcdf import TRACK_TITLE

    out = check_output_file(_default_out(args.out, "track.nc", args.input), (".nc",), what="--out", kind=TRACK_TITLE)
    if args.kymograph:
        check_output_file(args.kymograph, (".png", ".pdf", ".svg"), what="--kymograph")
    times = None
    if args.times is not None:
        from .io import read_times

        times = read_times(args.times)
    tr = track(args.input, px_per_mm=args.px_per_mm, fps=args.fps, roi=args.roi, n_points=args.points,
               start_end=args.start_end, field_angle=field_angle, dark_line=args.dark_line,
               sigma=args.sigma, times=times,
               progress=not args.quiet)
    save_track(tr, out)
    m = tr.meta
    fails = failures(tr)
    counts: dict[str, int] = {}
    for _, _, why in fails:
        counts[why.split(":")[0]] = counts.get(why.split(":")[0], 0) + 1
    note = "; failed: " + ", ".join(f"{k} {v}" for k, v in counts.items()) if counts else ""
    print(f"tracked {m['n_frames'] - m['n_failed']} of {m['n_frames']} frames in {m['wall_time_s']:.2f} s; body length "
          f"{tr.length:.4g} mm, spread {100 * m['length_spread']:.2g}% (sd {m['length_std_px'] / m['px_per_mm']:.2g} mm)"
          f"{note}; wrote {out}", file=sys.stderr if args.json else sys.stdout)
    periodic = str((m.get("temporal") or {}).get("periodic", ""))
    if periodic.startswith("not done"):  # (its reason may say what to do: --times for dropped frames)
        print(f"note: periodic template {periodic}", file=sys.stderr if args.json else sys.stdout)
    if args.kymograph:
        from .kymograph import plot_raw_kymographs, raw_kymographs

        plot_raw_kymographs(raw_kymographs(args.input, tr), args.kymograph, tr=tr)
        print(f"wrote {args.kymograph}", file=sys.stderr if args.json else sys.stdout)
    if args.json:
        from ..analysis.descriptors import describe

        print(dumps(describe(tr, n_last=args.last).to_dict(), indent=2))
    return 0


def _cmd_batch(args) -> int:
    from functools import partial

    from ..cli import as_typed
    from .batch import DEFAULT_PATTERN, failures_path, track_batch

    positive_int("--last", args.last)  # checked before tracking (track_batch checks them again)
    for name, v in (("--px-per-mm", args.px_per_mm), ("--fps", args.fps)):
        if v is not None:
            positive(name, v)
    field = {} if args.field_angle_deg is None else {"field_angle": direction_deg("--field-angle-deg", args.field_angle_deg)}
    out, rows, failed = track_batch(args.folder, _default_out(args.out, "trials.csv", args.folder),
                                    px_per_mm=args.px_per_mm, fps=args.fps,
                                    pattern=DEFAULT_PATTERN if args.pattern is None else args.pattern, n_last=args.last, plot=args.plot,
                                    progress=not args.quiet, as_typed=partial(as_typed, args),
                                    dark_line=args.dark_line,
                                    **field,
                                    **({} if args.start_end is None else {"start_end": args.start_end}))
    for trial, why in failed:
        print(f"flutterswim track-batch: {trial}: {why}", file=sys.stderr)
    failed_csv = f"; the failures and their reasons in {failures_path(out)}" if failed else ""
    if not rows:  # (track_batch wrote no CSV of descriptors)
        earlier = " (the file there is an earlier run's)" if out.exists() else ""
        print(f"flutterswim track-batch: no trial was tracked ({len(failed)} failed){failed_csv}; {out} was not "
              f"written{earlier}", file=sys.stderr)
        return 1
    print(f"tracked {len(rows)} of {len(rows) + len(failed)} trials; wrote {out}" + (f" and {args.plot}" if args.plot else "")
          + failed_csv)
    # a failed trial fails the batch (exit 1), as a failed point fails a sweep; the others are kept
    return 1 if failed else 0
