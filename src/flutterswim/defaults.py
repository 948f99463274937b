"""The one place for the numerical defaults shared by the API, the CLI, the demo and the README.

At N_SEGMENTS = 48, RTOL = 1e-4 the paper's limit cycle has its period within 4e-4 and its
advancement per cycle within 4e-3 of a much finer run (N = 128, rtol 1e-6; measured 3.8e-4 and
3.5e-3), see ``benchmarks/RESULTS.md``. Near the onset the space error grows, roughly as
(shift of the discrete Hopf point) / (chi - chi_c): at 0.8 kappa_E,fit the advance is 8.5e-3 off
at N = 48, at 0.72 kappa_E,fit 2.5e-2; resolve such strokes with more segments (the error falls
as 1/N^2).

Sweeps use a coarser resolution per point (``SWEEP_N_SEGMENTS``) to cover many points; at
the paper's parameters it gives the period within ``SWEEP_PERIOD_ERROR`` and the advancement
per cycle within ``SWEEP_ADVANCE_ERROR`` (relative, against the same fine run; measured by
``tests/test_hardening_defaults.py``). Pass ``n_segments=N_SEGMENTS`` for the accuracy of
:func:`flutterswim.simulate`.
"""

from __future__ import annotations

#: Segments of the discretised filament.
N_SEGMENTS = 48
#: Relative and absolute tolerance of the time integrator.
RTOL = 1e-4
ATOL = 1e-6
#: Saved frames per relaxation time tau (runs of :func:`flutterswim.simulate`).
FRAMES_PER_TAU = 50
#: Settled cycles simulated by ``run_to_limit_cycle`` / ``flutterswim simulate`` and averaged
#: by ``describe``.
N_CYCLES = 15
#: cycles a tracked movie is described over (the paper's experiments: advance over 5 cycles)
N_CYCLES_MOVIE = 5

#: Sweep points: segments and saved frames per tau (a sweep point is analysed, not kept).
SWEEP_N_SEGMENTS = 24
SWEEP_FRAMES_PER_TAU = 25
#: Stated accuracy of a sweep point at SWEEP_N_SEGMENTS (relative errors at the paper's point).
SWEEP_PERIOD_ERROR = 2.5e-3
SWEEP_ADVANCE_ERROR = 2e-2

#: Largest sweep grid accepted (points), checked before anything is allocated.
MAX_SWEEP_POINTS = 100_000
#: Largest stability-map grid accepted (eta_perp x chi values).
MAX_MAP_POINTS = 20_000_000
#: Most frames a simulation saves (t_end x frame rate; 10,000 tau at FRAMES_PER_TAU), checked
#: before anything is allocated: about 1 GB in memory at N_SEGMENTS.
MAX_FRAMES = 500_000
#: Seconds to wait for a Dask scheduler before giving up.
SCHEDULER_TIMEOUT_S = 10.0

__all__ = [
    "N_SEGMENTS", "RTOL", "ATOL", "FRAMES_PER_TAU", "N_CYCLES", "N_CYCLES_MOVIE", "SWEEP_N_SEGMENTS", "SWEEP_FRAMES_PER_TAU",
    "SWEEP_PERIOD_ERROR", "SWEEP_ADVANCE_ERROR", "MAX_SWEEP_POINTS", "MAX_MAP_POINTS", "MAX_FRAMES", "SCHEDULER_TIMEOUT_S",
]
