"""``fit``: B, tau and kappa_E from measured descriptors (and optionally shapes, the onset, or
several voltages), with their uncertainty.

Costs:
- ``"sem"`` (default): least squares of (model - mean) / SEM per descriptor, solved by scipy's
  trust-region reflective method in the identifiable coordinates (log eta_perp, log chi,
  log tau) and mapped back;
- ``"paper"``: the paper's C = sum (c_e / c_n - 1)^2, minimised by SLSQP over factors in
  [0.5, 1.5] of B0, tau0, kappa_E0 (the paper's procedure).
The descriptors come from the periodic-orbit solver, so the cost is smooth.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from .._validate import ParameterError, positive, positive_int
from ..params import Parameters, preset
from .model import LOG_MAP, DescriptorModel, NotSwimming, OutsideModel, Unresolved, to_identifiable, to_physical
from .reach import MAX_FAILED_IN_A_ROW, MAX_FAILED_POINTS, Reach, Stuck, beyond_resolution  # noqa: F401 (the limits: public here)
from .uncertainty import NAMES, covariance, identifiability_card
from .._json import dumps

__all__ = ["FitResult", "fit", "PAPER_GUESS", "paper_cost"]

#: The paper's initial guess (SI): B0 = 2e-8 N mm^2, tau0 = 0.3 s, kappa_E0 = 18 1/mm.
PAPER_GUESS = (2.0e-14, 0.3, 18.0e3)
#: the paper's box: factors of the initial guess its fit searched within
BOX = (0.5, 1.5)
#: a fit whose largest relative 1-sigma exceeds this says which combination is weakly determined
WEAK_SIGMA_REL = 0.3
#: a converged one-voltage fit with a misfit above FOLD_CHI2 and a condition number above
#: FOLD_CONDITION stopped on a fold (FitResult.at_fold); an exact solution ends at chi2 ~ 1e-10,
#: and a weakly determined one that is exact (condition numbers up to ~4400) at chi2 ~ 0
FOLD_CHI2 = 1e-4
FOLD_CONDITION = 1e4
#: most parametric bootstrap draws
MAX_BOOTSTRAP = 10_000
#: most extra starts of a multi-start search (each is a fit: 10-40 s)
MAX_STARTS = 64
#: solutions whose parameters differ from each other by less than this (relative) are one
SAME_SOLUTION_REL = 0.01
PENALTY = 1e3  # weighted residual when there is no stable stroke


def paper_cost(measured: np.ndarray, model: np.ndarray) -> float:
    """C = sum_k (c_e / c_n - 1)^2 over (period, advance, lateral)."""
    return float(np.sum((np.asarray(measured) / np.asarray(model) - 1.0) ** 2))


@dataclass(frozen=True)
class FitResult:
    """Fitted B [N m^2], tau [s], kappa_E [1/m], relative 1-sigma of each, correlations, the
    identifiability card, profiles and bootstrap if asked, the costs and the settings.
    ``measured``, ``sem`` and ``model`` are (3,), or (m, 3) for a joint fit over m voltages
    (:func:`flutterswim.fitting.fit_voltages`; kappa_E at ``settings["v_ref_V"]``)."""

    B: float
    tau: float
    kappa_E: float
    sigma_rel: np.ndarray
    correlation: np.ndarray
    cost: float
    paper_cost: float
    cost_kind: str
    converged: bool
    message: str
    n_model_evaluations: int
    wall_time_s: float
    measured: np.ndarray
    sem: np.ndarray
    model: np.ndarray
    card: Any
    profiles: dict = field(default_factory=dict)
    bootstrap_sigma_rel: np.ndarray | None = None
    settings: dict = field(default_factory=dict)
    #: parameters held at a bound of the paper's box (``cost="paper"``); their 1-sigma is that of
    #: the unconstrained local problem (finite, never NaN), and the bound itself is reported
    at_bound: tuple = ()

    @property
    def weakly_determined(self) -> str:
        """A note when some parameter's 1-sigma exceeds WEAK_SIGMA_REL ("" otherwise): the data
        leave a combination nearly free, along which other parameter sets fit as well (at
        (1.5, 0.7, 1.5) x the paper's guess the three descriptors have a second exact solution,
        B, tau, kappa_E 18 %, 14 %, 13 % lower, which the fit may find instead)."""
        s = np.asarray(self.sigma_rel, float)
        if not (np.all(np.isfinite(s)) and s.max() > WEAK_SIGMA_REL):
            return ""
        a = self.card.weakest / self.card.weakest[np.argmax(np.abs(self.card.weakest))]
        combo = " ".join(f"{n}^{v:+.2f}" for n, v in zip(NAMES, a) if abs(v) > 0.05)
        return (f"the data determine {combo} poorly (1-sigma up to {100 * s.max():.0f} %): parameter sets far apart "
                "along it fit as well, and some may fit exactly; the profiles (--profiles) show the range, and "
                "tracked shapes, the onset or several voltages (--joint) narrow it")

    @property
    def at_fold(self) -> bool:
        """The fit stopped on a fold of the map from parameters to descriptors, not at a
        solution: three descriptors of one voltage fitted with three parameters, converged at no
        bound, with a misfit (chi2 > FOLD_CHI2) and a Jacobian close to singular (condition
        number > FOLD_CONDITION). The gradient J^T r vanishes with r != 0 only where J is
        singular: no parameter set near it reproduces the data, which lie beyond the fold; its 1-sigma
        from the curvature is meaningless (a review: 4e5-6e7 %), and the value is biased towards
        the fold (B +10 % over 300 noise draws, 38 % of them at a fold)."""
        return bool(self.converged and self.cost_kind == "sem" and np.asarray(self.measured).size == 3
                    and not self.at_bound and self.cost > FOLD_CHI2
                    and not self.card.condition_number <= FOLD_CONDITION)

    @property
    def fold_note(self) -> str:
        """What :attr:`at_fold` means for the user ("" when it does not hold)."""
        if not self.at_fold:
            return ""
        # (chi2 < 1 with "no parameter set reproduces these data" read as a contradiction)
        within = (", within the standard errors: the data are consistent with the model there, but it reproduces "
                  "them exactly nowhere near") if self.cost < 1.0 else ""
        return (f"no parameter set near the fit reproduces these data exactly: it stopped where the model folds (chi2 = "
                f"{self.cost:.3g}{within}, with three descriptors and three parameters; condition number "
                f"{self.card.condition_number:.3g}), and the data lie beyond the fold; the 1-sigma from the "
                "curvature is meaningless there and the values lean towards the fold: the profiles (--profiles, "
                "profiles=True) give the range of parameters consistent with the data, and starts over the box "
                "(--starts) may find an exact solution elsewhere")

    def _descriptor_names(self) -> list[str]:
        """Names of the measured descriptors, per voltage for a joint fit ("period@85V")."""
        names = ["period", "advance", "lateral"]
        volts = self.settings.get("voltages_V")
        return [f"{d}@{v:g}V" for v in volts for d in names] if volts else names

    @property
    def failure(self) -> str:
        """Why this is not a fit ("" for a converged one): data beyond the model's reach, or
        "not converged: " and the optimiser's reason."""
        if self.converged:
            return ""
        return self.message if self.settings.get("out_of_reach") else f"not converged: {self.message}"

    def to_dict(self) -> dict[str, Any]:
        def f(v):
            return None if v is None or not math.isfinite(float(v)) else float(v)

        out = {
            # first, so that a failed fit's values are not read as a fit's
            # (a fit stopped on a fold said "converged": a script reading it took values off by 5-58 %)
            "status": ("at_fold" if self.at_fold else "converged") if self.converged else "failed",
            **({"failure": self.failure} if not self.converged else {}),
            "values": {"B_N_m2": self.B, "tau_s": self.tau, "kappa_E_per_m": self.kappa_E,
                       "B_N_mm2": self.B * 1e6, "kappa_E_per_mm": self.kappa_E * 1e-3},
            "sigma_rel": {n: f(s) for n, s in zip(NAMES, self.sigma_rel)},
            "correlation": {f"{a}-{b}": f(self.correlation[i, j]) for i, a in enumerate(NAMES)
                            for j, b in enumerate(NAMES) if j > i},
            "cost": {"kind": self.cost_kind, "value": self.cost, "paper_C": self.paper_cost},
            "at_bound": list(self.at_bound),
            "at_fold": self.at_fold,
            "convergence": {"converged": self.converged, "message": self.message,
                            "model_evaluations": self.n_model_evaluations, "wall_time_s": self.wall_time_s},
            "data": {"descriptors": ["period_s", "advance_mm", "lateral_mm"],
                     "measured": self.measured.tolist(),
                     "sem": np.vectorize(f, otypes=[object])(self.sem).tolist(),
                     "model": self.model.tolist()},
            "identifiability": {"singular_values": self.card.singular_values.tolist(),
                                "condition_number": self.card.condition_number,
                                "weakest_combination_exponents": dict(zip(NAMES, self.card.weakest.tolist())),
                                "summary": self.card.describe(),
                                "note": "; ".join(n for n in (self.fold_note, self.weakly_determined) if n) or None,
                                "sensitivities_dlog_descriptor_dlog_parameter":
                                    {d: dict(zip(NAMES, row)) for d, row in
                                     zip(self._descriptor_names(), self.card.sensitivities.tolist())}},
            "settings": self.settings,
        }
        if self.profiles:
            out["profiles"] = {k: {"values": v["values"].tolist(), "chi2": [f(c) for c in v["chi2"]],
                                   "sigma_rel_profile": f(v["sigma_rel"]),
                                   "interval_rel": [f(v.get("lower")), f(v.get("upper"))],
                                   "note": "interval null: the profile flattens before rising by 1 (unbounded); "
                                           "chi2 null: the model has no stroke there"}
                               for k, v in self.profiles.items()}
        if self.bootstrap_sigma_rel is not None:
            out["bootstrap_sigma_rel"] = dict(zip(NAMES, self.bootstrap_sigma_rel.tolist()))
        return out

    def save(self, path) -> None:
        from .._paths import atomic_write_text, check_output_file

        p = check_output_file(path, (".json",), kind="fit")
        from .. import __version__

        # ("generator", as every other JSON flutterswim writes; it was "software": "flutterswim fit")
        atomic_write_text(p, dumps({"generator": f"flutterswim {__version__} fit", **self.to_dict()}, indent=2))


