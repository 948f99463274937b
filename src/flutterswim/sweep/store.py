"""Durable point-by-point sweep store (Zarr v3 directory, no pickle, JSON metadata).

Layout (k = point index, one chunk per point so every point is its own files):

- ``values`` (n_points, n_vars) float64: the point's variables (names in attrs ``variables``)
- ``message`` (n_points, 1024) uint8: UTF-8 failure reason, zero padded ("" if ok)
- ``failed`` (n_points,) int8, ``wall_time`` (n_points,) float64 [s]
- ``state`` (n_points, n_state) float64: final state (for continuation)
- ``done`` (n_points,) int8: written last; a point counts only once ``done == 1``

Only the parent process writes. A SIGKILL between the value writes and the ``done`` write
leaves the point undone: it is recomputed and overwritten on resume. The definition
(:class:`~flutterswim.sweep.spec.SweepSpec` as JSON) is in the group attributes; opening
a store with a different definition raises :class:`SweepDefinitionError`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from .._validate import ParameterError
from .spec import SweepSpec

__all__ = ["SweepStore", "SweepDefinitionError", "MESSAGE_BYTES"]

MESSAGE_BYTES = 1024
FORMAT = "flutterswim-sweep/1"


class SweepDefinitionError(ParameterError):
    """The store holds a different sweep than the one requested."""


def _acquire(path: Path):
    """Exclusive advisory lock next to the store: one writer at a time."""
    import fcntl

    lock_path = path.parent / f".{path.name}.lock"
    path.parent.mkdir(parents=True, exist_ok=True)
    f = open(lock_path, "a+")
    try:
        fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        f.close()
        raise SweepDefinitionError(
            f"the store {str(path)!r} is being written by another sweep process (lock {str(lock_path)!r}); "
            "wait for it to finish or stop it, then rerun to resume"
        ) from None
    return f


class SweepStore:
    def __init__(self, path: str | Path, group, spec: SweepSpec, variables: list[str]):
        self.path, self.group, self.spec, self.variables = Path(path), group, spec, variables
        self._lock = None
        self._arr = {k: group[k] for k in ("values", "message", "failed", "wall_time", "state", "done")}

    # ------------------------------------------------------------------ open/create
    @classmethod
    def open(cls, path: str | Path, spec: SweepSpec, variables: Sequence[str], n_state: int,
             *, overwrite: bool = False) -> "SweepStore":
        """Open (resume) or create the store and take its writer lock (released by
        :meth:`close` or when the process ends, SIGKILL included)."""
        lock = _acquire(Path(path))
        try:
            store = cls._open(path, spec, variables, n_state, overwrite=overwrite)
        except BaseException:
            lock.close()
            raise
        store._lock = lock
        return store

    def close(self) -> None:
        if self._lock is not None:
            self._lock.close()
            self._lock = None

    @classmethod
    def _open(cls, path, spec, variables, n_state, *, overwrite):
        import zarr

        path = Path(path)
        variables = list(variables)
        if path.exists() and not overwrite:
            g = zarr.open_group(str(path), mode="r+")
            attrs = dict(g.attrs)
            if attrs.get("format") == FORMAT and "spec" in attrs:
                stored = attrs["spec"]
                if stored != json.loads(spec.to_json()) or attrs.get("variables") != variables:
                    diffs = spec.diff(stored)
                    if attrs.get("variables") != variables:
                        diffs.append("variables: the point function returns a different set of variables")
                    raise SweepDefinitionError(
                        f"the store {str(path)!r} holds a different sweep (definition "
                        f"{attrs.get('fingerprint')}, requested {spec.fingerprint}); differences: "
                        + "; ".join(diffs[:8]) + ". Use another --out path, or overwrite=True "
                        "(--overwrite) to discard the stored points."
                    )
                return cls(path, g, spec, variables)
            if any(True for _ in g.array_keys()) and attrs.get("format") not in (None, FORMAT):
                raise SweepDefinitionError(f"{str(path)!r} is a Zarr group but not a flutterswim sweep store")
            # an incomplete creation (killed before the definition was written): start again
        return cls._create(path, spec, variables, n_state)

    @classmethod
    def _create(cls, path: Path, spec: SweepSpec, variables: list[str], n_state: int) -> "SweepStore":
        import zarr

        g = zarr.open_group(str(path), mode="w")
        n, nv = spec.n_points, len(variables)
        kw = {"compressors": None}
        g.create_array("values", shape=(n, nv), chunks=(1, max(nv, 1)), dtype="f8", fill_value=np.nan, **kw)
        g.create_array("message", shape=(n, MESSAGE_BYTES), chunks=(1, MESSAGE_BYTES), dtype="u1", fill_value=0, **kw)
        g.create_array("failed", shape=(n,), chunks=(1,), dtype="i1", fill_value=0, **kw)
        g.create_array("wall_time", shape=(n,), chunks=(1,), dtype="f8", fill_value=np.nan, **kw)
        g.create_array("state", shape=(n, max(n_state, 1)), chunks=(1, max(n_state, 1)), dtype="f8",
                       fill_value=np.nan, **kw)
        g.create_array("done", shape=(n,), chunks=(1,), dtype="i1", fill_value=0, **kw)
        # the definition last: a store without it is an unfinished creation
        g.attrs.update({"variables": variables, "n_state": int(n_state), "fingerprint": spec.fingerprint,
                        "spec": json.loads(spec.to_json()), "format": FORMAT})
        return cls(path, g, spec, variables)

    # ------------------------------------------------------------------ points
    def done_mask(self) -> np.ndarray:
        return np.asarray(self._arr["done"][:], dtype=np.int8) == 1

    def write_point(self, k: int, values: dict[str, float] | None, *, failed: bool, message: str,
                    wall_time: float, state: np.ndarray | None = None) -> None:
        """Write point k: values, message, flags, then mark it done (last)."""
        row = np.full(len(self.variables), np.nan)
        if values is not None:
            for i, name in enumerate(self.variables):
                v = values.get(name, math.nan)
                try:
                    row[i] = float(v)
                except (TypeError, ValueError):
                    row[i] = math.nan
        self._arr["values"][k] = row
        msg = np.zeros(MESSAGE_BYTES, np.uint8)
        b = message.encode("utf-8")[:MESSAGE_BYTES]
        b = b.decode("utf-8", errors="ignore").encode("utf-8")
        msg[: len(b)] = np.frombuffer(b, np.uint8)
        self._arr["message"][k] = msg
        self._arr["failed"][k] = 1 if failed else 0
        self._arr["wall_time"][k] = float(wall_time)
        st = self._arr["state"]
        srow = np.full(st.shape[1], np.nan)
        if state is not None:
            s = np.asarray(state, float).ravel()[: st.shape[1]]
            srow[: s.size] = s
        st[k] = srow
        self._arr["done"][k] = 1

    def state(self, k: int) -> np.ndarray | None:
        s = np.asarray(self._arr["state"][k])
        return None if not np.all(np.isfinite(s)) else s

    def value(self, k: int, j: int) -> float:
        return float(self._arr["values"][k, j])

    def failed(self, k: int) -> bool:
        return bool(self._arr["failed"][k])

    # ------------------------------------------------------------------ read
    def read(self) -> dict[str, Any]:
        msgs = np.asarray(self._arr["message"][:])
        return {
            "values": np.asarray(self._arr["values"][:]),
            "message": [bytes(m[m != 0]).decode("utf-8", errors="replace") for m in msgs],
            "failed": np.asarray(self._arr["failed"][:]).astype(bool),
            "wall_time": np.asarray(self._arr["wall_time"][:]),
            "done": self.done_mask(),
        }
