"""A closed path is followed lap after lap: the projection of the swimmer onto the path runs on
through the path's start. It stopped at the end of the first lap (the nearest point searched
near the last one never wrapped), so the swimmer left along the end's tangent while the
metrics, which project the same way, reported a cross-track error of about 0 (a review: 5.5
body lengths on the second lap of a circle, 0.0068 reported)."""

import math

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.steering.path import circle, square
from flutterswim.steering.reduced import ReducedModel
from flutterswim.steering.steer import steer


def test_projection_runs_on_through_the_start_of_a_closed_path():
    for path in (circle(2e-3, np.zeros(2), 0.3), square(3e-3, np.zeros(2), 0.0)):
        P = path.points
        n = len(P) - 1  # the last point is the first again
        for i_true in (20, 300):  # points just past the start of the second lap

            p = P[i_true] + 1e-5 * np.array([0.3, -0.2])
            i, e = path.project(p, near=n - 50)
            j, e_all = path.project(p)  # the whole path: the independent answer
            assert i == j and e == e_all
            assert abs(i - i_true) <= 2


def test_a_circle_is_followed_on_its_second_lap():
    p = fs.PAPER
    L = p.l
    red = ReducedModel(U=1.0582e-3, period=0.3776, k=3.83, omega_max=0.2606, omega_max_bracket=(0.2592, 0.2620),
                       r_min=4.061e-3, onset_time=12.0)
    R = 2 * L
    res = steer(p, lambda s, h: circle(R, s, h), red, laps=1.8)
    # independent: the one-period moving average of the centroid against the circle's radius
    t, run = res.run.t, res.run
    w = int(round(red.period / float(np.median(np.diff(t)))))
    k = np.ones(w) / w
    ax, ay = np.convolve(run.x.mean(1), k, "valid"), np.convolve(run.y.mean(1), k, "valid")
    tt = t[w // 2 : w // 2 + ax.size]
    c = res.path.points.mean(axis=0)
    err = np.abs(np.hypot(ax - c[0], ay - c[1]) - R)
    lap = 2 * math.pi * R / red.U
    t0 = red.onset_time
    second = (tt > t0 + 1.2 * lap) & (tt < tt[-1] - red.period)
    assert second.sum() > 100
    assert err[second].max() < 0.05 * L  # it was 5.5 L
    # the metrics see the same run: over the whole of it, within 0.02 L of the independent error
    assert res.metrics["cross_track_max_bl"] > err[tt > t0 + 3 * red.period].max() / L - 0.02
    assert res.metrics["path_covered_fraction"] > 1.5


def test_the_steering_file_alone_scores_the_run(tmp_path):
    """The saved run holds the path as placed: its distance to the averaged centroid, from the
    file alone, is the metrics' cross-track error."""
    import xarray as xr

    from flutterswim.steering.steer import steer_dataset

    p = fs.PAPER
    red = ReducedModel(U=1.0582e-3, period=0.3776, k=3.83, omega_max=0.2606, omega_max_bracket=(0.2592, 0.2620),
                       r_min=4.061e-3, onset_time=12.0)
    res = steer(p, lambda s, h: square(6 * p.l, s, h), red, laps=0.5)
    steer_dataset(res, red).to_netcdf(tmp_path / "r.nc", engine="h5netcdf")
    with xr.open_dataset(tmp_path / "r.nc", engine="h5netcdf") as ds:
        P = np.stack([ds["path_x"].values, ds["path_y"].values], 1)
        t0, T = float(ds.attrs["steering_control_start"]), red.period
        t, cx, cy = ds["t"].values, ds["x"].values.mean(1), ds["y"].values.mean(1)
    w = int(round(T / float(np.median(np.diff(t)))))
    k = np.ones(w) / w
    ax, ay = np.convolve(cx, k, "valid"), np.convolve(cy, k, "valid")
    tt = t[w // 2 : w // 2 + ax.size]
    sel = tt >= t0
    d = np.min(np.hypot(ax[sel, None] - P[None, :, 0], ay[sel, None] - P[None, :, 1]), axis=1)
    assert np.max(d) / p.l == pytest.approx(res.metrics["cross_track_max_bl"], rel=0.05, abs=0.005)