class Penalty:
    """The residuals of a trial point without a stroke, for one optimisation: ten times the
    largest residual seen at a point with one (at least PENALTY), so that the optimiser never
    takes such a point over one with a stroke (a fixed PENALTY was below the start's residuals
    on data far from the model: the optimiser took the point and asked for a Jacobian there)."""

    def __init__(self) -> None:
        self.value = PENALTY

    def seen(self, r: np.ndarray) -> np.ndarray:
        self.value = max(self.value, 10.0 * float(np.max(np.abs(r))))
        return r

    def failed(self, n: int) -> np.ndarray:
        return np.full(n, self.value)


def _weighted(model, x, mean, sem, penalty: Penalty):
    try:
        y = model(x)
    except NotSwimming:
        return penalty.failed(3), None
    return penalty.seen((y - mean) / sem), y


def _start(model, x0, mean) -> None:
    """Raise :class:`OutsideModel` if the model has no stroke at the start ``x0`` (nothing to fit
    from); a stroke not resolved there (Unresolved) propagates, for a finer model."""
    try:
        model(x0)
    except Unresolved:
        raise
    except NotSwimming as exc:
        raise OutsideModel(_outside(mean, f"no stable stroke at the fit's start ({exc})")) from None


def _outside(mean, why: str) -> str:
    return (f"the data (period {mean[0]:.4g} s, advance {mean[1]:.4g} mm, lateral {mean[2]:.4g} mm) are outside "
            f"what the model can reproduce: {why}")


