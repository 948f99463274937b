"""Targets from the linear theory: Table 1 with the derived groups, the two readings of b,
and Fig. 6 (stability map, bifurcation plots, first and second eigenmodes)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..params import PAPER, Parameters
from .io import save_figure, write_netcdf
from .targets import Context, Outcome, Settings, compare, cross_check, verdict

__all__ = ["readings", "mode_fields", "build_table1", "build_b_readings", "build_fig6a", "build_fig6b",
           "build_fig6cd", "PAPER_ONSET_RATIO"]

#: "a critical value of kappa_E,cr / kappa_E,fit ~ 0.65" (paper, section MOD:SIM)
PAPER_ONSET_RATIO = 0.65


def readings(params: Parameters = PAPER) -> dict[str, Parameters]:
    """The two readings of b in ln(2l/b): the semi-axis as printed (the table's width is 2b,
    so b is half the width) and the full width (b replaced by 2b)."""
    return {"semi-axis": params, "full width": params.replace(b=2.0 * params.b)}


def _var(dims, values, units, long_name):
    return (dims, np.asarray(values), {"units": units, "long_name": long_name})


# --- Table 1 -----------------------------------------------------------------------------
def table1_params(s: Settings) -> dict:
    return {"params": PAPER.to_dict()}


TABLE1_ROWS = (  # (label, paper value, unit, our value in the table's unit)
    ("Filament's length, l", 3.70, "mm", lambda p: p.l * 1e3),
    ("Filament's width, 2b", 3.96e-1, "mm", lambda p: 2 * p.b * 1e3),
    ("Filament's thickness, 2a", 8.30e-3, "mm", lambda p: 2 * p.a * 1e3),
    ("Bending stiffness, B", 1.94e-8, "N mm^2", lambda p: p.B * 1e6),
    ("Relaxation time, tau", 3.75e-1, "s", lambda p: p.tau),
    ("Target curvature, kappa_E", 1.91e1, "1/mm", lambda p: p.kappa_E * 1e-3),
    ("Viscosity, mu (rheometry)", 8e-4, "Pa s", lambda p: p.mu),
)


def build_table1(ctx: Context) -> Outcome:
    from .datasets import table1_dataset

    p = PAPER
    rows = [dataclasses.replace(compare(label, paper, f(p), unit=unit, rtol=1e-6), is_input=True)
            for label, paper, unit, f in TABLE1_ROWS]
    derived = []
    for name, pr in readings(p).items():
        g = pr.groups
        derived += [
            compare(f"mu_par = 4 pi mu / (2 ln(2l/b) - 1) [{name}]", None, pr.mu_par * 1e3, unit="mPa s",
                    paper_text="the paper's formula for the resistive coefficients"),
            compare(f"mu_perp = 4 pi mu / ln(2l/b) [{name}]", None, pr.mu_perp * 1e3, unit="mPa s",
                    paper_text="formula"),
            compare(f"eta_par = mu_par l^4/(B tau) [{name}]", None, g.eta_par, paper_text="defined, not stated"),
            compare(f"eta_perp = mu_perp l^4/(B tau) [{name}]", None, g.eta_perp, paper_text="defined, not stated"),
        ]
    derived += [compare("chi = kappa_E l", None, p.chi, paper_text="defined, not stated"),
                compare("force scale B / l^2", None, p.force_scale * 1e9, unit="nN", paper_text="scaling"),
                compare("time scale tau", None, p.tau, unit="s", paper_text="scaling")]
    values = {"params_SI": p.to_dict(), "groups": {k: r.groups.to_dict() for k, r in readings(p).items()},
              "mu_par": {k: r.mu_par for k, r in readings(p).items()},
              "mu_perp": {k: r.mu_perp for k, r in readings(p).items()}}
    write_netcdf(ctx.path("table1_data.nc"), table1_dataset(p, readings(p)))
    return Outcome("ok", tuple(rows + derived), ("The table lists the width 2b and the thickness 2a, so "
                   "b and a are semi-axes; the groups are given for both readings of b in ln(2l/b).",), values)


# --- the two readings of b ---------------------------------------------------------------
def b_params(s: Settings) -> dict:
    return {"params": PAPER.to_dict(), "n_segments": s.pick(24, 48), "step": s.pick(0.01, 0.002)}


def build_b_readings(ctx: Context) -> Outcome:
    import xarray as xr

    from ..orbits import hopf_point
    from ..stability import bifurcation, critical_chi, leading_eigenvalue
    from .plots import plot_b_readings

    prm = b_params(ctx.settings)
    ratios = np.round(np.arange(0.3, 1.2 + prm["step"] / 2, prm["step"]), 10)
    out, rows, growth = {}, [], {}
    for name, p in readings().items():
        g = p.groups
        chi_cr, beta_cr = critical_chi(g.eta_perp)
        le = leading_eigenvalue(g.chi, g.eta_perp)
        hp = hopf_point(p, "kappa_E_ratio", n_segments=prm["n_segments"])
        bif = bifurcation(parameter="chi", values=ratios * g.chi, fixed=g.eta_perp)
        growth[name] = bif.omega
        out[name] = {"b_m": p.b, "eta_par": g.eta_par, "eta_perp": g.eta_perp, "chi": g.chi,
                     "chi_cr": chi_cr, "onset_ratio": chi_cr / g.chi, "onset_omega_per_tau": beta_cr,
                     "onset_period_s": 2 * math.pi * p.tau / beta_cr,
                     "onset_ratio_discrete": hp.value, "discrete_n_segments": prm["n_segments"],
                     "omega_max_real": le.omega.real, "omega_max_imag": le.omega.imag}
        rows.append(compare(f"onset kappa_E,cr / kappa_E,fit, b = {name} (b = {p.b * 1e3:.3f} mm)",
                            PAPER_ONSET_RATIO, chi_cr / g.chi, rtol=0.02, paper_text="~ 0.65"))
        rows.append(cross_check(f"same, discrete model (N = {prm['n_segments']}) Hopf point, b = {name}",
                                chi_cr / g.chi, hp.value, rtol=0.01, reference="linear threshold (continuum)"))
    semi, full = out["semi-axis"], out["full width"]
    rows.append(verdict("which reading gives the paper's ~0.65", "the paper's onset ~ 0.65",
                        f"semi-axis {semi['onset_ratio']:.3f}, full width {full['onset_ratio']:.3f}",
                        abs(full["onset_ratio"] - 0.65) < abs(semi["onset_ratio"] - 0.65)))
    ds = xr.Dataset(
        {f"re_omega_{k}": _var(("kappa_E_ratio",), growth[n].real, "1/tau",
                               f"growth rate Re omega_max, b read as the {n}")
         for k, n in (("semi", "semi-axis"), ("full", "full width"))}
        | {f"im_omega_{k}": _var(("kappa_E_ratio",), growth[n].imag, "1/tau",
                                 f"angular frequency Im omega_max, b read as the {n}")
           for k, n in (("semi", "semi-axis"), ("full", "full width"))},
        coords={"kappa_E_ratio": ("kappa_E_ratio", ratios, {"units": "1", "long_name": "kappa_E / kappa_E,fit"})},
        attrs={"title": "flutterswim reproduce: the two readings of b in ln(2l/b), growth rate of the straight state",
               **{f"onset_ratio_{k}": out[n]["onset_ratio"] for k, n in (("semi", "semi-axis"), ("full", "full width"))},
               "onset_ratio_semi_units": "1", "onset_ratio_full_units": "1"},
    )
    write_netcdf(ctx.path("b_readings.nc"), ds)
    fig = plot_b_readings(ratios, growth, out, PAPER_ONSET_RATIO)
    save_figure(fig, ctx.path("b_readings.png"))
    notes = (f"ln(2l/b) with b the semi-axis (as printed, b = {PAPER.b * 1e3:.3f} mm) gives the onset "
             f"kappa_E,cr/kappa_E,fit = {semi['onset_ratio']:.4f}; with b the full width "
             f"({2 * PAPER.b * 1e3:.3f} mm) it gives {full['onset_ratio']:.4f}. The paper's ~0.65 matches only "
             "the full width. flutterswim's preset keeps the printed reading (semi-axis).",)
    return Outcome("ok", tuple(rows), notes, {"readings": out})


# --- Fig. 6a ----------------------------------------------------------------------------
def fig6a_params(s: Settings) -> dict:
    return {"step": s.pick(1.0, 0.1), "neutral_step": s.pick(0.5, 0.1), "params": PAPER.to_dict()}


def build_fig6a(ctx: Context) -> Outcome:
    import xarray as xr

    from ..stability import leading_eigenvalue, neutral_curve, stability_map
    from ..stability.plots import plot_map

    prm = fig6a_params(ctx.settings)
    g = PAPER.groups
    smap = stability_map(step=prm["step"])
    nc = neutral_curve(step=prm["neutral_step"])
    ds = smap.to_dataset()
    ds.attrs.pop("check_max_rel_diff", None)
    ds.attrs.pop("source", None)  # write_netcdf's: flutterswim <version> reproduce
    ds.attrs["title"] = "flutterswim reproduce: Fig. 6a, stability map (leading eigenvalue of the straight state)"
    ds.attrs["operating_eta_perp"], ds.attrs["operating_chi"] = g.eta_perp, g.chi
    enc = {k: {"zlib": True, "complevel": 4, "shuffle": True, "dtype": "float32" if not ctx.settings.quick else "float64"}
           for k in ("re_omega", "im_omega")}
    write_netcdf(ctx.path("fig6a_map.nc"), ds, encoding=enc)
    nds = xr.Dataset({"chi_cr": _var(("eta_perp",), nc.chi_cr, "1", "critical chi (Hopf), chi > 0 branch"),
                      "beta": _var(("eta_perp",), nc.beta, "1/tau", "angular frequency at onset")},
                     coords={"eta_perp": ("eta_perp", nc.eta_perp, {"units": "1", "long_name": "normal drag group eta_perp"})},
                     attrs={"title": "flutterswim reproduce: Fig. 6a, neutral curve (critical chi of the Hopf onset "
                                     "against eta_perp)"})
    write_netcdf(ctx.path("fig6a_neutral.nc"), nds)
    fig = plot_map(smap, neutral=nc, operating_point=(g.eta_perp, g.chi))
    fig.axes[0].set_title("Fig. 6a: stability map (leading eigenvalue of the straight state)", fontsize=9)
    save_figure(fig, ctx.path("fig6a.png"))
    le = leading_eigenvalue(g.chi, g.eta_perp)
    # map boundary (sign change of Re omega in chi at each eta_perp) vs the neutral curve
    re = smap.omega.real
    pos = smap.chi > 0
    diffs = []
    for i, e in enumerate(smap.eta_perp):
        crit = np.interp(e, nc.eta_perp, nc.chi_cr)
        row = re[i, pos]
        k = np.flatnonzero((row[:-1] <= 0) & (row[1:] > 0))
        if k.size and np.isfinite(crit):
            c0, c1 = smap.chi[pos][k[0]], smap.chi[pos][k[0] + 1]
            x = c0 + (c1 - c0) * (-row[k[0]]) / (row[k[0] + 1] - row[k[0]])
            diffs.append(abs(x - crit))
    worst = float(np.max(diffs)) if diffs else math.nan
    inside = nc.chi_cr <= 130.0
    eta_exit = float(nc.eta_perp[np.flatnonzero(inside)[0]]) if np.any(inside) else math.nan
    rows = (
        verdict("operating point (Table 1) in the flutter region", "the fitted swimmer flutters",
                f"Re omega_max = {le.omega.real:.4f} /tau > 0" if le.unstable else f"Re omega_max = {le.omega.real:.4f}",
                le.flutter),
        verdict("the sign of chi sets the swimming direction, not the stability",
                "map symmetric about chi = 0", "omega(chi) = omega(-chi) (spectrum invariant under chi -> -chi)",
                bool(np.allclose(re, re[:, ::-1], equal_nan=True)) if np.allclose(smap.chi, -smap.chi[::-1]) else True),
        verdict("the threshold leaves |chi| <= 130 at small eta_perp", "exits the range for small eta_perp",
                f"chi_cr > 130 for eta_perp < {eta_exit:.3g}", bool(np.isfinite(eta_exit) and eta_exit > 0)),
        compare("map boundary vs Hopf-Newton neutral curve (largest |Delta chi|)", None, worst,
                paper_text="one boundary", fmt="{:.2e}"),
    )
    values = {"omega_max_real": le.omega.real, "omega_max_imag": le.omega.imag, "eta_exit": eta_exit,
              "boundary_vs_neutral_max": worst, "step": prm["step"]}
    return Outcome("ok", rows, (f"Grid step {prm['step']} in eta_perp and chi (the paper: 0.1).",), values)


# --- Fig. 6b ----------------------------------------------------------------------------
def fig6b_params(s: Settings) -> dict:
    return {"step": s.pick(0.5, 0.1), "params": PAPER.to_dict()}


def build_fig6b(ctx: Context) -> Outcome:
    import xarray as xr

    from ..stability import bifurcation, critical_chi, leading_eigenvalue
    from ..stability.plots import plot_bifurcation

    step = fig6b_params(ctx.settings)["step"]
    g = PAPER.groups
    b1 = bifurcation(parameter="chi", values=np.round(np.arange(step, 130.0 + step / 2, step), 10), fixed=g.eta_perp)
    b2 = bifurcation(parameter="eta_perp", values=np.round(np.arange(step, 350.0 + step / 2, step), 10), fixed=g.chi)
    ds = xr.Dataset({
        "re_omega_vs_chi": _var(("chi",), b1.omega.real, "1/tau", f"Re omega_max at eta_perp = {g.eta_perp:.6g}"),
        "im_omega_vs_chi": _var(("chi",), b1.omega.imag, "1/tau", f"Im omega_max at eta_perp = {g.eta_perp:.6g}"),
        "re_omega_vs_eta_perp": _var(("eta_perp",), b2.omega.real, "1/tau", f"Re omega_max at chi = {g.chi:.6g}"),
        "im_omega_vs_eta_perp": _var(("eta_perp",), b2.omega.imag, "1/tau", f"Im omega_max at chi = {g.chi:.6g}"),
    }, coords={"chi": ("chi", b1.values, {"units": "1", "long_name": "activity group chi = kappa_E l"}),
               "eta_perp": ("eta_perp", b2.values, {"units": "1", "long_name": "normal drag group eta_perp"})},
        attrs={"title": "flutterswim reproduce: Fig. 6b, leading eigenvalue against chi and against eta_perp",
               "fixed_eta_perp": g.eta_perp, "fixed_chi": g.chi})
    write_netcdf(ctx.path("fig6b.nc"), ds)
    fig = plot_bifurcation([b1, b2])
    for ax, x0 in zip(fig.axes, (g.chi, g.eta_perp)):
        ax.axvline(x0, color="0.4", ls=":", lw=1)
        ax.text(x0, 0.02, " operating point", transform=ax.get_xaxis_transform(), fontsize=7, color="0.3")
    fig.suptitle("Fig. 6b: leading eigenvalue against chi and against eta_perp", fontsize=9)
    # (the panels' constrained layout places the title)
    save_figure(fig, ctx.path("fig6b.png"))
    chi_cr, _ = critical_chi(g.eta_perp)
    k = np.flatnonzero((b1.omega.real[:-1] <= 0) & (b1.omega.real[1:] > 0))
    cross = float(np.interp(0.0, b1.omega.real[k[0]:k[0] + 2], b1.values[k[0]:k[0] + 2])) if k.size else math.nan
    k2 = np.flatnonzero((b2.omega.real[:-1] <= 0) & (b2.omega.real[1:] > 0))
    eta_cr = float(np.interp(0.0, b2.omega.real[k2[0]:k2[0] + 2], b2.values[k2[0]:k2[0] + 2])) if k2.size else math.nan
    le = leading_eigenvalue(g.chi, g.eta_perp)
    rows = (
        verdict("oscillatory solutions for every chi != 0", "Im omega_max != 0 for chi != 0",
                f"min Im omega_max over chi in (0, 130] = {b1.omega.imag.min():.3g} /tau", bool(b1.omega.imag.min() > 0)),
        cross_check("Re omega_max = 0 crossing in chi (interpolated) vs Hopf-Newton chi_cr", chi_cr, cross, rtol=2e-3,
                    reference=f"damped below a critical chi (chi_cr = {chi_cr:.4f}, linear theory)"),
        compare("critical eta_perp at the paper's chi", None, eta_cr, paper_text="flutter needs eta_perp large enough"),
        compare("leading eigenvalue Re omega_max at the operating point", None, le.omega.real, unit="1/tau",
                paper_text="> 0 (flutter)"),
        compare("leading eigenvalue Im omega_max at the operating point", None, le.omega.imag, unit="1/tau",
                paper_text="!= 0"),
        compare("linear period 2 pi tau / Im omega_max", None, 2 * math.pi * PAPER.tau / le.omega.imag, unit="s",
                paper_text="not stated"),
    )
    return Outcome("ok", rows, (), {"chi_cross": cross, "chi_cr": chi_cr, "eta_cr": eta_cr,
                                    "omega_max": [le.omega.real, le.omega.imag]})


# --- Fig. 6c-d --------------------------------------------------------------------------
def mode_fields(omega: complex, chi: float, eta_perp: float, s: np.ndarray) -> dict[str, np.ndarray]:
    """Mode r(s) = sum_i c_i exp(lambda_i (s - s_i)) from the kernel of the boundary matrix
    (as in :func:`flutterswim.stability.mode_shape`), with its derivatives r', r'', r''',
    r'''' and kappa = -chi/(1+omega) r', kappa' (all (n,) complex, normalised so that r = 1
    where |r| is largest)."""
    from ..stability import quartic_roots

    lam = quartic_roots(omega, chi, eta_perp)
    c = chi / (omega + 1.0)
    shift = np.where(lam.real > 0, 1.0, 0.0)
    a = lam * (lam + c)
    e0, e1 = np.exp(-lam * shift), np.exp(lam * (1.0 - shift))
    bm = np.array([a * e0, lam * a * e0, a * e1, lam * a * e1])
    colscale = np.maximum(np.abs(bm).max(axis=0), 1e-300)
    _, sv, vh = np.linalg.svd(bm / colscale)
    coef = vh[-1].conj() / colscale
    E = np.exp(lam[None, :] * (s[:, None] - shift[None, :]))
    d = [E @ (coef * lam**k) for k in range(5)]
    norm = d[0][int(np.argmax(np.abs(d[0])))]
    d = [x / norm for x in d]
    return {"r": d[0], "r_s": d[1], "r_ss": d[2], "r_sss": d[3], "r_ssss": d[4],
            "kappa": -c * d[1], "kappa_s": -c * d[2], "residual": np.array(sv[-1] / sv[0])}


def fig6cd_params(s: Settings) -> dict:
    return {"n_points": s.pick(401, 2001), "params": PAPER.to_dict()}


def build_fig6cd(ctx: Context) -> Outcome:
    import xarray as xr

    from ..stability import eigenmodes
    from ..stability.plots import plot_modes

    n = fig6cd_params(ctx.settings)["n_points"]
    g = PAPER.groups
    modes = eigenmodes(g.chi, g.eta_perp, n_points=n)
    s = modes[0].s
    data, attrs = {}, {"title": "flutterswim reproduce: Fig. 6c-d, first and second eigenmodes at the operating point",
                       "chi": g.chi, "eta_perp": g.eta_perp}
    names = {"r": ("1", "lateral displacement r_2(s) / max|r_2|"), "r_s": ("1", "d r/ds"), "r_ss": ("1", "d2 r/ds2 (curvature theta_s)"),
             "r_sss": ("1", "d3 r/ds3"), "r_ssss": ("1", "d4 r/ds4"), "kappa": ("1", "spontaneous curvature kappa(s) l"),
             "kappa_s": ("1", "d kappa/ds")}
    for m in modes:
        f = mode_fields(m.omega, g.chi, g.eta_perp, s)
        for key, (u, ln) in names.items():
            data[f"mode{m.rank}_{key}_re"] = _var(("s",), f[key].real, u, f"mode {m.rank}: {ln}, real part")
            data[f"mode{m.rank}_{key}_im"] = _var(("s",), f[key].imag, u, f"mode {m.rank}: {ln}, imaginary part")
        attrs[f"mode{m.rank}_omega_re"], attrs[f"mode{m.rank}_omega_im"] = m.omega.real, m.omega.imag
        attrs[f"mode{m.rank}_kernel_residual"] = float(f["residual"])
    ds = xr.Dataset(data, coords={"s": ("s", s, {"units": "1", "long_name": "arc length s / l"})}, attrs=attrs)
    write_netcdf(ctx.path("fig6cd.nc"), ds)
    fig = plot_modes(modes)
    fig.suptitle("Fig. 6c-d: first and second eigenmodes at the operating point", fontsize=9)
    # (the panels' constrained layout places the title)
    save_figure(fig, ctx.path("fig6cd.png"))
    bc = []
    for m in modes:
        f = mode_fields(m.omega, g.chi, g.eta_perp, np.array([0.0, 1.0]))
        bc.append(float(np.max(np.abs(np.r_[f["r_ss"] - f["kappa"], f["r_sss"] - f["kappa_s"]]))))
    r1 = modes[0].r
    cosang = abs(np.vdot(r1.real, r1.imag)) / (np.linalg.norm(r1.real) * np.linalg.norm(r1.imag))
    rows = (
        verdict("mode 1 grows (largest Re omega)", "leading eigenvalue, Re > 0",
                f"omega_1 = {modes[0].omega.real:.4f} + {modes[0].omega.imag:.4f}i /tau", modes[0].omega.real > 0),
        verdict("mode 2 decays", "the second eigenvalue has negative real part",
                f"omega_2 = {modes[1].omega.real:.4f} + {modes[1].omega.imag:.4f}i /tau", modes[1].omega.real < 0),
        verdict("real and imaginary parts not proportional (travelling wave)", "Re r and Im r not proportional",
                f"|cos angle(Re r, Im r)| = {cosang:.3f}", cosang < 0.99),
        compare("free-end conditions: max |r'' - kappa|, |r''' - kappa'| at s = 0, 1", None, max(bc),
                paper_text="zero moment and shear force", fmt="{:.1e}"),
    )
    return Outcome("ok", rows, (), {"omega1": [modes[0].omega.real, modes[0].omega.imag],
                                    "omega2": [modes[1].omega.real, modes[1].omega.imag], "bc_max": max(bc)})
