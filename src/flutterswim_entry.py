"""The ``flutterswim`` command's entry point. It imports nothing heavy itself, so that a Ctrl-C
while the package and numpy/scipy load (the first half second) ends as any interrupt of the
command does: one line and exit status 130, not a traceback (a review of ``reproduce``)."""

import sys


def interrupted(exc: BaseException) -> bool:
    """True if a KeyboardInterrupt is in the exception's chain: a compiled module interrupted
    while it initialises raises ImportError from it, numba's dispatcher reports an interrupt
    inside a kernel as "SystemError: ... returned a result with an exception set". Here, not in
    the package, so that the entry point has it before the package loads
    (``flutterswim._interrupt`` re-exports it)."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


#: set when SIGTERM arrived: the command then exits 143 (128 + 15), after the cleanup an
#: interrupt gets
TERMINATED = []


def _on_sigterm(signum, frame) -> None:
    TERMINATED.append(signum)
    # (raised inside a callback, numba's compiler among them, the interrupt is printed as "Exception
    # ignored ..." with its traceback: the command's one line says it)
    sys.unraisablehook = lambda unraisable: None
    raise KeyboardInterrupt("terminated (SIGTERM)")


def handle_sigterm():
    """SIGTERM (kill, timeout, a batch system's time limit, docker stop) ends the command as
    Ctrl-C does: partial files removed, one line. It had killed the process at once and left
    hidden partial files (31 MB of a run) that no later run removed. Returns the handler it
    replaced (None: none replaced, outside the main thread)."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        TERMINATED.clear()  # (a program's earlier run that was terminated: not this one)
        return signal.signal(signal.SIGTERM, _on_sigterm)
    return None


def main() -> int:
    handle_sigterm()
    try:
        from flutterswim.cli import main as cli_main
    except (KeyboardInterrupt, ImportError) as exc:
        if not interrupted(exc):
            raise
        sys.stderr.write("flutterswim: interrupted while starting\n")
        return 143 if TERMINATED else 130
    return cli_main()
