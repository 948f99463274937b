"""Strict JSON for everything flutterswim writes or prints: numpy values as plain Python and
non-finite floats (an unmeasured standard error, a step error not checked) as ``null``.
Python's ``json`` writes NaN as the bare token ``NaN``, which is not JSON: ``jq``, browsers
and most other readers reject the whole document."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

__all__ = ["plain", "dumps"]


def plain(obj: Any) -> Any:
    """numpy scalars/arrays to plain Python, non-finite floats to None, complex to
    {"real", "imag"}; dict keys to str."""
    if isinstance(obj, dict):
        return {str(k): plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return plain(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (complex, np.complexfloating)):
        return {"real": plain(obj.real), "imag": plain(obj.imag)}
    return obj


def dumps(obj: Any, **kwargs: Any) -> str:
    """json.dumps of :func:`plain` (obj), strict (``allow_nan=False``)."""
    return json.dumps(plain(obj), allow_nan=False, **kwargs)