def default_guess(base: Parameters | None) -> tuple[float, float, float]:
    """The paper's initial guess carried to ``base``'s geometry and viscosity at the same
    dimensionless point (chi = kappa_E l and eta_perp = mu_perp l^4 / (B tau) as the guess's in
    the paper's geometry; tau as guessed): a shorter ribbon fitted from the paper's guess itself
    had no stroke at the start (l = 3 mm: chi 57, below the onset), and the data were blamed."""
    if base is None:
        return PAPER_GUESS
    B, tau, k = PAPER_GUESS
    paper = preset("paper")
    return (B * (base.mu_perp * base.l ** 4) / (paper.mu_perp * paper.l ** 4), tau, k * paper.l / base.l)


def fit(measured, sem=None, *, base: Parameters | None = None, guess=PAPER_GUESS, cost: str = "sem",
        tip: str = "trailing", model=None, profiles: bool = False, bootstrap: int = 0,
        n_segments: int = 24, extrapolate: bool = True, seed: int = 0, backend: str | None = None,
        workers: int | None = None, starts: int = 0) -> FitResult:
    """Fit (B, tau, kappa_E) to ``measured`` = (period [s], advance [mm], lateral [mm]) with
    standard errors ``sem`` (same units; required for the default cost and for uncertainties).

    ``base``: geometry and viscosity (default: the paper preset); ``guess``: (B, tau, kappa_E)
    to start from (default: the paper's initial guess, carried to ``base``'s geometry by
    :func:`default_guess`); ``model``: a descriptor model (default
    :class:`DescriptorModel` on periodic orbits: the continuum's descriptors, extrapolated from
    ``n_segments`` and twice as many; with ``extrapolate=False`` those of ``n_segments`` alone,
    whose discretisation the reported 1-sigma does not include: 24 alone puts the paper's advance
    1.8 % above the continuum and moves the fitted B, tau, kappa_E by 4-6 %);
    ``backend``, ``workers``:
    a sweep backend (``"processes"``, ``"dask-local"``, ...) on which the finite-difference
    orbits of each Jacobian are computed in parallel (default: in this process).

    ``starts``: search for other solutions from that many starts, the guess and then points
    spread over the paper's box (0.5-1.5 x the guess; a scrambled Halton sequence drawn with
    ``seed``), each by least squares deflated against the solutions known so far (so that a
    known solution no longer attracts it), and report every other parameter set that fits about
    as well (chi2 within 4 of the best) in ``settings["other_solutions"]``.
    Three descriptors can be matched exactly at two parameter sets (at (1.5, 0.7, 1.5) x the
    guess: B, tau, kappa_E 18, 14 and 13 % lower fit as well); a single fit finds one of them
    and its 1-sigma does not show the other. A start that reaches a clearly better solution
    (chi2 lower by more than 1) replaces the first fit. Each start is a fit (10-40 s); for
    the SEM-weighted cost only."""
    # (before any orbit is computed; each draw is a refit of seconds)
    bootstrap = positive_int("bootstrap", bootstrap, 0, MAX_BOOTSTRAP, "each draw is a refit: 10^4 take hours")
    starts = positive_int("starts", starts, 0, MAX_STARTS, "each start is a fit of 10-40 s")
    seed = positive_int("seed", seed, 0)
    if starts and cost != "sem":
        raise ParameterError(f"starts={starts} searches with the SEM-weighted cost; cost={cost!r} (the paper's) "
                             "takes none")
    if guess is PAPER_GUESS:
        guess = default_guess(base if isinstance(base, Parameters) else None)
    if backend is None or not hasattr(model if model is not None else DescriptorModel, "prefetch"):
        return _fit(measured, sem, base=base, guess=guess, cost=cost, tip=tip, model=model, profiles=profiles,
                    bootstrap=bootstrap, n_segments=n_segments, extrapolate=extrapolate, seed=seed, starts=starts)
    base_ = preset("paper") if base is None else base
    model = DescriptorModel(base_, tip=tip, n_segments=n_segments, extrapolate=extrapolate) if model is None else model
    return on_backend(model, backend, workers, lambda: _fit(
        measured, sem, base=base, guess=guess, cost=cost, tip=tip, model=model, profiles=profiles,
        bootstrap=bootstrap, n_segments=n_segments, extrapolate=extrapolate, seed=seed, starts=starts))


