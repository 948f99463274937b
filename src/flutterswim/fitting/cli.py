"""CLI: ``flutterswim fit trials.csv --preset paper [--voltage 85] [--tip trailing] --out fit.json``."""

from __future__ import annotations

__all__ = ["register"]

#: below this many trials at the fitted voltage, the CLI notes how uncertain the SEMs are
FEW_TRIALS = 5


def _sem_factor(n: int) -> float:
    """The factor by which an SEM from n trials can miss the true one, 90 % two-sided: the
    larger of sqrt((n - 1) / chi2_0.05) and sqrt(chi2_0.95 / (n - 1)), n - 1 degrees of freedom."""
    from scipy.stats import chi2

    return float(max(((n - 1) / chi2.ppf(0.05, n - 1)) ** 0.5, (chi2.ppf(0.95, n - 1) / (n - 1)) ** 0.5))


def register(subparsers) -> None:
    p = subparsers.add_parser("fit", help="fit B, tau and kappa_E to a trials CSV, with uncertainty",
                              description="Fit B, tau and kappa_E (geometry and viscosity from the preset) to the "
                                          "per-voltage means and SEMs of a trials CSV "
                                          "(voltage_V, sample, period_s, advance_mm, lateral_mm).")
    p.add_argument("trials")
    p.add_argument("--preset", default="paper", help="geometry and viscosity (default: paper)")
    p.add_argument("--length-mm", type=float, default=None,
                   help="the sample's length l [mm] (default: the preset's, 3.7); the paper measured l, width and "
                        "thickness per sample and fitted B, tau and kappa_E")
    p.add_argument("--width-mm", type=float, default=None, help="the sample's full width [mm] (default: the preset's, 0.396)")
    p.add_argument("--thickness-mm", type=float, default=None,
                   help="the sample's full thickness [mm] (default: the preset's, 0.0083)")
    p.add_argument("--viscosity", type=float, default=None, help="the fluid's viscosity [Pa s] (default: the preset's, 8e-4)")
    p.add_argument("--voltage", type=float, default=None,
                   help="voltage to fit (default: the one with most trials); with --joint, the voltage at which "
                        "kappa_E is reported")
    p.add_argument("--joint", action="store_true",
                   help="fit every voltage with two or more trials at once, kappa_E proportional to the voltage "
                        "(the chi-square of the fit tests the proportionality)")
    p.add_argument("--tip", choices=("trailing", "leading"), default="trailing",
                   help="which end's lateral excursion the CSV holds (default: trailing)")
    p.add_argument("--paper-cost", action="store_true", help="the paper's cost and bounds instead of SEM-weighted least squares")
    p.add_argument("--profiles", action="store_true", help="also compute profile likelihoods (slower)")
    p.add_argument("--bootstrap", type=int, default=0, help="parametric bootstrap refits (default 0)")
    p.add_argument("--starts", type=int, default=0,
                   help="also fit from this many starts over the paper's box and report every other parameter set "
                        "that fits as well (each start is a fit of 10-40 s; default 0)")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the bootstrap's draws and of the --starts points (default 0: a rerun repeats them)")
    p.add_argument("--segments", type=int, default=24,
                   help="segments of the model filament (default 24): the descriptors are extrapolated to the "
                        "continuum from N and 2N segments (within 0.05 %% of it at the paper's point)")
    p.add_argument("--no-extrapolate", action="store_true",
                   help="use the orbits of --segments alone, e.g. for data made by a model of that resolution "
                        "(24 alone puts the paper's advance 1.8 %% above the continuum and moves B, tau, kappa_E "
                        "by 4-6 %%)")
    p.add_argument("--backend", default=None,
                   help="compute the finite-difference orbits in parallel: processes, dask-local, dask (default: in this process)")
    p.add_argument("--workers", type=int, default=None, help="worker processes for --backend")
    p.add_argument("--out", default="fit.json")
    p.add_argument("--plot", default=None, help="figure of the data (Fig. 3e), the fit and its profiles")
    p.set_defaults(func=_cmd_fit)


