"""CLI: ``flutterswim reproduce --out DIR [--quick | --full] [--trials CSV] [--only NAME ...]``."""

from __future__ import annotations

import sys

__all__ = ["register"]


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "reproduce", help="every model figure and table of the paper, with data, a manifest and an HTML report",
        description="Regenerate the paper's model figures (Table 1, Figs. 4b-e, 5, 6a-d, Videos S4-S5, Fig. 3e "
                    "from a trials CSV) into a folder, skipping targets that are up to date.")
    p.add_argument("--out", required=True, help="output folder (new, empty, or an earlier reproduce folder)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--quick", dest="mode", action="store_const", const="quick",
                   help="coarse grids, short branch, small videos (the default; minutes)")
    g.add_argument("--full", dest="mode", action="store_const", const="full",
                   help="paper-resolution map (step 0.1), fine branch (N = 48), default simulator resolution")
    p.add_argument("--trials", default=None, help="trials CSV for Fig. 3e")
    p.add_argument("--only", nargs="+", default=None, metavar="TARGET", help="build only these targets (and their inputs)")
    p.add_argument("--force", action="store_true", help="rebuild even up-to-date targets")
    p.add_argument("--quiet", action="store_true", help="no per-target log")
    p.set_defaults(func=_cmd, mode="quick")


def _cmd(args) -> int:
    from .run import reproduce

    def log(msg: str) -> None:
        print(f"reproduce: {msg}", file=sys.stderr, flush=True)

    res = reproduce(args.out, mode=args.mode, trials=args.trials, targets=args.only, force=args.force,
                    log=None if args.quiet else log)
    n = len(res.records)
    skipped = [k for k, r in res.records.items() if r.status == "skipped"]
    built = sum(r.reran and r.status == "ok" for r in res.records.values())
    ok = n - len(res.failed) - len(skipped)
    print(f"{ok} of {n} targets ok ({built} built, {ok - built} up to date), {len(skipped)} skipped"
          + (f", FAILED: {', '.join(res.failed)}" if res.failed else "")
          + f"; {res.wall_time:.1f} s; report: {res.report}")
    return 0 if res.ok else 1