def on_backend(model, backend: str, workers: int | None, call) -> FitResult:
    """``call()`` with the model's finite-difference orbits computed on a sweep backend; the
    result's settings name the backend."""
    from ..sweep.backends import check_backend, get_backend

    check_backend(backend, workers=workers)
    with get_backend(backend, workers=workers) as ex:
        model.executor = ex
        try:
            res = call()
        finally:
            model.executor = None
    return replace(res, settings={**res.settings, "backend": backend, "workers": workers})


#: a fit that hit strokes its model does not resolve (Unresolved) and ends with a misfit above
#: these (chi-square: a 3-sigma miss; the paper's C: 1 % per descriptor) stopped against them
STALL_CHI2 = 9.0
#: a fit stops after this long (its tries at finer resolutions included), at its best point, and
#: says why: a good fit takes 10-40 s; the leading end's excursions fitted as the trailing end's
#: searched among strokes near the onset (slow orbits) for over 18 minutes without a word
MAX_FIT_SECONDS = 240.0
STALL_PAPER_C = 1e-4


def _stalled(res: "FitResult", model) -> bool:
    if not getattr(model, "n_unresolved", 0) or res.settings.get("out_of_reach"):
        return False
    if res.cost_kind == "sem":
        return not res.cost <= STALL_CHI2
    return not res.paper_cost <= STALL_PAPER_C and not res.at_bound


def refine_while_stalled(run, model, stalled, misfit):
    """``run(model)`` -> FitResult, repeated from twice the segments (``model.finer()``) while
    ``stalled(res, model)``: the fit hit strokes the model does not resolve and ended with a
    poor misfit (near the onset of swimming the 24-segment stroke differs from the 48-segment
    one by over 10 %, and the fit stops against those parameters as against a wall); when no
    finer model is left, the result is marked not converged and says why (``misfit(res)``: the
    misfit in words)."""
    first = getattr(model, "n_segments", None)
    while True:
        if hasattr(model, "n_unresolved"):
            model.n_unresolved = 0  # this fit's own
        try:
            res = run(model)
        except Unresolved:  # not even a start: refine, or say why
            if getattr(model, "finer", lambda: None)() is None:
                raise
            model = model.finer()
            continue
        if not stalled(res, model):
            break
        finer = model.finer()
        if finer is None:
            far = beyond_resolution(res, getattr(model, "last_change", 0.0))
            if far:
                return replace(res, converged=False, message=(
                    f"not a fit: the data are out of the model's reach: at the best point it found, {far}; more "
                    "segments would not help"))
            return replace(res, converged=False, message=(
                f"not a fit: it stopped against parameters whose stroke is not resolved ({model.last_unresolved}), "
                f"with {misfit(res)}; give more --segments or --no-extrapolate"))
        model = finer
    if getattr(model, "n_segments", first) != first:
        res = replace(res, settings={**res.settings, "refined_from_segments": first},
                      message=f"{res.message} (refined from {first} to {model.n_segments} segments: strokes near "
                              f"the data were not resolved at {first})")
    return res


def _fit(measured, sem=None, *, base, guess, cost, tip, model, profiles, bootstrap, n_segments, extrapolate,
         seed, starts=0) -> FitResult:
    base_ = preset("paper") if base is None else base
    if not isinstance(base_, Parameters):
        raise ParameterError(f"base={base!r} must be flutterswim.Parameters")
    model = DescriptorModel(base_, tip=tip, n_segments=n_segments, extrapolate=extrapolate) if model is None else model

    t_start = time.perf_counter()

    def run(m, start=None, box=False):  # (MAX_FIT_SECONDS for the whole fit, finer tries included: at least 10 s each)
        left = max(MAX_FIT_SECONDS - (time.perf_counter() - t_start), min(10.0, MAX_FIT_SECONDS))
        return _fit_once(measured, sem, base=base, guess=guess, cost=cost, tip=tip, model=m, n_segments=n_segments,
                         seconds=left, start=start, box=box)

    res = refine_while_stalled(run, model, _stalled, lambda r: f"chi2 = {r.cost:.3g}" if r.cost_kind == "sem"
                               else f"the paper's C = {r.paper_cost:.3g}")
    while getattr(model, "n_segments", None) is not None and model.n_segments < res.settings.get("n_segments", 0):
        model = model.finer()  # (the resolution refine_while_stalled ended at)
    # the profiles and bootstrap on the first fit's model even when the fit is repeated finer:
    # their widths come from the standard errors (20 % at the paper's point), which a model
    # 0.1-1 % finer does not change, and on the finer model they took 3-4 times as long
    # (--profiles at the paper's point over 13 minutes against about 2)
    res, kept = _refine_if_sensitive(res, model, run, base_)
    res = _prefer_the_box(res, kept, run, guess)
    if starts:
        res = _search_starts(res, starts, seed, guess, base_, kept, lambda start: _fit_once(
            measured, sem, base=base, guess=guess, cost=cost, tip=tip, model=kept, n_segments=n_segments,
            start=start))
    res = replace(res, wall_time_s=time.perf_counter() - t_start)  # (all its passes: the JSON's time)
    return _with_extras(res, model, base_, profiles, bootstrap, seed)


