"""Figure data of ``flutterswim reproduce`` against mathematics (not pixels): the onset of
the branch is the linear threshold, the eigenmodes satisfy the free-end conditions and their
ODE, the kymograph's average velocity is the periodic orbit's speed, the steering circle has
radius U / Omega; two runs write identical data files; the report renders in Chromium."""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import flutterswim as fs

xr = pytest.importorskip("xarray")
pytest.importorskip("jinja2")
pytest.importorskip("matplotlib")

FAST = ["table1", "b_readings", "fig6a", "fig6b", "fig6cd", "paper_run", "fig4b", "fig4c", "fig4de", "fig5", "fig3e", "video_s4"]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    from flutterswim.reproduce import figures_model as fm
    from flutterswim.reproduce import reproduce

    mp = pytest.MonkeyPatch()
    # a short branch (the Hopf point does not depend on the number of orbits)
    mp.setattr(fm, "fig4b_params", lambda s: {"n_points": 8, "n_segments": 24, "to": 1.2,
                                              "params": fs.PAPER.to_dict()})
    try:
        res = reproduce(tmp_path_factory.mktemp("rep") / "out", mode="quick", targets=FAST)
    finally:
        mp.undo()
    assert res.ok, {k: r.error for k, r in res.records.items() if r.status == "failed"}
    return res


def _open(res, name):
    return xr.open_dataset(res.out / name, engine="h5netcdf")


def _assert_cf(ds, name):
    """CF-style: Conventions and a title, units and a long name on every variable and coordinate."""
    assert ds.attrs["Conventions"].startswith("CF-") and ds.attrs["title"], name
    for k, var in {**ds.data_vars, **ds.coords}.items():
        assert isinstance(var.attrs.get("units"), str) and var.attrs["units"], (name, k)
        assert var.attrs.get("long_name"), (name, k)


def test_table1_data_is_cf_netcdf_with_the_tables_numbers(built):
    """table1_data was JSON without units: CF NetCDF now, holding the numbers the table shows."""
    ds = _open(built, "table1_data.nc")
    _assert_cf(ds, "table1_data.nc")
    assert {ds[k].attrs["units"] for k in ("l", "b", "B", "tau", "mu", "mu_perp", "eta_perp")} >= {"m", "Pa s", "1"}
    rows = {c.quantity: c.our_value for c in built.records["table1"].outcome.comparisons}
    assert rows["Filament's width, 2b"] == pytest.approx(2e3 * float(ds["b"]), rel=1e-12)  # mm
    assert rows["Bending stiffness, B"] == pytest.approx(1e6 * float(ds["B"]), rel=1e-12)  # N mm^2
    readings = ds.attrs["b_drag_readings"].split("; ")
    assert ds["b_drag"].values.tolist() == [float(ds["b"]), 2 * float(ds["b"])]  # semi-axis, full width
    l, B, tau, mu = (float(ds[k]) for k in ("l", "B", "tau", "mu"))
    for i, name in enumerate(readings):
        L = math.log(2 * l / float(ds["b_drag"][i]))  # the Koens-Lauga coefficients from the file's own b
        assert float(ds["mu_perp"][i]) == pytest.approx(4 * math.pi * mu / L, rel=1e-12)
        assert float(ds["mu_par"][i]) == pytest.approx(4 * math.pi * mu / (2 * L - 1), rel=1e-12)
        assert float(ds["eta_perp"][i]) == pytest.approx(float(ds["mu_perp"][i]) * l**4 / (B * tau), rel=1e-12)
        assert rows[f"mu_perp = 4 pi mu / ln(2l/b) [{name}]"] == pytest.approx(1e3 * float(ds["mu_perp"][i]), rel=1e-12)
        assert rows[f"eta_perp = mu_perp l^4/(B tau) [{name}]"] == pytest.approx(float(ds["eta_perp"][i]), rel=1e-12)
    assert float(ds["chi"]) == pytest.approx(float(ds["kappa_E"]) * l, rel=1e-12)


