"""The ``flutterswim`` command line: a thin layer over the Python API.

Errors are one line on stderr: exit status 2 for bad input (parameters, files), 1 for a
failed computation, 130 for Ctrl-C; ``--debug`` shows the traceback.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from . import defaults
from ._interrupt import interrupted
from ._json import dumps

PLOTS = ("ghosts", "swimmer", "kymograph", "descriptors", "summary")
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit 2) and negative numbers read as values
    (``--rtol -1e-4`` reaches the parameter check instead of "expected one argument")."""

    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        self._negative_number_matcher = re.compile(
            r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?(,[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?)*$"
            r"|^-(inf|infinity|nan)(,.*)?$", re.IGNORECASE)  # also "--roi -5,0,100,100"

    def error(self, message: str):  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def add_subparsers(self, **kw):
        self.commands = super().add_subparsers(**kw)  # kept: an error names the options of its command
        return self.commands


def _still_and_bent(run) -> str:
    """A note when a fixed-time run ends without a stroke, bent away from the field: trapped in a
    bent equilibrium (a sudden turn of the field can do this), which "completed" did not say."""
    import numpy as np

    from .settle import STRAIGHT_ANGLE, SWIM_AMPLITUDE

    t = np.asarray(run.t)
    last = t >= t[-1] - 0.2 * (t[-1] - t[0])
    if t.size < 10 or last.sum() < 5:
        return ""
    rel = np.asarray(run.theta)[last] - np.asarray(run.field_angle)[last][:, None]
    swing = 0.5 * float(np.ptp(rel[:, 0]))  # the end angle's half-range over the last fifth
    bent = float(np.max(np.abs(np.angle(np.exp(1j * rel[-1])))))
    if swing < 0.1 * SWIM_AMPLITUDE and bent > STRAIGHT_ANGLE:
        return (f"; not swimming at the end: still (the end angle swings by {swing:.2g} rad over the last fifth) and "
                f"bent up to {np.degrees(bent):.0f} degrees off the field, trapped in a bent equilibrium")
    return ""


def _crossing(run) -> str:
    """A note when the body crosses itself over the last fifth of a run: the model has no contact
    between parts of the body, so such shapes are not physical. A field turning faster than the
    swimmer can follow, or turning while its stroke still grows, curls it up this way, and the run
    said only "completed" (its trap note looks for a still, bent filament)."""
    import numpy as np

    from .analysis.intersection import polyline_self_intersects

    t = np.asarray(run.t)
    last = t >= t[-1] - 0.2 * (t[-1] - t[0])
    if t.size < 10 or last.sum() < 5:
        return ""
    hit = polyline_self_intersects(np.asarray(run.x), np.asarray(run.y))
    if not hit[last].any():
        return ""
    note = (f"; the body crosses itself in {100 * float(np.mean(hit[last])):.2g} % of the frames of the last fifth "
            f"(first at t = {float(t[np.argmax(hit)]):.4g} s): the model has no contact between parts of the body, so these shapes "
            "are not physical")
    field = np.unwrap(np.asarray(run.field_angle, float))
    if field.size and np.ptp(field) > np.radians(5.0):
        note += (" (a swimmer curls up when the field turns faster than it can follow, its step-out rate Omega_max "
                 "that `flutterswim steer` reports, or while its stroke still grows: start turning after the onset, "
                 "--field-start)")
    return note


def _simulate(args: argparse.Namespace) -> int:
    from ._paths import check_output_file
    from ._validate import ParameterError
    from .params import preset

    if args.cycles is not None and args.t_end is not None:
        raise ParameterError(
            f"--cycles={args.cycles} and --t-end={args.t_end} were both given; --cycles runs to that many "
            "settled cycles of the limit cycle, --t-end for a fixed time: give one of them")
    from .result import RUN_TITLE

    out = check_output_file(args.out, (".nc",), what="--out", kind=RUN_TITLE)
    params = preset(args.preset)
    if args.kappa_E_ratio is not None:
        from ._validate import finite

        params = params.replace(kappa_E=params.kappa_E * finite("kappa_E_ratio", args.kappa_E_ratio))
    from ._validate import tolerance

    tolerance("--rtol", args.rtol)
    tolerance("--atol", args.atol)
    if args.t_end is not None:
        from ._validate import finite
        from .simulate import frame_count

        t_end = finite("--t-end", args.t_end)
        frames = frame_count(t_end / params.tau) if t_end > 0 else 0.0
        if frames > defaults.MAX_FRAMES:  # before anything is allocated (1e7 s grew to 6.6 GB in 15 s)
            rate = defaults.FRAMES_PER_TAU / params.tau
            raise ParameterError(
                f"--t-end={args.t_end!r} implies {frames:.3g} saved frames ({rate:.6g} per s, "
                f"{defaults.FRAMES_PER_TAU} per tau = {params.tau:g} s); at most {defaults.MAX_FRAMES} are saved: "
                f"give --t-end at most {(defaults.MAX_FRAMES - 1) / rate:.6g} s")
    opts = dict(n_segments=args.segments, rtol=args.rtol, atol=args.atol, progress=not args.quiet)
    from .steering.schedules import field_from_args

    field = field_from_args(args)
    if field is not None and args.t_end is None:
        raise ParameterError("a field schedule (--field-*) needs --t-end: the settle engine runs in a steady field")
    if getattr(args, "field_start", None) is not None and args.t_end is not None and args.field_start >= args.t_end:
        raise ParameterError(f"--field-start={args.field_start!r} is not before --t-end={args.t_end!r}: the field would "
                             "never change; start it earlier, or run longer")
    if args.t_end is not None:
        import warnings

        from .simulate import RunFailedWarning, simulate

        with warnings.catch_warnings():  # (a failure is said below, on one line)
            warnings.simplefilter("ignore", RunFailedWarning)
            run = simulate(params, args.t_end, field=field, **opts)
    else:
        from .limit_cycle import run_to_limit_cycle

        cycles = defaults.N_CYCLES if args.cycles is None else args.cycles
        run = run_to_limit_cycle(params, n_cycles=cycles, **opts)
    path = run.save(out)
    note = _still_and_bent(run) if args.t_end is not None else ""
    if args.t_end is None:  # the settle engine's verdict and its reason
        note = f" -> {run.settings.get('outcome', '?')}: {run.settings.get('outcome_reason', '')}"
        orb = run.settings.get("orbit")
        if orb:
            note += (f"; periodic orbit: period {orb['period']:.6g} s, advance {orb['advance'] * 1e3:.6g} mm "
                     f"per cycle, {'stable' if orb['stable'] else 'UNSTABLE'}")
    note += _crossing(run)
    line = (f"{run.status}: {run.message}; {run.t[-1]:.3f} s simulated, "
            f"{run.stats.n_steps} steps in {run.stats.wall_time:.2f} s; wrote {path}{note}")
    if not run.ok:  # a failure goes to stderr, with the command's name, as every error does
        print(f"flutterswim simulate: {line}", file=sys.stderr)
        return 1
    print(line)
    return 0


def _load_run_or_track(path: str):
    """A simulated run, or a movie tracked by ``flutterswim track`` (same analysis)."""
    from ._validate import ParameterError
    from .result import load

    try:
        return load(path)
    except ParameterError as exc:
        if "not a flutterswim run" not in str(exc):
            raise
        from .tracking.netcdf import load_track

        try:
            return load_track(path)
        except ParameterError:
            raise exc from None


def _describe(args: argparse.Namespace) -> int:
    from .analysis.descriptors import describe

    from ._validate import positive

    # checked before computing: --period 0 printed numpy's "invalid value" warning before the error
    kw = {} if args.period is None else {"period": positive("--period", args.period)}
    obj = _load_run_or_track(args.run)
    n_last = args.last
    if n_last is None:  # a run made with --cycles N is described over its N settled cycles
        asked = (getattr(obj, "settings", None) or {}).get("n_cycles_requested")
        n_last = (int(asked) if isinstance(asked, (int, float)) and asked >= 1 else
                  defaults.N_CYCLES_MOVIE if "px_per_mm" in (getattr(obj, "meta", None) or {}) else defaults.N_CYCLES)
    from ._validate import ParameterError

    try:
        desc = describe(obj, n_last=n_last, max_gap=args.max_gap, **kw)
    except ParameterError as exc:  # name the file (e.g. a track of too few frames), not for a bad option
        if re.match(r"(n_last|max_gap|period)=", str(exc)):
            raise
        raise ParameterError(f"run={args.run!r}: {exc}") from None
    d = desc.to_dict()
    if args.json:
        print(dumps(d, indent=2))
    else:  # the note once, on stderr below, as in JSON mode (it printed twice, on stdout and stderr)
        width = max(len(k) for k in d)
        for k, v in d.items():
            if k == "note":
                continue
            if v is None:
                v = "unknown"
            print(f"{k:<{width}}  {v:.6g}" if isinstance(v, float) else f"{k:<{width}}  {v}")
    if desc.note:
        print(f"flutterswim describe: note: {desc.note}", file=sys.stderr)
    return 0


def _plot(args: argparse.Namespace) -> int:
    from ._paths import check_output_file

    out = args.out or str(Path(args.run).with_suffix("")) + f"_{args.kind}.png"
    check_output_file(out, FIGURE_SUFFIXES, what="--out")
    from .plotting import figures

    run = _load_run_or_track(args.run)
    func = {"ghosts": figures.plot_ghosts, "swimmer": figures.plot_swimmer,
            "kymograph": figures.plot_kymographs, "descriptors": figures.plot_descriptors,
            "summary": figures.plot_summary}[args.kind]
    func(run, out)
    print(f"wrote {out}")
    return 0


def _animate(args: argparse.Namespace) -> int:
    from ._paths import check_output_file

    check_output_file(args.out, (".mp4", ".gif"), what="out")
    from .plotting.animation import animate

    animate(_load_run_or_track(args.run), args.out, fps=args.fps, progress=not args.quiet)
    print(f"wrote {args.out}")
    return 0


def _stability(args: argparse.Namespace) -> int:
    from ._paths import check_output_dir
    from .stability import stability_figures

    check_output_dir(args.out, what="--out")
    res = stability_figures(args.out, step=args.step, progress=not args.quiet,
                            dtype="float32" if args.float32 else "float64")
    print(f"wrote stability figures to {args.out}")
    return 0 if res is not None else 1


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    ap = _Parser(prog="flutterswim", description="Soft filaments that swim by flutter.")
    ap.add_argument("--version", action="version", version=f"flutterswim {__version__}")
    ap.add_argument("--debug", action="store_true", help="show the traceback of an error")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("simulate", help="simulate a preset to a settled stroke (or to --t-end) and save NetCDF")
    p.add_argument("--preset", default="paper", help="parameter preset (default: paper)")
    p.add_argument("--kappa-E-ratio", type=float, default=None, help="scale the preset's kappa_E")
    p.add_argument("--cycles", type=int, default=None,
                   help=f"settled cycles to simulate (default {defaults.N_CYCLES}; not with --t-end)")
    p.add_argument("--t-end", type=float, default=None, help="simulate to this time [s] instead of --cycles")
    p.add_argument("--segments", type=int, default=defaults.N_SEGMENTS, help=f"N (default {defaults.N_SEGMENTS})")
    p.add_argument("--rtol", type=float, default=defaults.RTOL, help=f"(default {defaults.RTOL:g})")
    p.add_argument("--atol", type=float, default=defaults.ATOL, help=f"(default {defaults.ATOL:g})")
    p.add_argument("--out", default="run.nc", help="NetCDF file (.nc; default run.nc; a file an earlier flutterswim run wrote is replaced, any other refused)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    from .steering.schedules import add_field_options

    add_field_options(p)
    p.set_defaults(func=_simulate)

    p = sub.add_parser("describe", help="stroke descriptors of a saved run")
    p.add_argument("run")
    p.add_argument("--last", type=int, default=None,
                   help=f"average over the last N cycles (default: the --cycles a run was made with, else {defaults.N_CYCLES}; "
                        f"{defaults.N_CYCLES_MOVIE} for a tracked movie, as the paper measured)")
    p.add_argument("--max-gap", type=float, default=0.25,
                   help="leave out cycles missing frames over more than this many periods (tracked movies; default 0.25)")
    p.add_argument("--period", type=float, default=None, metavar="SECONDS",
                   help="approximate stroke period, refined from the data (default: estimated; give it for a "
                        "record that swims in part only)")
    p.add_argument("--json", action="store_true", help="print the descriptors as JSON (null: not defined)")
    p.set_defaults(func=_describe)

    p = sub.add_parser("plot", help="figures of a saved run")
    p.add_argument("run")
    p.add_argument("--kind", choices=PLOTS, default="ghosts")
    p.add_argument("--out", default=None, help="figure file (.png, .pdf, .svg, .jpg; default <run>_<kind>.png beside the run)")
    p.set_defaults(func=_plot)

    p = sub.add_parser("animate", help="MP4 or GIF of a saved run")
    p.add_argument("run")
    p.add_argument("out", help="video file (.mp4 or .gif)")
    p.add_argument("--fps", type=float, default=25.0, help="video frames per second [1/s] (default 25)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_animate)

    p = sub.add_parser("stability", help="stability map, neutral curve, bifurcation plots and eigenmodes")
    p.add_argument("--out", default="stability", help="output folder (made in an existing one; default stability)")
    p.add_argument("--step", type=float, default=0.1, help="map grid step in eta_perp and chi (default 0.1, the paper's)")
    p.add_argument("--float32", action="store_true", help="store the map in single precision (a third to a half of the size, compressed)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_stability)

    _register_extensions(sub)
    for command in sub.choices.values():  # (as_typed: each command's own options)
        command.set_defaults(command_parser=command)
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


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


# the extra of pyproject.toml that brings each optional package (the import name)
_EXTRA_OF = {"xarray": "io", "h5netcdf": "io", "h5py": "io", "zarr": "io", "matplotlib": "plot",
             "imageio": "video", "imageio_ffmpeg": "video", "dask": "dask", "distributed": "dask",
             "numba": "fast", "jinja2": "report", "skimage": "track",
             "tifffile": "track"}

#: optional packages each command needs for what it writes, checked before it computes (a
#: command that computed for minutes, or tracked a whole movie, then could not write its file
#: wasted that time: a review met it with branch, simulate, track, stability and steer)
_NEEDS = {"simulate": ("xarray", "h5netcdf"), "branch": ("xarray", "h5netcdf"), "steer": ("xarray", "h5netcdf"),
          "stability": ("xarray", "h5netcdf", "matplotlib"), "sweep": ("zarr", "xarray"),
          "track": ("skimage", "xarray", "h5netcdf"), "track-batch": ("skimage",),
          "reproduce": ("jinja2", "matplotlib", "xarray", "h5netcdf")}


def _bad_backend(exc: BaseException) -> str:
    """The line for matplotlib refusing the backend named in the environment (bad input, exit 2;
    it failed as "ValueError: Key backend ...", exit 1), else "". Only a command that draws meets
    it: one that draws nothing runs whatever MPLBACKEND says."""
    import os

    name = os.environ.get("MPLBACKEND")
    if name and isinstance(exc, ValueError) and "Key backend" in str(exc):
        return (f"MPLBACKEND={name!r} (environment) is not a matplotlib backend; unset it, or set one such as Agg "
                "(the commands write their figures to files)")
    return ""


def _check_optional(args: argparse.Namespace) -> None:
    """Raise ModuleNotFoundError (one line, naming the extra: :func:`_describe_error`) for an
    optional package the command ``args`` will need, before it does any work."""
    import importlib.util

    need = list(_NEEDS.get(args.command, ()))
    if getattr(args, "plot", None) or getattr(args, "kymograph", None):
        need.append("matplotlib")
    if getattr(args, "animate", None):  # (steer --animate: a video of the run)
        need += ["matplotlib", "imageio"]
    if getattr(args, "scheduler", None) or getattr(args, "backend", None) in ("dask", "dask-local"):
        need.append("distributed")
    for name in need:
        if importlib.util.find_spec(name) is None:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)


#: Python API parameters whose option is not spelt --name-with-dashes
_OPTION_OF = {"n_segments": "--segments", "n_cycles": "--cycles", "n_last": "--last", "n_points": "--points",
              "targets": "--only", "out_dir": "--out"}


def _option(name: str, parser: argparse.ArgumentParser) -> str | None:
    """The option of ``parser`` for the Python API parameter ``name``, or None."""
    for option in ("--" + name.replace("_", "-"), _OPTION_OF.get(name)):
        if option in parser._option_string_actions:
            return option
    return None


def _as_typed(message: str, parser: argparse.ArgumentParser | None) -> str:
    """The message with its leading ``name=`` (a Python API parameter) spelt as the option of
    ``parser`` the user typed: ``px_per_mm=-3.0 must be > 0`` -> ``--px-per-mm=-3.0 must be > 0``
    (an option the API message names after it is not said twice), its advice "give name" as
    "give --name" and a parameter named in passing, "(name=)", as "(--name)"; unchanged where
    the command has no such option."""
    if parser is None:
        return message
    # a switch: "give dark_line=True (--dark-line)" is "give --dark-line" (its "=True" fails to parse)
    message = re.sub(r"\bgive ([A-Za-z_]\w*)=True(?: \((--[\w-]+)\))?",
                     lambda g: f"give {opt}" if (opt := _option(g.group(1), parser)) else g.group(0), message)
    message = re.sub(r"\bgive ([A-Za-z_]\w*)\b",
                     lambda g: f"give {_option(g.group(1), parser) or g.group(1)}", message)
    message = re.sub(r"\(([A-Za-z_]\w*)=\)", lambda g: f"({_option(g.group(1), parser) or g.group(1) + '='})",
                     message)
    m = re.match(r"([A-Za-z_]\w*)=", message)
    option = None if m is None else _option(m.group(1), parser)
    if option is None:
        return message
    message = option + message[len(m.group(1)):].replace(f" ({option})", "", 1)
    # a second parameter named with the first: "--rtol=1e-13 and atol=1e-14 are both ..."
    return re.sub(r"(?<= and )([A-Za-z_]\w*)(?==)", lambda g: _option(g.group(1), parser) or g.group(1), message)


def as_typed(args: argparse.Namespace, message: str) -> str:
    """``message``, in an API's words, said as the command ``args`` was parsed for is typed
    (:func:`_as_typed`): for what a command writes or warns itself (its errors are said so by
    :func:`main`)."""
    return _as_typed(message, getattr(args, "command_parser", None))


def _describe_error(exc: BaseException, parser: argparse.ArgumentParser | None = None) -> tuple[int, str]:
    """(exit status, one-line message) of an exception escaping a subcommand; ``parser``: the
    subcommand's, whose option spellings a bad parameter is named by."""
    from ._validate import ParameterError

    if isinstance(exc, ParameterError):
        return 2, _as_typed(_one_line(exc), parser)
    if isinstance(exc, ModuleNotFoundError) and exc.name and not exc.name.startswith("flutterswim"):
        top = exc.name.split(".")[0]
        extra = _EXTRA_OF.get(top, "all")
        return 1, (f"this command needs the optional package {top!r}; install it with "
                   f"pip install 'flutterswim[{extra}]' (or 'flutterswim[all]')")
    if isinstance(exc, (FileNotFoundError, IsADirectoryError, NotADirectoryError, PermissionError,
                        FileExistsError)):
        what = {FileNotFoundError: "does not exist", IsADirectoryError: "is a directory",
                NotADirectoryError: "has a part that is not a directory", PermissionError: "is not accessible "
                "(permission denied)", FileExistsError: "already exists"}[type(exc)]
        name = exc.filename if exc.filename is not None else ""
        return 2, f"{str(name)!r} {what}" if name else _one_line(exc)
    if isinstance(exc, OSError) and getattr(exc, "filename", None):
        return 2, f"{str(exc.filename)!r}: {_one_line(exc.strerror or exc)}"
    if isinstance(exc, MemoryError):
        return 1, "out of memory; reduce the problem size (grid, N, duration)"
    msg = _one_line(exc) or type(exc).__name__
    return 1, f"failed: {type(exc).__name__}: {msg}"


def _quiet_warnings() -> None:
    """Warnings as one line each (no source line), each said once: Python's registry of the
    warnings shown is reset whenever the warning filters change (a lazy import of scipy, any
    catch_warnings), so the same warning came again (branch a=1e-05:5e-05 said twice that a
    typed end is not slender)."""
    import warnings

    said: set[str] = set()

    def show(message, category, filename, lineno, file=None, line=None):
        text = _one_line(message)
        if text not in said:
            said.add(text)
            print(f"flutterswim: warning: {text}", file=sys.stderr if file is None else file)

    warnings.showwarning = show


def _written_note(paths: list) -> str:
    """The files a command interrupted had already replaced (a stability run left a new map beside
    the old figures, with only "interrupted" said)."""
    if not paths:
        return ""
    names = list(dict.fromkeys(str(p) for p in paths))
    shown = ", ".join(names[:6]) + (f" and {len(names) - 6} more" if len(names) > 6 else "")
    return f"; written before the interrupt: {shown} (any other output is as it was)"


def _quiet_unraisable() -> None:
    """After a Ctrl-C, objects the interrupt left half-closed (h5netcdf's file in the middle of a
    save) are finalised with errors Python prints as "Exception ignored in ..." (26 lines after
    the one-line message): the command's line is what is said. Only for the command itself,
    whose process ends: ``main`` called with arguments, in a process that goes on, keeps the hook."""
    sys.unraisablehook = lambda unraisable: None


def _interrupt_status() -> int:
    """130 for Ctrl-C, 143 (128 + 15) for SIGTERM."""
    from flutterswim_entry import TERMINATED

    return 143 if TERMINATED else 130


def main(argv: list[str] | None = None) -> int:
    program = argv is None  # (run as the command, not called in a process that goes on)
    if not program:
        return _main(argv, program)
    import signal

    from flutterswim_entry import handle_sigterm

    previous = handle_sigterm()  # (python -m flutterswim too)
    try:
        return _main(argv, program)
    finally:  # (a program calling main() keeps its own handler afterwards)
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _main(argv: list[str] | None, program: bool) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    if debug:
        argv = [a for a in argv if a != "--debug"]
    try:  # (building the parser imports the subcommands' modules: a Ctrl-C lands here too)
        ap = build_parser()
        args = ap.parse_args(argv)
    except KeyboardInterrupt:
        print("flutterswim: interrupted", file=sys.stderr)
        return _interrupt_status()
    except ImportError as exc:
        # a Ctrl-C while a compiled module initialises (scipy's HiGHS) surfaces as its
        # "ImportError: initialization failed", the interrupt its cause: it printed a traceback
        if not interrupted(exc):
            raise
        print("flutterswim: interrupted", file=sys.stderr)
        return _interrupt_status()
    if not debug:
        _quiet_warnings()
    from ._paths import write_mark, written_since

    first_write = write_mark()
    try:
        _check_optional(args)
        return int(args.func(args) or 0)
    except KeyboardInterrupt as exc:
        if debug:
            import traceback

            traceback.print_exc()
        elif program:
            _quiet_unraisable()
        msg = _one_line(exc) or "interrupted"
        print(f"flutterswim {args.command}: {msg}{_written_note(written_since(first_write))}", file=sys.stderr)
        return _interrupt_status()
    except BrokenPipeError:
        return 1
    except Exception as exc:  # noqa: BLE001 - every error becomes one line (traceback with --debug)
        from flutterswim_entry import TERMINATED

        # Ctrl-C inside a compiled kernel surfaces as its SystemError; a SIGTERM while numba
        # compiles is swallowed by its callback, and what fails next fails because of it
        if interrupted(exc) or TERMINATED:
            if not debug and program:
                _quiet_unraisable()
            print(f"flutterswim {args.command}: {'terminated (SIGTERM)' if TERMINATED else 'interrupted'}",
                  file=sys.stderr)
            return _interrupt_status()
        if debug:
            import traceback

            traceback.print_exc()
        backend = _bad_backend(exc)
        if backend:
            print(f"flutterswim {args.command}: {backend}", file=sys.stderr)
            return 2
        status, msg = _describe_error(exc, ap.commands.choices.get(args.command))
        hint = "" if status == 2 or debug else " (rerun with --debug for the traceback)"
        print(f"flutterswim {args.command}: {msg}{hint}", file=sys.stderr)
        return status


if __name__ == "__main__":
    raise SystemExit(main())