def _in_box(res: "FitResult", guess) -> bool:
    f = np.array([res.B, res.tau, res.kappa_E]) / np.asarray(guess, float)
    return bool(np.all((f >= BOX[0] * (1 - 1e-9)) & (f <= BOX[1] * (1 + 1e-9))))


def _prefer_the_box(res: "FitResult", model, run, guess) -> "FitResult":
    """A converged SEM-weighted fit that ended outside the paper's box (factors [0.5, 1.5] of
    the guess) is searched again within it. The three descriptors can be matched exactly at two
    parameter sets (a review: leading-end data made at (0.6, 1.4, 0.8) x the guess were fitted
    exactly at B 45 % lower, outside the box, with a 1-sigma of 6 %). A solution inside the box
    that fits as well (chi2 within 1 of the first) is kept, the other reported in
    ``settings["other_solutions"]``; one that fits worse is reported only if within 4."""
    if not (res.converged and res.cost_kind == "sem") or _in_box(res, guess):
        return res
    try:
        alt = run(model, box=True)
    except (NotSwimming, Unresolved):
        return res
    if not (alt.converged and not alt.at_bound and alt.cost <= res.cost + 4.0):
        return res
    first, second = (alt, res) if alt.cost <= res.cost + 1.0 else (res, alt)
    other = {"B_N_m2": second.B, "tau_s": second.tau, "kappa_E_per_m": second.kappa_E, "chi2": second.cost,
             "in_box": second is alt}
    why = ("another parameter set fits these data as well: the one inside the paper's box (0.5-1.5 x the guess) "
           "is reported" if first is alt else "a parameter set inside the paper's box fits nearly as well")
    return replace(first, settings={**first.settings, "other_solutions": [other]},
                   message=f"{first.message} ({why}; see other_solutions)")


def start_points(guess, n: int, seed: int = 0) -> np.ndarray:
    """``n`` (B, tau, kappa_E) spread over the paper's box: a scrambled Halton sequence in the
    log factors of ``guess``, kept off the box's faces (factors 0.55-1.45)."""
    from scipy.stats import qmc

    u = qmc.Halton(d=3, scramble=True, seed=seed).random(n)
    lo, hi = math.log(0.55), math.log(1.45)
    return np.asarray(guess, float) * np.exp(lo + (hi - lo) * u)


def _distinct(a: "FitResult", b) -> bool:
    p = np.array([a.B, a.tau, a.kappa_E])
    q = np.array([b.B, b.tau, b.kappa_E]) if isinstance(b, FitResult) else np.array(
        [b["B_N_m2"], b["tau_s"], b["kappa_E_per_m"]])
    return bool(np.max(np.abs(np.log(p / q))) > SAME_SOLUTION_REL)


def _deflated(model, base, guess, x0, mean, sem, known) -> np.ndarray:
    """From ``x0``, a zero of the weighted residual r(x) within the paper's box (factors
    [0.5, 1.5] of ``guess``) away from the ``known`` solutions (identifiable coordinates):
    bounded least squares of the deflated residual r(x) prod_k (1 / |x - x_k|^2 + 1)
    (deflation: Farrell, Birkisson & Funke, SIAM J. Sci. Comput. 2015), which a known solution
    no longer attracts; returns where it ended. (Unbounded, the search left the box for
    factors of 3 where the deflated residual has other minima.)"""
    from scipy.optimize import least_squares

    penalty = Penalty()
    y0 = np.log(np.asarray(guess, float))
    lo, hi = np.full(3, math.log(BOX[0])), np.full(3, math.log(BOX[1]))

    def x_of(z):
        return to_identifiable(base, *np.exp(y0 + z))

    def fun(z):
        x = x_of(z)
        factor = math.prod(1.0 / max(float(np.sum((x - xk) ** 2)), 1e-300) + 1.0 for xk in known)
        return _weighted(model, x, mean, sem, penalty)[0] * factor

    z0 = np.log(np.asarray(to_physical(base, x0)) / np.asarray(guess, float)).clip(lo, hi)
    # in steps d from the start (d = 0 exactly): trf's first trust region is |x0|, which at the
    # guess, z0 ~ 1e-16 from round-off, stopped the search where it began
    res = least_squares(lambda d: fun(z0 + d), np.zeros(3), bounds=(lo - z0, hi - z0), method="trf",
                        diff_step=1e-6, xtol=1e-12, ftol=1e-14, gtol=1e-14, max_nfev=80)
    return x_of(z0 + res.x)


