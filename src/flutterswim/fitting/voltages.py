"""``fit_voltages``: B, tau and kappa_E from the descriptors at several voltages at once.

The active curvature follows the field, kappa_E proportional to the voltage V (the paper's
Fig. 3b, and the model's kappa_E = chi / l): chi(V) = chi_ref V / v_ref. Each voltage adds three
descriptors for the same three unknowns, (log eta_perp, log chi_ref, log tau), so the
B-tau degeneracy of one voltage is broken by how the stroke changes with V, and the chi-square
of the 3 m residuals against its 3 m - 3 degrees of freedom tests the proportionality itself.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .._validate import ParameterError, positive
from ..params import Parameters, preset
from .fit import PAPER_GUESS, FitResult, Penalty, held_fixed, model_jacobian, paper_cost
from .model import DescriptorModel, NotSwimming, Unresolved, to_identifiable, to_physical
from .uncertainty import covariance, identifiability_card

__all__ = ["fit_voltages", "voltage_residuals"]


def _at(x: np.ndarray, v: float, v_ref: float) -> np.ndarray:
    """Identifiable coordinates at voltage v of the joint x = (log eta_perp, log chi_ref, log tau)."""
    return np.array([x[0], x[1] + math.log(v / v_ref), x[2]])


def voltage_residuals(model, x: np.ndarray, voltages, means, sems, v_ref: float) -> np.ndarray:
    """Descriptors at several voltages with kappa_E proportional to the voltage:
    chi(V) = chi_ref V / v_ref; x = (log eta_perp, log chi_ref, log tau)."""
    return np.concatenate([(model(_at(x, v, v_ref)) - mu) / se for v, mu, se in zip(voltages, means, sems)])


def _arrays(voltages, means, sems) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    v = np.asarray(voltages, float).ravel()
    mu, se = np.asarray(means, float), np.asarray(sems, float)
    if v.size < 2 or not np.all(np.isfinite(v)) or np.any(v <= 0) or np.unique(v).size != v.size:
        raise ParameterError(f"voltages={voltages!r} must be two or more distinct positive voltages")
    if mu.shape != (v.size, 3) or not np.all(np.isfinite(mu)) or np.any(mu <= 0):
        raise ParameterError(f"means (shape {mu.shape}) must be {v.size} rows of three positive numbers "
                             "(period s, advance mm, lateral mm), one per voltage")
    if se.shape != (v.size, 3) or not np.all(np.isfinite(se)) or np.any(se <= 0):
        raise ParameterError(f"sems (shape {se.shape}) must be {v.size} rows of three positive standard errors "
                             "(a voltage needs two or more trials)")
    return v, mu, se


def _p_value(chi2: float, jw: np.ndarray, n_trials, rng_seed: int = 0, draws: int = 20000) -> tuple[float, str]:
    """P(chi-square >= chi2) for the fit's 3 m residuals and 3 parameters: from the chi-square
    distribution when the SEMs are known, or, with ``n_trials`` (m,) (SEMs from so many trials,
    so each weighted residual is Student-t with n - 1 degrees of freedom), by simulation: t
    draws with the fit's Jacobian columns projected out (linearised). Returns (p, method)."""
    from scipy.stats import chi2 as chi2_dist

    dof = jw.shape[0] - jw.shape[1]
    if n_trials is None:
        return float(chi2_dist.sf(chi2, dof)), "chi-square distribution (SEMs taken as known)"
    nu = np.repeat(np.asarray(n_trials, float) - 1.0, 3)
    z = np.random.default_rng(rng_seed).standard_t(nu, (draws, nu.size))
    q, _ = np.linalg.qr(jw)
    r = z - (z @ q) @ q.T
    return float(np.mean(np.sum(r * r, axis=1) >= chi2)), (
        f"simulated ({draws} draws): Student-t residuals, SEMs from {', '.join(str(int(n)) for n in n_trials)} trials")


