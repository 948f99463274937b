"""One writer at a time: an exclusive advisory lock (``flock``) in a file beside a store or
folder, ``.<name>.lock``. Only the parent process holds it (close-on-exec); the file is removed
when the run ends if this run created it, or one a killed run left (signed)."""

from __future__ import annotations

import os
from pathlib import Path

from ._validate import ParameterError


class _Lock:
    """The open lock file; :meth:`close` removes it if it is still the file this process
    created, or one a killed run left (signed); another lock file there, or one replaced, is
    left alone."""

    def __init__(self, f, path: Path, created: bool):
        self.f, self.path, self.created = f, path, created

    def close(self) -> None:
        if self.f.closed:
            return
        try:
            # unlink while still holding the lock: a process that opened the old file meanwhile
            # finds it unlinked after it gets the lock and retries on a new one (acquire)
            if self.created and _same_file(self.f, self.path):
                self.path.unlink()
        except OSError:
            pass
        finally:
            self.f.close()

    def __enter__(self) -> "_Lock":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _same_file(f, path: Path) -> bool:
    try:
        a, b = os.fstat(f.fileno()), os.stat(path)
    except OSError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def acquire(path: str | os.PathLike, *, kind: str, noun: str, error: type[Exception] = ParameterError,
            then: str = "rerun the same command", inside: bool = False) -> _Lock:
    """Lock ``path`` (a store or folder, made or not; its parent exists) for this process;
    ``error`` (naming the ``kind`` of process, the ``noun`` and what to do ``then``) if another
    process holds it. ``inside``: the lock file is ``.lock`` in the folder ``path`` (which
    exists), for a folder whose parent may not be writable."""
    import fcntl

    path = Path(os.fspath(path))
    signature = f"flutterswim {kind} lock\n"
    # next to the store itself: a run through a symbolic link to it took another lock, and two
    # processes wrote one store at once
    real = Path(os.path.realpath(path))
    lock_path = real / ".lock" if inside else real.parent / f".{real.name}.lock"
    for _ in range(100):
        created = True
        try:
            f = open(lock_path, "x")  # Python opens files non-inheritable (O_CLOEXEC)
        except PermissionError:
            raise error(f"the lock file {str(lock_path)!r} of the {noun} {str(path)!r} cannot be made (permission "
                        "denied): give a writable folder") from None
        except FileExistsError:
            created = False
            try:
                f = open(lock_path, "a+")
            except FileNotFoundError:  # removed by its owner just now
                continue
        try:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            raise error(f"the {noun} {str(path)!r} is being written by another {kind} process (lock "
                        f"{str(lock_path)!r} is held); wait for it to finish or stop it, then {then}") from None
        if _same_file(f, lock_path):
            if created:  # signed: a lock a killed run leaves is known as ours and removed by the next
                f.write(signature)
                f.flush()
            else:
                f.seek(0)
                created = f.read(len(signature)) == signature
            return _Lock(f, lock_path, created)
        f.close()  # the file was removed by the process that held it: lock the current one
    raise error(f"the lock {str(lock_path)!r} of the {noun} {str(path)!r} keeps being replaced; another process is "
                "creating and removing it")
