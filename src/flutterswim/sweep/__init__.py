"""Parameter sweeps: definition, execution backends, durable Zarr store, continuation, plots.

Entry point :func:`sweep`; see :mod:`.spec` for the grid syntax (``kappa_E_ratio=0:2:101``),
:mod:`.backends` for "serial", "processes", "dask", "dask-local".
"""

from .backends import SchedulerUnreachable, WorkerLost, available_backends, get_backend, register_backend
from .continuation import OnsetFit, hysteresis, onset_fit
from .point import VARIABLES, run_point
from .run import SweepInterrupted, open_sweep, sweep, to_dataset
from .spec import Axis, PointSettings, SweepSpec, parse_axis
from .store import SweepDefinitionError, SweepLockedError, SweepStore, SweepStoreError

__all__ = [
    "Axis", "OnsetFit", "PointSettings", "SchedulerUnreachable", "SweepDefinitionError", "SweepInterrupted",
    "SweepLockedError", "SweepSpec", "SweepStore", "SweepStoreError", "VARIABLES", "WorkerLost",
    "available_backends", "get_backend", "hysteresis", "onset_fit", "open_sweep", "parse_axis",
    "register_backend", "run_point", "sweep", "to_dataset",
]