def test_paper_orbit_is_cf_netcdf_and_what_the_later_targets_read(built):
    """paper_orbit was JSON without units, read back by Fig. 4c-e: CF NetCDF now, the same
    numbers in the run's comparisons and in the files of the targets that read it."""
    ds = _open(built, "paper_orbit.nc")
    _assert_cf(ds, "paper_orbit.nc")
    assert (ds["period"].attrs["units"], ds["advance"].attrs["units"], ds["speed"].attrs["units"]) == ("s", "m", "m s-1")
    assert float(ds["speed"]) == pytest.approx(float(ds["advance"]) / float(ds["period"]), rel=1e-9)
    rows = {c.quantity: c.paper_value for c in built.records["paper_run"].outcome.comparisons}
    assert rows["period: simulation (mean of settled cycles) vs periodic orbit"] == float(ds["period"])
    assert _open(built, "fig4de.nc").attrs["orbit_speed_m_s"] == float(ds["speed"])
    # Fig. 4c draws the trailing end: s = 0 when s = l leads
    tip = "start" if int(ds["leading_end"]) == 1 else "end"
    assert f"({tip} of the filament)" in _open(built, "fig4c.nc")["tip_x"].attrs["long_name"]
    assert np.hypot(ds["multiplier_real"], ds["multiplier_imag"]).max() == pytest.approx(1.0, abs=1e-6)  # trivial one


def test_every_data_file_is_titled_cf_netcdf(built):
    """b_readings, Fig. 4c, 4d-e, 5 and 6a-d had no title: every NetCDF file of the run is CF
    with a title, units and a long name on everything and no _FillValue on a coordinate (the
    title is what tells a flutterswim file's kind)."""
    names = [f for r in built.records.values() if r.status == "ok" for f in r.target.data if f.endswith(".nc")]
    assert {"b_readings.nc", "fig4c.nc", "fig4de.nc", "fig5.nc", "fig6a_map.nc", "fig6a_neutral.nc", "fig6b.nc",
            "fig6cd.nc"} <= set(names)
    for name in names:
        with _open(built, name) as ds:
            _assert_cf(ds, name)
            for c in ds.coords:
                assert ds[c].encoding.get("_FillValue") is None, (name, c)


def test_b_readings_match_the_formula_and_the_curves(built):
    from flutterswim.params import PAPER

    ds = _open(built, "b_readings.nc")
    L1, L2 = math.log(2 * PAPER.l / PAPER.b), math.log(PAPER.l / PAPER.b)
    vals = built.records["b_readings"].outcome.values["readings"]
    # eta_perp ~ 1 / ln(2l/b): doubling b multiplies it by ln(2l/b) / ln(l/b)
    assert vals["full width"]["eta_perp"] / vals["semi-axis"]["eta_perp"] == pytest.approx(L1 / L2, rel=1e-12)
    for key in ("semi", "full"):
        x, re_ = ds["kappa_E_ratio"].values, ds[f"re_omega_{key}"].values
        k = np.flatnonzero((re_[:-1] <= 0) & (re_[1:] > 0))[0]
        cross = x[k] - re_[k] * (x[k + 1] - x[k]) / (re_[k + 1] - re_[k])
        # root following along kappa_E vs the Hopf-Newton threshold (independent solves)
        assert cross == pytest.approx(ds.attrs[f"onset_ratio_{key}"], abs=1e-4)
    assert abs(ds.attrs["onset_ratio_full"] - 0.65) < 0.005 < 0.03 < abs(ds.attrs["onset_ratio_semi"] - 0.65)


def test_eigenmodes_satisfy_free_end_conditions_and_the_ode(built):
    ds = _open(built, "fig6cd.nc")
    s = ds["s"].values
    chi, eta = ds.attrs["chi"], ds.attrs["eta_perp"]
    for m in (1, 2):
        f = {k: ds[f"mode{m}_{k}_re"].values + 1j * ds[f"mode{m}_{k}_im"].values
             for k in ("r", "r_s", "r_ss", "r_sss", "r_ssss", "kappa", "kappa_s")}
        om = ds.attrs[f"mode{m}_omega_re"] + 1j * ds.attrs[f"mode{m}_omega_im"]
        scale = np.max(np.abs(f["r_ss"]))
        for end in (0, -1):  # zero moment theta_s - kappa and zero shear at both free ends
            assert abs(f["r_ss"][end] - f["kappa"][end]) < 1e-8 * scale
            assert abs(f["r_sss"][end] - f["kappa_s"][end]) < 1e-8 * np.max(np.abs(f["r_sss"]))
        # the interior equations: r'''' - kappa'' + omega eta r = 0 and (1 + omega) kappa = -chi r'
        c = chi / (1 + om)
        assert np.max(np.abs(f["r_ssss"] + c * f["r_sss"] + om * eta * f["r"])) < 1e-8 * np.max(np.abs(f["r_ssss"]))
        assert np.allclose((1 + om) * f["kappa"], -chi * f["r_s"], atol=1e-10 * np.max(np.abs(f["kappa"])))
        # the stored derivatives are those of the stored shape (finite differences, O(h^2))
        h = s[1] - s[0]
        assert np.max(np.abs(np.gradient(f["r"], h, edge_order=2) - f["r_s"])) < 2e-3 * np.max(np.abs(f["r_s"]))
        # the stored shape is the stability package's eigenmode (normalised the same way)
        mode = fs.stability.eigenmodes(chi, eta, n_points=s.size)[m - 1]
        assert np.allclose(mode.r, f["r"], atol=1e-8)
    assert ds.attrs["mode1_omega_re"] > 0 > ds.attrs["mode2_omega_re"]