def _search_starts(res: "FitResult", n: int, seed: int, guess, base, model, fit_from) -> "FitResult":
    """``res`` and the other solutions found from ``n`` starts, the guess first and then
    :func:`start_points` over the paper's box: from each, a search deflated against the
    solutions known so far (:func:`_deflated`), then ``fit_from(start)`` at its end. Converged
    fits with chi2 within 4 of the best, distinct from each other, go to
    ``settings["other_solutions"]``; one better than ``res`` by more than 1 in chi2 is reported
    instead of it. ``settings["starts"]`` counts the starts."""
    from tqdm.auto import tqdm

    if not (res.converged and res.cost_kind == "sem"):
        return replace(res, settings={**res.settings, "starts": {
            "n": n, "seed": seed, "skipped": "the fit did not converge: no solution to search away from"}})
    sem = np.asarray(res.sem, float)
    known = [to_identifiable(base, res.B, res.tau, res.kappa_E)] + [
        to_identifiable(base, o["B_N_m2"], o["tau_s"], o["kappa_E_per_m"])
        for o in res.settings.get("other_solutions", [])]
    found, skipped, failed = [], 0, 0
    starts = np.vstack([np.asarray(guess, float)[None], start_points(guess, n - 1, seed)]) if n > 1 \
        else np.asarray(guess, float)[None]
    for start in tqdm(starts, desc="fit starts", unit="start", disable=None, leave=False):
        try:
            x = _deflated(model, base, guess, to_identifiable(base, *start), res.measured, sem, known)
            r = fit_from(to_physical(base, x))
        except (NotSwimming, Unresolved):  # no stroke at the start, or none resolved there
            skipped += 1
            continue
        if not r.converged:
            failed += 1
            continue
        found.append(r)
        x_r = to_identifiable(base, r.B, r.tau, r.kappa_E)
        if all(np.max(np.abs(x_r - xk)) > SAME_SOLUTION_REL for xk in known):  # (a known one again: not twice)
            known.append(x_r)
    best = min([res] + found, key=lambda r: r.cost)
    if best is not res and not best.cost < res.cost - 1.0:
        best = res  # (as good: the first fit stays, the others are reported)
    others = [o for o in res.settings.get("other_solutions", []) if _distinct(best, o)]
    for r in sorted([res] + found, key=lambda r: r.cost):
        if r.cost <= best.cost + 4.0 and _distinct(best, r) and all(_distinct(r, o) for o in others):
            others.append({"B_N_m2": r.B, "tau_s": r.tau, "kappa_E_per_m": r.kappa_E, "chi2": r.cost,
                           "in_box": _in_box(r, guess)})
    note = {"n": n, "seed": seed, "converged": len(found), "not_converged": failed, "no_stroke_at_start": skipped,
            "distinct_solutions": 1 + len(others), "method": "deflated least squares from each start",
            "caution": "finding no other solution does not show that the fit is unique: on a surrogate with two "
                       "exact solutions in the box (64 of 216 data sets), 1-2 starts found the second in 19 % of "
                       "them, 4-8 in 48 %, 16 in 91 %"}
    message = best.message
    if best is not res:
        message = f"{message} (a start found this, chi2 {best.cost:.3g} against the first fit's {res.cost:.3g})"
    if len(others) > len(res.settings.get("other_solutions", [])):
        message = f"{message} ({len(others)} other parameter set(s) fit as well or nearly: see other_solutions)"
    return replace(best, message=message, settings={**best.settings, "starts": note,
                                                    **({"other_solutions": others} if others else {})})


def _with_extras(res: "FitResult", model, base, profiles: bool, bootstrap: int, seed) -> "FitResult":
    """``res`` with its profile likelihoods and parametric bootstrap (as asked), on ``model``;
    none for data out of the model's reach, and no profiles without standard errors."""
    if not (profiles or bootstrap) or res.settings.get("out_of_reach"):
        return res
    sem_arr = res.sem if np.all(np.isfinite(res.sem)) else None
    x = to_identifiable(base, res.B, res.tau, res.kappa_E)
    prof, boot = {}, None
    if profiles and sem_arr is not None:
        from .profile import profile_likelihood

        prof = profile_likelihood(model, base, x, res.measured, sem_arr, res.sigma_rel)
    if bootstrap:
        if sem_arr is None:
            raise ParameterError("bootstrap needs the standard errors (sem)")
        boot = _bootstrap(model, x, res.measured, sem_arr, bootstrap, seed)
    return replace(res, profiles=prof, bootstrap_sigma_rel=boot)


#: a converged fit is repeated with the model from twice the segments when the finer model's
#: descriptors at the fit would move a parameter by more than this (relative): a poorly
#: conditioned point turns the extrapolated model's error of about 1e-4 into parameter errors of
#: 1 % (a review: B -1.06 % at 0.6, 1.4, 1.4 x the guess, condition number 1590; -0.24 % at 48)
REFINE_PARAMETER_TOL = 1e-3


