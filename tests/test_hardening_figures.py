"""Figures say what they show (units, legends, the operating point), kymograph sections sit on
the swimmer's path, the stability map is saved compressed (float32 optional) and a grid that
is too large is refused before anything is allocated."""

import math
import time

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.analysis.track import Track
from flutterswim.plotting.figures import path_sections, plot_kymographs, plot_swimmer
from flutterswim.stability import load_map, stability_map
from flutterswim.stability.plots import plot_bifurcation, plot_map


def _oblique_swimmer(angle=math.pi / 6, n_frames=400):
    """A travelling-wave swimmer moving 6 body lengths along ``angle``."""
    t = np.linspace(0.0, 4.0, n_frames)
    s = np.linspace(0.0, 1.0, 41)
    T, S = np.meshgrid(t, s, indexing="ij")
    u = S + 1.5 * T  # along the path
    w = 0.1 * np.sin(2 * math.pi * (S / 0.8 - T / 0.4))  # across it
    c, sn = math.cos(angle), math.sin(angle)
    return Track(t=t, x=c * u - sn * w + 3.0, y=sn * u + c * w - 2.0, s=s, length=1.0, units="mm")


def test_kymograph_sections_follow_the_mean_path():
    tr = _oblique_swimmer()
    along, across, ang = path_sections(tr)
    assert math.degrees(ang) == pytest.approx(30.0, abs=0.5)
    # the filament crosses its own mean path in (nearly) every frame, and the section moving
    # with the centroid in every frame
    assert np.mean(along.counts > 0) > 0.95
    assert np.all(across.counts > 0)
    # the old fixed lab line y = mean centroid y is crossed only while the swimmer passes it
    from flutterswim.analysis.kymograph import line_kymograph

    assert np.mean(line_kymograph(tr, "horizontal").counts > 0) < 0.5
    fig = plot_kymographs(tr)
    ax = fig.axes[0]
    n_dots = ax.collections[0].get_offsets().shape[0]
    assert n_dots >= along.counts.sum() * 0.99 and "mean path" in ax.get_title()
    assert ax.get_ylabel().endswith("(mm)") and fig.axes[1].get_ylabel().endswith("(mm)")


def test_swimmer_figure_legend_names_the_trails():
    fig = plot_swimmer(_oblique_swimmer())
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any("tip" in lab and "trajectory" in lab for lab in labels)
    assert any("centroid" in lab for lab in labels)


def test_stability_map_figure_marks_the_operating_point_with_units():
    g = fs.PAPER.groups
    m = stability_map(step=10.0)
    fig = plot_map(m, operating_point=(g.eta_perp, g.chi))
    ax = fig.axes[0]
    star = [ln for ln in ax.lines if ln.get_marker() == "*"]
    assert len(star) == 1
    np.testing.assert_allclose(np.r_[star[0].get_xdata(), star[0].get_ydata()], [g.eta_perp, g.chi])
    assert "operating point" in star[0].get_label()
    assert "dimensionless" in ax.get_xlabel() and "dimensionless" in ax.get_ylabel()
    from flutterswim.stability import bifurcation

    b = bifurcation(parameter="chi", values=np.arange(5.0, 100.0, 5.0), fixed=g.eta_perp)
    fig = plot_bifurcation([b])
    assert "1/" in fig.axes[0].get_ylabel() and "tau" in fig.axes[0].get_ylabel()


def test_stability_map_is_saved_compressed_and_float32_on_request(tmp_path):
    import xarray as xr

    m = stability_map(step=2.0)
    a = m.save(tmp_path / "a.nc")
    b = m.save(tmp_path / "b.nc", dtype="float32")
    m.to_dataset().to_netcdf(tmp_path / "plain.nc", engine="h5netcdf")  # uncompressed reference
    assert a.stat().st_size < 0.85 * (tmp_path / "plain.nc").stat().st_size
    assert b.stat().st_size < 0.6 * a.stat().st_size
    with xr.open_dataset(a, engine="h5netcdf") as ds:
        assert ds["re_omega"].encoding["zlib"] and ds["re_omega"].attrs["scaled_units"] == "1/tau"
        assert all("units" in ds[k].attrs and "long_name" in ds[k].attrs for k in ds.variables)
    back = load_map(b)
    ok = np.isfinite(m.omega)
    np.testing.assert_allclose(back.omega[ok], m.omega[ok], rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(load_map(a).omega[ok], m.omega[ok])


def test_too_large_map_grid_is_refused_before_allocating():
    t0 = time.perf_counter()
    with pytest.raises(fs.ParameterError, match="at most"):
        stability_map(step=1e-4)
    assert time.perf_counter() - t0 < 5.0


def test_sweep_plot_legend_explains_the_red_points():
    import xarray as xr

    from flutterswim.sweep.plot import plot_sweep

    x = np.linspace(0.5, 1.5, 6)
    red = np.array([0, 0, 0, 1, 1, 0], bool)
    ds = xr.Dataset({"advance_per_cycle_bl": ("chi", x * 0.1), "period_s": ("chi", 0.4 + 0 * x),
                     "swimming": ("chi", np.ones(6, bool)), "failed": ("chi", np.zeros(6, bool)),
                     "straight": ("chi", np.zeros(6, bool)), "self_intersecting": ("chi", red),
                     "limit_cycle_reached": ("chi", np.ones(6, bool)),
                     "unstable": ("chi", np.ones(6, bool))},
                    coords={"chi": x}, attrs={"time_unit": "s"})
    fig = plot_sweep(ds, x="chi")
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "self-intersecting stroke" in labels and "swimming stroke" in labels
