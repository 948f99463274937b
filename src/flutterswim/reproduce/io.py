"""Deterministic, atomic writers for the reproduction targets.

Every file is written under a temporary name in its folder and renamed (``os.replace``), so
a SIGKILL leaves the old file or the new one. Data files carry no timestamps and no wall
times: two runs of the same code on the same inputs write byte-identical NetCDF and JSON.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

from .._json import plain as clean_json

__all__ = ["sha256_file", "write_json", "write_netcdf", "save_figure", "clean_json", "read_json"]


def sha256_file(path: str | os.PathLike) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_json(path: str | os.PathLike, obj: Any) -> Path:
    """Sorted keys, fixed indentation, strict JSON, atomic."""
    from .. import __version__
    from .._paths import atomic_path

    p = Path(path)
    body = {"generator": f"flutterswim {__version__}", **clean_json(obj)} if isinstance(obj, dict) else obj
    text = json.dumps(body, indent=1, sort_keys=True, allow_nan=False) + "\n"
    with atomic_path(p) as tmp:
        tmp.write_text(text)
    return p


def read_json(path: str | os.PathLike) -> Any:
    return json.loads(Path(path).read_text())


def write_netcdf(path: str | os.PathLike, ds, *, encoding: dict | None = None) -> Path:
    """CF-style NetCDF through h5netcdf (HDF5 object times are not tracked, so the bytes depend
    only on the data), atomic. Every variable must carry ``units`` and ``long_name``, the
    dataset a ``title``. ``encoding``: as :meth:`xarray.Dataset.to_netcdf`'s (compression)."""
    from .. import __version__
    from .._cf import cf_dataset
    from .._paths import write_netcdf as _write

    for name, var in {**ds.data_vars, **ds.coords}.items():
        missing = [a for a in ("units", "long_name") if a not in var.attrs]
        if missing:
            raise ValueError(f"variable {name!r} lacks the attributes {missing}")
    if not ds.attrs.get("title"):
        raise ValueError("the dataset has no title (global attribute)")
    ds = cf_dataset(ds.copy())
    ds.attrs = {"Conventions": "CF-1.10", "source": f"flutterswim {__version__} reproduce", **ds.attrs}
    return _write(ds, Path(path), encoding=encoding)


def save_figure(fig, path: str | os.PathLike, *, dpi: float = 130) -> Path:
    """PNG with the flutterswim signature and no date, atomic; closes nothing (Agg figures)."""
    from .._paths import atomic_path, figure_metadata

    p = Path(path)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png", bbox_inches="tight", **figure_metadata(".png"))
    return p
