"""Telling an interrupt (Ctrl-C) from a failure: :func:`flutterswim_entry.interrupted`, which
the command's entry point needs before the package loads."""

from __future__ import annotations

from flutterswim_entry import interrupted

__all__ = ["interrupted"]
