"""Run a simulation until the stroke has settled on a limit cycle."""

from __future__ import annotations

from typing import Any

from ._validate import positive, positive_int
from .params import Groups, Parameters
from .result import SimulationResult, concatenate
from .simulate import simulate

__all__ = ["run_to_limit_cycle"]


def run_to_limit_cycle(
    params: Parameters | Groups,
    *,
    n_cycles: int = 15,
    t_max: float | None = None,
    chunk: float | None = None,
    tol: float = 1e-2,
    progress: bool = False,
    **simulate_kwargs: Any,
) -> SimulationResult:
    """Simulate in chunks until ``n_cycles`` cycles have followed the limit-cycle verdict
    of :func:`flutterswim.analysis.detect_cycles` (cycle-to-cycle change below ``tol``),
    or until ``t_max``. Times in s for :class:`Parameters`, in tau for :class:`Groups`.

    Defaults: ``chunk`` 10 tau, ``t_max`` 200 tau. The result's settings record
    ``limit_cycle`` (bool) and ``limit_cycle_time``; a filament that never settles (a
    straight, stable one has no cycles at all) runs to ``t_max``. The sweeps
    (:mod:`flutterswim.sweep.point`) add early stops for decaying and saturated points.
    """
    from .analysis import detect_cycles

    tau = params.tau if isinstance(params, Parameters) else 1.0
    n_cycles = positive_int("n_cycles", n_cycles)
    chunk = positive("chunk", 10.0 * tau if chunk is None else chunk)
    t_max = positive("t_max", 200.0 * tau if t_max is None else t_max)
    parts: list[SimulationResult] = []
    t0 = 0.0
    initial = simulate_kwargs.pop("initial", None)
    verdict: dict[str, Any] = {"limit_cycle": False, "limit_cycle_time": float("nan")}
    bar = _bar(progress, t_max / tau)
    while t0 < t_max - 1e-12 * tau:
        t1 = min(t0 + chunk, t_max)
        part = simulate(params, t1, t_start=t0, initial=initial, **simulate_kwargs)
        parts.append(part)
        if bar is not None:
            bar.update(round((t1 - t0) / tau, 3))
        if not part.ok or part.status == "stopped":
            break
        initial, t0 = part.final_state(), t1
        run = concatenate(parts)
        try:
            cyc = detect_cycles(run, tol=tol)
        except ValueError:
            continue
        if cyc.limit_cycle:
            after = int((cyc.starts[:-1] >= cyc.limit_cycle_time).sum())
            verdict = {"limit_cycle": True, "limit_cycle_time": float(cyc.limit_cycle_time)}
            if after >= n_cycles:
                break
            # run just long enough for the missing cycles (and a little of the next)
            period = float(cyc.periods[-1])
            chunk = max((n_cycles - after + 0.25) * period, 0.05 * tau)
    if bar is not None:
        bar.close()
    run = concatenate(parts)
    from dataclasses import replace

    return replace(run, settings={**run.settings, **verdict, "n_cycles_requested": n_cycles})


def _bar(enabled: bool, total: float):
    if not enabled:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=round(total, 3), unit="tau", desc="simulate")