def fit_voltages(voltages, means, sems, *, v_ref: float | None = None, n_trials=None, base: Parameters | None = None,
                 guess=PAPER_GUESS, tip: str = "trailing", model=None, n_segments: int = 24,
                 extrapolate: bool = True, backend: str | None = None, workers: int | None = None) -> FitResult:
    """Fit (B, tau, kappa_E at ``v_ref``) to the means (m, 3) = (period [s], advance [mm],
    lateral [mm]) at ``voltages`` (m,) with standard errors ``sems`` (m, 3), kappa_E
    proportional to the voltage (SEM-weighted least squares, trust-region reflective).

    ``v_ref``: the voltage at which kappa_E is reported and ``guess`` = (B, tau, kappa_E) holds
    (default: the median voltage); when it is one of ``voltages``, the joint fit starts from
    the fit of its descriptors alone. The result's ``measured``, ``sem`` and ``model`` are (m, 3);
    its settings hold the voltages, kappa_E per volt, and the test of the fit: its chi-square
    over 3 m residuals with 3 parameters, and the p-value (from the chi-square distribution, or
    with ``n_trials`` (m,), the trials behind each voltage's SEMs, by simulation of Student-t
    residuals: SEMs from 2-10 trials make large chi-squares common); a small p-value says the
    data reject kappa_E proportional to V (or the model). Other arguments as
    :func:`flutterswim.fitting.fit`."""
    from scipy.optimize import least_squares

    from .fit import fit, on_backend, refine_while_stalled

    t0 = time.perf_counter()
    v, mu, se = _arrays(voltages, means, sems)
    v_ref = float(np.median(v)) if v_ref is None else positive("v_ref (the reference voltage, --voltage)", v_ref)
    if n_trials is not None:
        n_trials = np.asarray(n_trials)
        if n_trials.shape != v.shape or np.any(n_trials < 2) or np.any(n_trials != np.round(n_trials)):
            raise ParameterError(f"n_trials={n_trials!r} must be {v.size} whole numbers >= 2, one per voltage")
    base = preset("paper") if base is None else base
    if not isinstance(base, Parameters):
        raise ParameterError(f"base={base!r} must be flutterswim.Parameters")
    if guess is PAPER_GUESS:  # (carried to the base's geometry, as fit's)
        from .fit import default_guess

        guess = default_guess(base)
    B0, tau0, k0 = (positive(n, g) for n, g in zip(("guess B", "guess tau", "guess kappa_E"), guess))
    model = DescriptorModel(base, tip=tip, n_segments=n_segments, extrapolate=extrapolate) if model is None else model
    hit = np.nonzero(np.isclose(v, v_ref, rtol=0.0, atol=1e-9))[0]
    dof = 3 * v.size - 3

    def run(m) -> FitResult:
        def start() -> tuple[np.ndarray, str]:
            x0 = to_identifiable(base, B0, tau0, k0)
            if hit.size:
                # from the fit of v_ref's descriptors alone: the guess then holds at v_ref, and
                # kappa_E proportional to V carries it to the other voltages
                try:
                    one = fit(mu[hit[0]], se[hit[0]], base=base, guess=(B0, tau0, k0), model=m)
                    if one.converged:
                        return to_identifiable(base, one.B, one.tau, one.kappa_E), f"the fit at {v_ref:g} V alone"
                except NotSwimming:
                    pass
            return x0, "the guess"

        penalty = Penalty()

        def fun(x):
            try:
                return penalty.seen(voltage_residuals(m, x, v, mu, se, v_ref))
            except NotSwimming:  # no stroke at one of the voltages
                return penalty.failed(3 * v.size)

        def at_voltage(f, x, vk):
            try:
                return f(_at(x, vk, v_ref))
            except Unresolved:
                raise
            except NotSwimming as exc:
                _, _, k = to_physical(base, _at(x, vk, v_ref))
                raise NotSwimming(f"no stroke at {vk:g} V (kappa_E = {k * 1e-3:.4g} 1/mm, proportional to the voltage "
                                  f"from {v_ref:g} V, where the guess holds; another reference voltage, --voltage, "
                                  f"may start nearer): {exc}") from exc

        def jac(x):
            return np.vstack([at_voltage(lambda z: model_jacobian(m, z, m(z)), x, vk) / sk[:, None]
                              for vk, sk in zip(v, se)])

        x0, started = start()
        # (ftol relative: noisy data stop once the chi-square no longer falls by 1e-12 of itself)
        r = least_squares(fun, x0, jac=jac, method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=100)
        x = r.x
        y = np.array([m(_at(x, vk, v_ref)) for vk in v])
        jw = jac(x)
        B, tau, kE = to_physical(base, x)
        sens = np.vstack([model_jacobian(m, _at(x, vk, v_ref), yk) / yk[:, None] for vk, yk in zip(v, y)])
        chi2 = float(np.sum(((y - mu) / se) ** 2))
        # a chi-square above its degrees of freedom widens the 1-sigma by sqrt(chi2 / dof) (the
        # Birge ratio, the PDG's scale factor): SEMs from few trials are themselves uncertain,
        # and 2 trials per voltage gave chi2 = 52 for 6 (p = 0.43 allowing for that) with the
        # truth 3-5 of the unscaled sigmas away
        scale = math.sqrt(max(1.0, chi2 / dof)) if dof > 0 else 1.0
        cov = covariance(jw / scale)
        p_value, method = _p_value(chi2, jw, n_trials)
        x0B, x0tau, x0k = to_physical(base, x0)
        settings = {
            "tip": tip, "n_segments": getattr(m, "n_segments", n_segments),
            "extrapolate": bool(getattr(m, "_fine", None) is not None),
            "model": getattr(m, "resolution", type(m).__name__), "guess": list(guess),
            "start": {"from": started, "B_N_m2": x0B, "tau_s": x0tau, "kappa_E_per_m": x0k},
            "cost": "sem", "held_fixed": held_fixed(base),
            "uncertainty_weights": "sem",
            "voltages_V": v.tolist(), "v_ref_V": v_ref, "kappa_E_proportional_to_voltage": True,
            "kappa_E_per_m_per_V": kE / v_ref,
            "kappa_E_per_m_at_voltages": (kE * v / v_ref).tolist(),
            "chi2": chi2, "dof": dof, "p_value": p_value, "p_value_method": method,
            "sigma_scale": scale,  # sqrt(max(1, chi2 / dof)): the 1-sigma is the SEMs' times this
            "n_trials": None if n_trials is None else [int(n) for n in n_trials],
            "paper_C": "summed over the voltages",
        }
        return FitResult(B, tau, kE, cov.sigma_rel, cov.correlation, chi2,
                         float(sum(paper_cost(mk, yk) for mk, yk in zip(mu, y))), "sem", bool(r.success),
                         str(r.message), getattr(m, "evaluations", getattr(m, "n_evaluations", 0)),
                         time.perf_counter() - t0, mu, se, y, identifiability_card(jw, sens), settings=settings)

    def stalled(res, m) -> bool:
        return bool(getattr(m, "n_unresolved", 0)) and res.settings["p_value"] < 1e-3

    def misfit(res) -> str:
        return f"chi2 = {res.cost:.3g} for {dof} degrees of freedom"

    if backend is not None and hasattr(model, "prefetch"):
        return on_backend(model, backend, workers, lambda: refine_while_stalled(run, model, stalled, misfit))
    return refine_while_stalled(run, model, stalled, misfit)