def test_bifurcation_and_map_cross_zero_at_the_neutral_curve(built):
    from flutterswim.stability import critical_chi

    g = fs.PAPER.groups
    chi_cr, _ = critical_chi(g.eta_perp)
    ds = _open(built, "fig6b.nc")
    c, r = ds["chi"].values, ds["re_omega_vs_chi"].values
    k = np.flatnonzero((r[:-1] <= 0) & (r[1:] > 0))
    assert k.size == 1
    assert c[k[0]] - r[k[0]] * (c[k[0] + 1] - c[k[0]]) / (r[k[0] + 1] - r[k[0]]) == pytest.approx(chi_cr, abs=0.05)
    assert np.all(ds["im_omega_vs_chi"].values > 0)
    m = _open(built, "fig6a_map.nc")
    n = _open(built, "fig6a_neutral.nc")
    for e in (20.0, 71.0, 200.0):
        row = m["re_omega"].sel(eta_perp=e).values
        chis = m["chi"].values
        unstable = chis[row > 0]
        crit = float(n["chi_cr"].sel(eta_perp=e, method="nearest"))
        # the map is unstable exactly beyond +-chi_cr (grid step 1)
        assert np.all(np.abs(unstable) >= crit - 1e-9)
        assert np.all(row[np.abs(chis) > crit + 1.0] > 0)


def test_branch_onset_is_the_linear_threshold(built):
    from flutterswim.stability import critical_chi

    g = fs.PAPER.groups
    linear = critical_chi(g.eta_perp)[0] / g.chi
    ds = _open(built, "fig4b.nc")
    hopf = ds.attrs["hopf_kappa_E_ratio"]
    assert hopf == pytest.approx(linear, rel=1e-2)  # N = 24 discrete vs the continuum
    x = ds["kappa_E_ratio"].values
    assert np.all(x > hopf) and np.all(ds["advance"].values > 0)
    # the amplitude grows like sqrt(kappa - kappa_cr) near a supercritical Hopf point
    a = ds["amplitude"].values
    assert ds.attrs["lyapunov_coefficient"] < 0 and a[1] / a[0] == pytest.approx(
        math.sqrt((x[1] - hopf) / (x[0] - hopf)), rel=0.1)


def test_kymograph_velocity_is_the_orbit_speed(built):
    ds = _open(built, "fig4de.nc")
    v = ds.attrs["limit_average_velocity_m_s"]
    assert v == pytest.approx(ds.attrs["orbit_speed_m_s"], rel=1e-2)
    assert ds.attrs["onset_average_velocity_m_s"] < 0.5 * v
    # the line's slope is the centroid's net displacement along the path over the window
    assert "t_limit" in ds.indexes and "t_onset" in ds.indexes  # times are coordinates (they were plain variables)
    t, u = ds["t_limit"].values, ds["limit_centroid_along"].values
    assert (u[-1] - u[0]) / (t[-1] - t[0]) == pytest.approx(v, rel=1e-12)


def test_onset_shapes_are_small_and_limit_shapes_large(built):
    ds = _open(built, "fig4c.nc")
    p2p = {k: np.ptp(ds[f"ghost_{k}_y"].values[:, 0]) for k in ("onset", "limit")}
    assert p2p["onset"] < 0.5 * p2p["limit"]
    assert ds.attrs["onset_window_s"][1] < ds.attrs["limit_window_s"][0]
    # the report's limit-cycle tip excursion is the stroke's: the periodic orbit's trailing end
    # (it was read off the 8 shapes drawn: 1.062 against 1.132 mm)
    import json

    reported = json.loads((built.out / "fig4c.json").read_text())["values"]["tip_p2p_limit_mm"]
    orbit = float(_open(built, "paper_orbit.nc")["lateral_trailing"])
    assert reported == pytest.approx(orbit * 1e3, rel=0.01)


