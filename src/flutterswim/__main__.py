"""``python -m flutterswim``: the command line (same as the ``flutterswim`` command)."""

from .cli import main

if __name__ == "__main__":
    raise SystemExit(main())
