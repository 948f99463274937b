"""Calibration of the reported uncertainty: refits of synthetic data drawn at given SEMs.

Data y_j = model(x_true) + sem * N(0, 1) are fitted back (default cost, start at the truth);
the spread of log(B, tau, kappa_E) over the refits is what the reported 1-sigma claims to be.
Refits are independent, so they run in parallel on a sweep backend; each worker keeps its
own descriptor model (orbits cached from its previous refits).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import ParameterError, positive_int

__all__ = ["Calibration", "calibrate", "refit_task"]

_MODELS: dict = {}  # per worker process: one descriptor model per (base, tip, resolution)


@dataclass(frozen=True)
class Calibration:
    """``logs`` (n_ok, 3): log(B, tau, kappa_E) of the refits that converged; ``spread``:
    their standard deviation (ddof 1) and ``robust_spread`` half the 15.9-84.1 % range;
    ``reported``: the Jacobian 1-sigma at the truth; ``n_failed``: refits without a stroke."""

    truth: np.ndarray
    sem: np.ndarray
    reported: np.ndarray
    logs: np.ndarray
    spread: np.ndarray
    robust_spread: np.ndarray
    n_failed: int


def refit_task(item):
    """Worker function: ``item = (base, tip, n_segments, steps, extrapolate, truth (3,), data (3,),
    sem (3,))``
    -> log(B, tau, kappa_E) of the refit, or None when it failed."""
    from .fit import fit
    from .model import DescriptorModel, NotSwimming

    base, tip, n_segments, steps, extrapolate, truth, data, sem = item
    key = (repr(base), tip, n_segments, steps, extrapolate)
    if key not in _MODELS:
        _MODELS[key] = DescriptorModel(base, tip=tip, n_segments=n_segments, steps=steps, extrapolate=extrapolate)
    try:
        r = fit(data, sem, model=_MODELS[key], guess=tuple(truth))
    except (NotSwimming, RuntimeError):
        return None
    return np.log([r.B, r.tau, r.kappa_E]) if r.converged else None


def calibrate(model, truth, sem, *, n: int = 100, seed: int = 0, backend: str = "serial",
              workers: int | None = None) -> Calibration:
    """Refit ``n`` noisy copies of the descriptors at ``truth`` = (B [N m^2], tau [s], kappa_E
    [1/m]) with noise ``sem`` (period s, advance mm, lateral mm). ``model``: a
    :class:`DescriptorModel` (its base, tip and resolution are used in the workers) or any
    descriptor callable (then the refits run here, serially)."""
    from ..sweep.backends import get_backend
    from .fit import fit
    from .model import DescriptorModel, to_identifiable

    n = positive_int("n", n, minimum=2)
    truth = np.asarray(truth, float)
    sem = np.asarray(sem, float)
    if truth.shape != (3,) or sem.shape != (3,) or not np.all(sem > 0):
        raise ParameterError(f"truth={truth!r} and sem={sem!r} must each be three numbers (sem > 0)")
    y = model(to_identifiable(model.base, *truth))
    reported = fit(y, sem, model=model, guess=tuple(truth)).sigma_rel
    rng = np.random.default_rng(seed)
    draws = [y + sem * rng.standard_normal(3) for _ in range(n)]
    logs = []
    if isinstance(model, DescriptorModel) and backend != "serial":
        items = [(k, (model.base, model.tip, model.n_segments, model.steps, model.extrapolate, truth, d, sem))
                 for k, d in enumerate(draws)]
        with get_backend(backend, workers=workers) as ex:
            logs = [v for _, v in ex.imap(refit_task, items)]
        logs = [v for v in logs if isinstance(v, np.ndarray)]
    else:
        for d in draws:
            try:
                r = fit(d, sem, model=model, guess=tuple(truth))
            except RuntimeError:
                continue
            if r.converged:
                logs.append(np.log([r.B, r.tau, r.kappa_E]))
    arr = np.array(logs).reshape(-1, 3)
    if arr.shape[0] < 2:
        raise RuntimeError(f"only {arr.shape[0]} of {n} refits converged: no spread to compare")
    q = np.percentile(arr, [15.865, 84.135], axis=0)
    return Calibration(truth, sem, reported, arr, np.std(arr, axis=0, ddof=1), 0.5 * (q[1] - q[0]),
                       n - arr.shape[0])
