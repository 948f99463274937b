"""A pool worker: a separate Python program (``python -m flutterswim.sweep._worker``).

It never imports the user's main module (a script without ``if __name__ == "__main__":``
works, also when piped into ``python -``), holds none of the parent's files (the store lock
stays with the parent), ignores Ctrl-C (the parent handles it) and dies with its parent:
``prctl(PR_SET_PDEATHSIG, SIGKILL)`` on Linux plus a watchdog thread that polls
``os.getppid()``. Protocol over two pipes (``multiprocessing.connection``): the parent sends
``sys.path`` first, then ``(key, pickled (fn, item))`` per task or None to stop; the worker
answers ``(key, "ok", result)`` or ``(key, "error", message)``.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
import threading
import time

POLL_S = 0.5


def _die_with_parent(parent: int) -> None:
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        pass
    if os.getppid() != parent:  # the parent died before prctl took effect
        os._exit(1)

    def watch() -> None:
        while True:
            if os.getppid() != parent:
                os._exit(1)
            time.sleep(POLL_S)

    threading.Thread(target=watch, name="flutterswim-parent-watchdog", daemon=True).start()


def main(argv: list[str]) -> int:
    parent, rfd, wfd = (int(a) for a in argv[:3])
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with_parent(parent)
    from multiprocessing.connection import Connection

    rd, wr = Connection(rfd, writable=False), Connection(wfd, readable=False)
    try:
        sys.path[:] = list(rd.recv())
    except EOFError:
        return 0
    try:
        from threadpoolctl import threadpool_limits

        threadpool_limits(limits=1)
    except ImportError:  # pragma: no cover
        pass
    while True:
        try:
            msg = rd.recv()
        except EOFError:
            return 0
        if msg is None:
            return 0
        key, payload = msg
        try:
            fn, item = pickle.loads(payload)
            reply = (key, "ok", fn(item))
        except Exception as exc:  # noqa: BLE001 - reported to the parent
            reply = (key, "error", f"{type(exc).__name__}: {exc}")
        try:
            wr.send(reply)
        except (pickle.PicklingError, TypeError, AttributeError) as exc:
            wr.send((key, "error", f"the result cannot be sent back: {type(exc).__name__}: {exc}"))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