def test_rows_against_our_own_numbers_are_not_agreements_with_the_paper(built):
    """The run's period against our periodic orbit's (its "paper" column our own number) was
    counted as an agreement with the paper; such rows are ours only now, and the report counts
    the rows compared with the paper."""
    orbit = _open(built, "paper_orbit.nc")
    ours = {float(orbit["period"]), float(orbit["advance"]) * 1e3, float(orbit["speed"]) * 1e3}
    rows = [c for r in built.records.values() for c in r.outcome.comparisons]
    against_orbit = [c for c in rows if c.paper_value in ours]
    assert len(against_orbit) >= 3 and not any(c.from_paper for c in against_orbit)
    assert all(c.from_paper and c.ok for c in built.records["table1"].outcome.comparisons if c.paper_value)
    if built.records["fig3e"].status == "ok":  # a fit recovering the truth of its synthetic data
        assert not any(c.from_paper for c in built.records["fig3e"].outcome.comparisons)
    paper = [c for c in rows if c.from_paper and c.ok is not None and not c.is_input]
    n_agree = sum(c.ok for c in paper)
    assert 0 < len(paper) < len([c for c in rows if c.ok is not None])
    html = built.report.read_text()
    assert f"Comparisons with the paper: {n_agree} agree, {len(paper) - n_agree} disagree." in html
    # Table 1's inputs compared with themselves are counted apart (7 of the "22 agree" were),
    # and each disagreement is named in the headline
    inputs = [c for c in built.records["table1"].outcome.comparisons if c.paper_value]
    assert inputs and all(c.is_input for c in inputs)
    assert f"Table 1's {len(inputs)} inputs, as printed ({sum(c.ok for c in inputs)} transcribed" in html
    import html as html_lib

    for c in paper:
        assert (html_lib.escape(c.quantity) in html.split("<h2")[0]) == (not c.ok), c.quantity


def test_every_model_figure_names_its_place_in_the_latex_source():
    """The targets keep the issue's numbering (Fig. 4b ...); the LaTeX source numbers its figures
    in source order, fig:exp_stat as Fig. 4, so its fig:model is Fig. 5 (a review took "Fig. 4b"
    for the experimental equilibrium shapes). Each figure target names its label, and the number
    given is the label's place among the source's figure environments."""
    import re
    from pathlib import Path

    from flutterswim.reproduce.catalog import TARGETS

    paper = Path(__file__).resolve().parents[2] / "shared" / "paper" / "000_030aa27e52f153d6.txt"
    if not paper.is_file():
        pytest.skip("the paper's LaTeX source is not beside the repository")
    text = paper.read_text()
    order = []  # figure labels in source order: the \label right after each figure's caption
    for env in re.findall(r"\\begin\{figure\*?\}(.*?)\\end\{figure\*?\}", text, re.S):
        labels = re.findall(r"\\label\{(fig:[^}:]*)\}", env)
        order.append(labels[-1])
    for t in TARGETS:
        if not t.name.startswith("fig"):
            continue
        label, number = re.match(r"\\ref\{([^}]*)\}.*Fig\. (\d+)", t.source).groups()
        assert order.index(label) + 1 == int(number), (t.name, label, number, order)
        assert t.title.startswith("Fig. ")


def test_video_s5_resolves_the_stroke():
    """Video S5 at 6x and 15 fps showed a frame every 0.4 s of a 0.377 s stroke: a slow, false
    undulation (stroboscopic aliasing). Every mode now shows a frame per quarter stroke or less."""
    from flutterswim.orbits import periodic_orbit
    from flutterswim.reproduce.figures_steering import video_s5_params
    from flutterswim.reproduce.targets import Settings

    period = periodic_orbit(fs.PAPER, n_segments=12).period
    for mode in ("quick", "full"):
        prm = video_s5_params(Settings(mode))
        assert prm["speed"] / prm["fps"] <= period / 4, (mode, prm, period)


def test_steering_circle_radius_is_U_over_Omega(built):
    ds = _open(built, "fig5.nc")
    predicted = ds.attrs["orbit_speed_m_s"] / ds.attrs["rate_rad_s"]
    assert ds.attrs["circle_radius_m"] == pytest.approx(predicted, rel=3e-2)
    sel = ds["avg_in_fit"].values.astype(bool)
    d = np.hypot(ds["avg_x"].values[sel] - ds.attrs["circle_xc_m"], ds["avg_y"].values[sel] - ds.attrs["circle_yc_m"])
    assert np.std(d) < 0.01 * ds.attrs["circle_radius_m"]
    # the field turns only after onset
    t, phi = ds["t"].values, ds["field_angle"].values
    assert np.all(phi[t <= ds.attrs["start_s"]] == 0)