def _refine_if_sensitive(res: "FitResult", model, run, base) -> tuple["FitResult", object]:
    """(the fit kept, its model): ``res``, or the fit repeated with ``model.finer()`` when that
    model's descriptors at ``res`` would move a parameter by over REFINE_PARAMETER_TOL."""
    finer = model.finer() if res.converged and hasattr(model, "finer") else None
    if finer is None:
        return res, model
    if res.at_fold:  # (the linear estimate of the shift divides by the fold's singular Jacobian: 9e15 %)
        return res, model
    x = to_identifiable(base, res.B, res.tau, res.kappa_E)
    try:
        y_fine = np.asarray(finer(x), float)
    except (NotSwimming, Unresolved):
        return res, model
    y = np.asarray(res.model, float)
    try:
        dx = np.linalg.solve(res.card.sensitivities, np.log(y_fine / y))
    except np.linalg.LinAlgError:
        return res, model
    shift = np.abs(np.asarray(to_physical(base, x + dx)) / np.array([res.B, res.tau, res.kappa_E]) - 1.0)
    if not np.max(shift) <= 1.0:  # (a near-singular Jacobian: the linear estimate means nothing)
        return replace(res, settings={**res.settings, "resolution_shift_rel": None}), model
    if not np.max(shift) > REFINE_PARAMETER_TOL:
        return replace(res, settings={**res.settings, "resolution_shift_rel": float(np.max(shift))}), model
    finer_res = run(finer, (res.B, res.tau, res.kappa_E))  # (from the first fit: from the guess it fell elsewhere)
    if not finer_res.converged:
        return replace(res, settings={**res.settings, "resolution_shift_rel": float(np.max(shift)),
                                      "refit_failed": finer_res.message}), model
    return replace(finer_res, settings={**finer_res.settings, "refined_from_segments": model.n_segments,
                                        "resolution_shift_rel": float(np.max(shift))},
                   message=f"{finer_res.message} (refined from {model.n_segments} to {finer.n_segments} segments: "
                           f"the finer model moved a parameter by {100 * np.max(shift):.2g} % at the first fit)"), finer


def _fit_once(measured, sem=None, *, base, guess, cost, tip, model, n_segments, seconds: float | None = None,
              start=None, box: bool = False) -> FitResult:
    """One fit with ``model`` (no profiles or bootstrap: :func:`_with_extras` adds them to the
    fit that is kept), from ``start`` (B, tau, kappa_E; default ``guess``). ``box``: the
    SEM-weighted cost searched within the paper's box, factors [0.5, 1.5] of ``guess``."""
    t0 = time.perf_counter()
    base = preset("paper") if base is None else base
    if not isinstance(base, Parameters):
        raise ParameterError(f"base={base!r} must be flutterswim.Parameters")
    mean = np.asarray(measured, float)
    if mean.shape != (3,) or not np.all(np.isfinite(mean)) or np.any(mean <= 0):
        raise ParameterError(f"measured={measured!r} must be three positive numbers (period s, advance mm, lateral mm)")
    if cost not in ("sem", "paper"):
        raise ParameterError(f"cost={cost!r} must be 'sem' or 'paper'")
    sem_arr = None if sem is None else np.asarray(sem, float)
    if sem_arr is not None and (sem_arr.shape != (3,) or not np.all(np.isfinite(sem_arr) & (sem_arr > 0))):
        raise ParameterError(f"sem={sem!r} must be three finite positive standard errors (or None)")
    if cost == "sem" and sem_arr is None:
        raise ParameterError("sem=None: the default cost weights by the standard errors; give sem or cost='paper'")
    if np.ndim(guess) != 1 or np.size(guess) != 3:
        raise ParameterError(f"guess={guess!r} must be three numbers (B [N m^2], tau [s], kappa_E [1/m])")
    B0, tau0, k0 = (positive(n, v) for n, v in zip(("guess B", "guess tau", "guess kappa_E"), guess))
    x0 = to_identifiable(base, *(start if start is not None else (B0, tau0, k0)))
    from scipy.optimize import least_squares, minimize

    _start(model, x0, mean)
    # the strokes the fit computed, its failed points, and its time (what is left of the fit's
    # MAX_FIT_SECONDS after its coarser tries)
    track = Reach(MAX_FIT_SECONDS if seconds is None else seconds)
    if cost == "sem":
        penalty = Penalty()

        def fun(x):
            r, y = _weighted(model, x, mean, sem_arr, penalty)
            track.record(x, r, y)
            return r

        def jac(x):
            y = model(x)
            return model_jacobian(model, x, y) / sem_arr[:, None]

        at_bound = ()
        try:
            if box:
                # log factors z of (B, tau, kappa_E) on the guess, within the paper's box; x of z
                # is affine (x = const + LOG_MAP^-1 y), so d x / d z = LOG_MAP^-1
                y0, dxdz = np.log([B0, tau0, k0]), np.linalg.inv(LOG_MAP)
                lo, hi = np.full(3, math.log(BOX[0])), np.full(3, math.log(BOX[1]))

                def x_of(z):
                    return to_identifiable(base, *np.exp(y0 + z))

                res = least_squares(lambda z: fun(x_of(z)), np.zeros(3), jac=lambda z: jac(x_of(z)) @ dxdz,
                                    bounds=(lo, hi), method="trf", xtol=1e-13, ftol=1e-15, gtol=1e-15, max_nfev=60)
                x, ok, msg = x_of(res.x), bool(res.success), str(res.message)
                at_bound = tuple(n for n, z in zip(("B", "tau", "kappa_E"), res.x)
                                 if z - lo[0] < 1e-6 or hi[0] - z < 1e-6)
            else:
                # in steps from the start: the first trust region is then 1 (a factor e per
                # parameter), not the start's length in log units (about 6: factors of hundreds,
                # where the model has no stroke and its solves fail slowly)
                res = least_squares(lambda d: fun(x0 + d), np.zeros_like(x0), jac=lambda d: jac(x0 + d),
                                    method="trf", xtol=1e-13, ftol=1e-15, gtol=1e-15, max_nfev=60)
                x, ok, msg = x0 + res.x, bool(res.success), str(res.message)
        except Stuck as stuck:
            x, ok, msg = stuck.x, False, str(stuck)
    else:
        lo = np.log(np.full(3, BOX[0]))
        hi = math.log(BOX[1])  # the paper's box: factors in [0.5, 1.5]
        # optimisation variables: log factors (alpha: kappa_E, beta: B, gamma: tau) as in the paper

        def x_of(f):
            return to_identifiable(base, B0 * math.exp(f[1]), tau0 * math.exp(f[2]), k0 * math.exp(f[0]))

        def c_of(f):
            try:
                return paper_cost(mean, model(x_of(f)))
            except NotSwimming:
                return 1e6

        def g_of(f, h=1e-6):
            return np.array([(c_of(f + h * e) - c_of(f - h * e)) / (2 * h) for e in np.eye(3)])

        r = minimize(c_of, np.zeros(3), jac=g_of, method="SLSQP",
                     bounds=[(lo[0], hi)] * 3, options={"ftol": 1e-14, "maxiter": 100})
        x, ok, msg = x_of(r.x), bool(r.success), str(r.message)
        # (alpha, beta, gamma) = (kappa_E, B, tau); a bound is active within 1e-6 in log
        at_bound = tuple(n for n, f in zip(("kappa_E", "B", "tau"), r.x)
                         if f - lo[0] < 1e-6 or hi - f < 1e-6)
    try:
        y = model(x)
    except Unresolved:
        raise
    except NotSwimming as exc:  # the optimiser ended where the model fails
        raise OutsideModel(_outside(mean, f"the fit ended at a point without a stable stroke ({exc})")) from None
    B, tau, kE = to_physical(base, x)
    jw = model_jacobian(model, x, y)
    sens = jw / y[:, None]
    weights = sem_arr if sem_arr is not None else 0.05 * mean  # 5 % when no SEMs are given
    jw_w = jw / weights[:, None]
    cov = covariance(jw_w)
    card = identifiability_card(jw_w, sens)
    chi2 = float(np.sum(((y - mean) / weights) ** 2))
    # a poor fit whose data are beyond every stroke it computed is no fit (nor would a finer model be)
    beyond = track.beyond(mean, sem_arr) if cost == "sem" and not chi2 <= STALL_CHI2 else None
    if beyond:
        ok, msg = False, _outside(mean, beyond)
    elif track.timed_out:  # (no finer model either: it would be slower)
        beyond = msg = (
            f"{msg} ({MAX_FIT_SECONDS:g} s, MAX_FIT_SECONDS; chi2 = {chi2:.3g} at the best point): the strokes where the fit searched are slow to "
            "compute (near the onset of swimming, where the lateral excursions are small)"
            + ("; if the lateral excursions are the leading end's, fit them as such (--tip leading, tip='leading')"
               if tip == "trailing" else ""))
    return FitResult(B, tau, kE, cov.sigma_rel, cov.correlation, chi2 if cost == "sem" else paper_cost(mean, y),
                     paper_cost(mean, y), cost, ok, msg, getattr(model, "evaluations", getattr(model, "n_evaluations", 0)),
                     time.perf_counter() - t0, mean, sem_arr if sem_arr is not None else np.full(3, np.nan), y,
                     card, {}, None,
                     {"tip": tip, "n_segments": getattr(model, "n_segments", n_segments),
                      "extrapolate": bool(getattr(model, "_fine", None) is not None),
                      "model": getattr(model, "resolution", type(model).__name__), "guess": list(guess), "cost": cost,
                      "held_fixed": held_fixed(base),
                      "uncertainty_weights": "sem" if sem_arr is not None else "5% of the measured values",
                      **({"out_of_reach": beyond} if beyond else {})},
                     at_bound)


