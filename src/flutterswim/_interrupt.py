"""Telling an interrupt (Ctrl-C) from a failure."""

from __future__ import annotations

__all__ = ["interrupted"]


def interrupted(exc: BaseException) -> bool:
    """True if a KeyboardInterrupt is in the exception's chain (numba's dispatcher reports an
    interrupt inside a kernel as "SystemError: ... returned a result with an exception set")."""
    seen = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False