def _cmd_fit(args) -> int:
    import sys

    import numpy as np

    from .._paths import check_output_file
    from .._validate import ParameterError, positive_int
    from ..params import preset
    from .data import check_spread, read_trials, summarise
    from .fit import fit

    out = check_output_file(args.out, (".json",), kind="fit")
    if args.plot:
        check_output_file(args.plot, (".png", ".pdf", ".svg"), what="--plot")
    base = _geometry(args, preset(args.preset))
    if args.workers is not None and args.backend is None:  # (it was ignored without a word)
        raise ParameterError(f"--workers={args.workers} needs --backend (processes, dask-local, ...): without one "
                             "the fit runs in this process")
    from .fit import MAX_BOOTSTRAP, MAX_STARTS

    # before the data are read or anything is fitted
    positive_int("--bootstrap", args.bootstrap, 0, MAX_BOOTSTRAP, "each draw is a refit: 10^4 take hours")
    positive_int("--starts", args.starts, 0, MAX_STARTS, "each start is a fit of 10-40 s")
    if args.joint and (args.paper_cost or args.profiles or args.bootstrap or args.starts):
        raise ParameterError("--joint fits by the SEM-weighted cost, without profiles, bootstrap or starts: "
                             "--paper-cost, --profiles, --bootstrap and --starts are for one voltage")
    if args.starts and args.paper_cost:
        raise ParameterError(f"--starts={args.starts} searches with the SEM-weighted cost; --paper-cost takes none")
    trials = read_trials(args.trials)
    from .data import check_geometry

    summary = summarise(trials)
    if args.joint:
        fitted = summary.voltage_V[np.all(np.isfinite(summary.sem), axis=1)]
        _geometry_note(check_geometry(trials, base, fitted))
        return _joint(args, base, trials, summary, out)
    v = args.voltage if args.voltage is not None else float(summary.voltage_V[np.argmax(summary.n)])
    _geometry_note(check_geometry(trials, base, [v]))
    mean, sem = summary.at(v)
    if not args.paper_cost:
        check_spread(trials, summary, [summary.voltage_V[np.isclose(summary.voltage_V, v)][0]])
    if not args.paper_cost and not np.all(np.isfinite(sem)):
        raise ParameterError(f"voltage {v:g} V has {int(summary.n[np.isclose(summary.voltage_V, v)][0])} trial(s): "
                             "the SEM needs at least two (or use --paper-cost)")
    from .model import OutsideModel

    usable = bool(np.all(np.isfinite(sem) & (sem > 0)))
    if args.paper_cost and not usable:
        import sys

        # (a descriptor without spread, e.g. periods quantised by the frame rate: the paper's cost
        # takes no SEM, and was handed a zero one, refused as an API argument)
        print(f"flutterswim fit: note: voltage {v:g} V has no standard error for every descriptor (a single trial, or "
              "trials that agree exactly): the paper's cost is fitted without standard errors", file=sys.stderr)
    try:
        res = fit(mean, sem if usable else None, base=base,
                  cost="paper" if args.paper_cost else "sem", tip=args.tip, profiles=args.profiles,
                  bootstrap=args.bootstrap, n_segments=args.segments, extrapolate=not args.no_extrapolate,
                  backend=args.backend, workers=args.workers, starts=args.starts, seed=args.seed)
    except OutsideModel as exc:  # a failure of the fit, not bad input: one line, exit 1
        print(f"flutterswim fit: failed: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1
    from dataclasses import replace

    res = replace(res, settings={**res.settings, "voltage_V": float(v)})  # (kappa_E is this voltage's)
    res.save(out)
    if res.settings.get("out_of_reach") or not res.converged:
        # no values to speak of: the one line why (the JSON has the rest; a failed fit's values
        # printed as a result's read as one)
        return _verdict(res)
    if res.at_fold and res.cost >= 1.0 and not args.profiles:
        # (it exited 0, status "converged": a script took values 5-58 % off, with a 1-sigma of
        # 1e5 %); within the standard errors (chi2 < 1) the data are consistent with it, and the
        # status and the note say what the values are
        print(f"flutterswim fit: failed: the fit stopped on a fold of the model, not at a solution, and misses the data "
              f"by chi2 = {res.cost:.3g} (status at_fold in {out}): {res.fold_note}", file=sys.stderr)
        return 1
    n = int(summary.n[np.isclose(summary.voltage_V, v)][0])
    if not args.paper_cost and n < FEW_TRIALS:
        print(f"flutterswim fit: note: the SEMs at {v:g} V come from {n} trials, so the reported 1-sigma is itself "
              f"uncertain (from {n} trials, within a factor {_sem_factor(n):.2g} either way at 90 %), and it covers "
              "the trials' scatter only, not an error common to them (tracking, frame rate"
              + (", the model's resolution: --no-extrapolate" if args.no_extrapolate else "") + ")",
              file=sys.stderr)
    s = res.sigma_rel
    pm = (["1-sigma undetermined: at a fold"] * 3 if res.at_fold else [f"+-{100 * x:.2g}%" for x in s])
    print(f"{out}: B = {res.B * 1e6:.4g} N mm^2 ({pm[0]}), tau = {res.tau:.4g} s ({pm[1]}), "
          f"kappa_E = {res.kappa_E * 1e-3:.4g} 1/mm ({pm[2]}) at {v:g} V"
          + ("" if res.settings.get("uncertainty_weights") == "sem" else
             " (1-sigma from an assumed 5 % error per descriptor: no SEMs)")
          + f"; paper cost C = {res.paper_cost:.3g}; {res.card.describe()}")
    for o in res.settings.get("other_solutions", ()):
        where = "inside" if o["in_box"] else "outside"
        print(f"flutterswim fit: note: another parameter set, {where} the paper's box (0.5-1.5 x the guess), fits "
              f"these data {'as well' if o['chi2'] <= res.cost + 1.0 else 'nearly as well'}: "
              f"B = {o['B_N_m2'] * 1e6:.4g} N mm^2, tau = {o['tau_s']:.4g} s, "
              f"kappa_E = {o['kappa_E_per_m'] * 1e-3:.4g} 1/mm (chi2 {o['chi2']:.3g}, the fit's {res.cost:.3g}); "
              "the three descriptors do not tell them apart (shapes, the onset or several voltages do)",
              file=sys.stderr)
    st = res.settings.get("starts") or {}
    if args.starts and "skipped" in st:
        print(f"flutterswim fit: the {args.starts} starts were not searched: {st['skipped']}", file=sys.stderr)
    elif args.starts:
        others = max(0, int(st.get("distinct_solutions", 1)) - 1)
        print(f"flutterswim fit: {args.starts} starts over the paper's box: {st.get('converged', 0)} converged, "
              f"{st.get('no_stroke_at_start', 0)} without a stroke at the start; {others} other parameter set(s) "
              "fit as well" + ("" if others else " (which does not show that the fit is unique: the search finds "
                               "a second solution in some cases only)"), file=sys.stderr)
    r, pair = _strongest_correlation(res)
    if res.at_fold:
        print(f"flutterswim fit: note: {res.fold_note}", file=sys.stderr)
    elif res.weakly_determined:
        print(f"flutterswim fit: note: {res.weakly_determined}", file=sys.stderr)
    elif not args.profiles and r > STRONG_CORRELATION:
        # (the +-20 % hid a second exact solution 60-73 % away, which the profiles showed)
        print(f"flutterswim fit: note: {pair} are correlated by {r:.2f}: the 1-sigma is the cost's curvature at the "
              "fit, and along that direction the data may allow far more (or another exact solution); --profiles "
              "gives the range, --starts searches for other solutions", file=sys.stderr)
    if res.at_bound:
        print(f"flutterswim fit: note: {', '.join(res.at_bound)} ended on the bound of the paper's box (factor 0.5 or "
              "1.5 of the guess): the data ask for a value beyond it, so that value is the bound's, not the fit's "
              "(without --paper-cost the fit is unbounded)", file=sys.stderr)
    _plot(args, res, summary, trials, v)
    return _verdict(res)


def _geometry_note(note: str) -> None:
    if note:
        import sys

        print(f"flutterswim fit: note: {note}", file=sys.stderr)


def _geometry(args, base):
    """The preset with the sample's geometry and viscosity given on the command line."""
    from .._validate import positive

    change = {}
    for opt, name, factor in (("length_mm", "l", 1e-3), ("width_mm", "b", 0.5e-3), ("thickness_mm", "a", 0.5e-3),
                              ("viscosity", "mu", 1.0)):
        v = getattr(args, opt)
        if v is not None:
            change[name] = positive(f"--{opt.replace('_', '-')}", v) * factor
    if not change:
        return base
    from .._validate import ParameterError

    try:
        return base.replace(**change)
    except ParameterError as exc:  # (it named b in metres, not the option typed)
        given = ", ".join(f"--{o.replace('_', '-')}={getattr(args, o)!r}" for o in
                          ("length_mm", "width_mm", "thickness_mm", "viscosity") if getattr(args, o) is not None)
        raise ParameterError(f"{given}: {exc} (b is half the width, a half the thickness)") from None


#: a correlation beyond this, without profiles, is noted (the 1-sigma is local along it)
STRONG_CORRELATION = 0.95


def _strongest_correlation(res) -> tuple[float, str]:
    """(|r|, "a and b") of the most correlated pair of the fit's parameters (0 when undefined)."""
    import numpy as np

    from .uncertainty import NAMES

    c = np.abs(np.nan_to_num(np.asarray(res.correlation, float), nan=0.0))
    np.fill_diagonal(c, 0.0)
    i, j = np.unravel_index(int(np.argmax(c)), c.shape)
    return float(c[i, j]), f"{NAMES[min(i, j)]} and {NAMES[max(i, j)]}"


def _verdict(res) -> int:
    """0 for a converged fit; otherwise one line saying why (the values are in the JSON) and 1."""
    if res.converged:
        return 0
    import sys

    print(f"flutterswim fit: failed: {res.failure}", file=sys.stderr)
    return 1


def _plot(args, res, summary, trials, v) -> None:
    if args.plot:
        from .plot import plot_fit

        plot_fit(res, summary, trials, args.plot, voltage=v)
        print(f"figure: {args.plot}")


def _joint(args, base, trials, summary, out) -> int:
    import sys

    import numpy as np

    from .._validate import ParameterError
    from .voltages import fit_voltages

    ok = np.all(np.isfinite(summary.sem), axis=1)
    from .data import check_spread

    check_spread(trials, summary, summary.voltage_V[ok])
    if ok.sum() < 2:
        raise ParameterError(f"--joint needs two or more voltages with two or more trials each; the CSV has "
                             f"{int(ok.sum())} ({', '.join(f'{v:g} V' for v in summary.voltage_V[ok]) or 'none'})")
    volts = summary.voltage_V[ok]
    if args.voltage is not None:
        v_ref = args.voltage
    else:  # the voltage with most trials, of those the one nearest the middle of the range
        most = volts[summary.n[ok] == summary.n[ok].max()]
        v_ref = float(most[np.argmin(np.abs(most - np.median(volts)))])
    res = fit_voltages(volts, summary.mean[ok], summary.sem[ok], v_ref=v_ref, n_trials=summary.n[ok].astype(int),
                       base=base, tip=args.tip,
                       n_segments=args.segments, extrapolate=not args.no_extrapolate, backend=args.backend,
                       workers=args.workers)
    res.save(out)
    if not ok.all():
        print("flutterswim fit: note: left out (one trial, no SEM): "
              + ", ".join(f"{v:g} V" for v in summary.voltage_V[~ok]), file=sys.stderr)
    few = [(v, int(n)) for v, n in zip(volts, summary.n[ok]) if n < FEW_TRIALS]
    if few:
        print("flutterswim fit: note: the SEMs at " + ", ".join(f"{v:g} V ({n} trials)" for v, n in few)
              + " come from fewer than 5 trials, so the reported 1-sigma is itself uncertain (the p-value allows "
              "for it: Student-t residuals)", file=sys.stderr)
    if not res.converged:
        return _verdict(res)
    s, st = res.sigma_rel, res.settings
    print(f"{out}: B = {res.B * 1e6:.4g} N mm^2 (+-{100 * s[0]:.2g}%), tau = {res.tau:.4g} s (+-{100 * s[1]:.2g}%), "
          f"kappa_E = {res.kappa_E * 1e-3:.4g} 1/mm (+-{100 * s[2]:.2g}%) at {v_ref:g} V "
          f"({st['kappa_E_per_m_per_V'] * 1e-3:.4g} 1/mm per V) from {len(volts)} voltages; chi2 = {st['chi2']:.3g} "
          f"for {st['dof']} degrees of freedom (p = {st['p_value']:.3g}"
          + (f"; 1-sigma widened x{st['sigma_scale']:.3g}, sqrt(chi2 / dof)" if st.get("sigma_scale", 1.0) > 1 else "")
          + ("; the data reject kappa_E proportional to V, or the model" if st["p_value"] < 0.01 else "")
          + f"); {res.card.describe()}")
    _plot(args, res, summary, trials, v_ref)
    return _verdict(res)