def test_synthetic_fit_recovers_the_truth(built):
    rec = built.records["fig3e"]
    if rec.status == "skipped":
        pytest.skip(rec.outcome.notes[0])
    ds = _open(built, "fig3e_data.nc")
    _assert_cf(ds, "fig3e_data.nc")
    assert ds.attrs["data_source"] == "synthetic" and ds.attrs["source"].startswith("flutterswim ")
    ratio = []
    for k, unit in (("B", "N m2"), ("tau", "s"), ("kappa_E", "1/m")):
        assert ds[f"{k}_true"].attrs["units"] == ds[f"{k}_fitted"].attrs["units"] == unit
        assert float(ds[f"{k}_true"]) == getattr(fs.PAPER, k)
        assert float(ds[f"{k}_fitted"]) == pytest.approx(float(ds[f"{k}_true"]), rel=1e-2)
        ratio.append(float(ds[f"{k}_fitted"]) / float(ds[f"{k}_true"]))
    assert ratio == pytest.approx(rec.outcome.values["ratio"], rel=1e-12)  # what the figure draws


def test_two_runs_write_identical_data_files(built, tmp_path):
    from flutterswim.reproduce import reproduce

    names = ["table1", "b_readings", "fig6cd", "paper_run", "fig4c"]
    res = reproduce(tmp_path / "again", targets=names)
    assert res.ok
    files = [f for n in names for f in built.records[n].target.data + (built.records[n].target.summary_file,)]
    assert any(f.endswith(".nc") for f in files)
    for f in files:
        assert (res.out / f).read_bytes() == (built.out / f).read_bytes(), f


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        p = shutil.which(name)
        if p:
            return p
    return None


def test_report_renders_in_headless_chromium(built):
    exe = _chromium()
    if exe is None:
        pytest.skip("no chromium on PATH (Debian: apt-get install chromium; .ci/run installs it)")
    html = Path(built.report)
    n_img = html.read_text().count("<img ")
    assert n_img >= 8 + (built.records["fig3e"].status == "ok")
    proc = subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                           "--virtual-time-budget=10000", "--dump-dom", html.resolve().as_uri()],
                          capture_output=True, text=True, timeout=120)
    dom = proc.stdout
    m = re.search(r'data-images-loaded="(\d+)"\s+data-images-total="(\d+)"', dom)
    assert m, f"the page's load script did not run: {proc.stderr[-500:]}"
    assert int(m.group(1)) == int(m.group(2)) == n_img  # every image decoded (naturalWidth > 0)
    # the videos play inline: each one's metadata loaded with a duration (they were links only)
    n_vid = html.read_text().count("<video ")
    assert n_vid >= 1
    mv = re.search(r'data-videos-total="(\d+)"\s+data-videos-loaded="(\d+)"', dom)
    assert mv and int(mv.group(1)) == int(mv.group(2)) == n_vid, proc.stderr[-500:]
    text = re.sub(r"<[^>]+>", " ", re.sub(r"<(script|style)[^>]*>.*?</\1>", " ", dom, flags=re.S))
    assert len(text.split()) > 500 and "0.65" in text  # not blank; the b readings are there


def test_fig3e_without_trials_is_called_a_stand_in_in_the_report(built):
    """(A review: without --trials the summary said "Fig. 3e: experimental descriptors against
    voltage - ok" over a synthetic fit-recovery figure.)"""
    rec = built.records["fig3e"]
    if rec.status == "skipped":
        pytest.skip(rec.outcome.notes[0])
    title = rec.outcome.values["title"]
    assert "stand-in" in title and "synthetic" in title
    html = (built.out / "report.html").read_text()
    assert title in html and "experimental descriptors against voltage" not in html


def test_fig4de_data_hold_all_four_panels(built):
    """(A review: fig4de.nc held only the crossings of the mean path, the first of four panels.)
    The crossings across the path, the curvature and the tangent-angle kymographs are there,
    with units, for both windows; the curvature is the tangent angle's derivative along s."""
    ds = _open(built, "fig4de.nc")
    _assert_cf(ds, "fig4de.nc")
    for k in ("onset", "limit"):
        for name in ("along_positions", "across_positions", "curvature", "tangent_angle"):
            assert f"{k}_{name}" in ds, (k, name)
        kap, th = ds[f"{k}_curvature"].values, ds[f"{k}_tangent_angle"].values
        fd = np.diff(th, axis=1) / np.diff(ds[f"s_mid_{k}"].values)
        assert np.max(np.abs(kap[:, 1:-1] - fd)) <= 1e-9 * np.max(np.abs(kap))
        assert np.isfinite(ds[f"{k}_across_positions"].values).any()