def held_fixed(base: Parameters) -> dict[str, float]:
    """The parameters a fit holds fixed (geometry, viscosity), SI, for its settings. The base's
    own B, tau and kappa_E are left out: the fit does not use them, and under a key "base" they
    were easily read as results."""
    return {k: float(v) for k, v in asdict(base).items() if k not in ("B", "tau", "kappa_E")}


def model_jacobian(model, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """d(descriptors)/dx: the model's own (exact in log tau) or central differences."""
    if hasattr(model, "jacobian"):
        return model.jacobian(x, y)
    jac = np.zeros((3, 3))
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1e-5
        try:
            jac[:, k] = (model(x + e) - model(x - e)) / 2e-5
        except NotSwimming:  # a neighbour without a stroke (the edge of the region): one side
            try:
                jac[:, k] = (model(x + e) - y) / 1e-5
            except NotSwimming:
                jac[:, k] = (y - model(x - e)) / 1e-5
    return jac


def _bootstrap(model, x, mean, sem, n, seed):
    """Parametric bootstrap: refit data drawn from N(mean, sem); spread of log parameters."""
    from scipy.optimize import least_squares

    from .model import LOG_MAP

    rng = np.random.default_rng(seed)
    ys = []
    for _ in range(n):
        d = mean + sem * rng.standard_normal(3)
        penalty = Penalty()
        r = least_squares(lambda z, d=d, penalty=penalty: _weighted(model, z, d, sem, penalty)[0], x,
                          jac=lambda z: model_jacobian(model, z, model(z)) / sem[:, None], method="trf",
                          xtol=1e-12, ftol=1e-14, gtol=1e-14, max_nfev=40)
        ys.append(LOG_MAP @ r.x)
    return np.std(np.array(ys), axis=0, ddof=1)
