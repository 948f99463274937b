"""The ``flutterswim`` command's entry point. It imports nothing heavy itself, so that a Ctrl-C
while the package and numpy/scipy load (the first half second) ends as any interrupt of the
command does: one line and exit status 130, not a traceback (a review of ``reproduce``)."""

import sys


def main() -> int:
    try:
        from flutterswim.cli import main as cli_main
    except KeyboardInterrupt:
        sys.stderr.write("flutterswim: interrupted while starting\n")
        return 130
    return cli_main()
