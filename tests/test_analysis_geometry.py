"""Self-intersection, line-crossing kymographs and polyline curvature against geometry."""

import math

import numpy as np
import pytest

from flutterswim.analysis.intersection import polyline_self_intersects, self_intersections
from flutterswim.analysis.kymograph import body_kymograph, kymograph_windows, line_kymograph
from flutterswim.analysis.synthetic import c_shape, figure_eight, wave_track
from flutterswim.analysis.track import Track, polyline_curvature


def test_figure_eight_flagged_c_shape_not():
    assert polyline_self_intersects(*figure_eight())
    assert not polyline_self_intersects(*c_shape())
    # a C closing up to an overlap (opening < 0) crosses itself
    assert polyline_self_intersects(*c_shape(opening=-0.3))
    # a straight line never does
    assert not polyline_self_intersects(np.linspace(0, 1, 10), np.zeros(10))


def test_self_intersections_per_frame():
    x8, y8 = figure_eight(61)
    xc, yc = c_shape(61)
    X = np.stack([xc, x8, xc, x8])
    Y = np.stack([yc, y8, yc, y8])
    tr = Track(t=[0, 1, 2, 3], x=X, y=Y)
    n = self_intersections(tr)
    assert list(n > 0) == [False, True, False, True]
    # the lemniscate crosses itself exactly once: one pair of segments (or two if the
    # crossing point falls on a node); never more
    assert 1 <= n[1] <= 4


def test_horizontal_line_crossings_match_sine():
    # frame: y = A sin(k s), x = s; crossings of y = 0 at s = n pi / k (interior)
    s = np.linspace(0, 1, 201)
    k = 2 * math.pi / 0.3
    A = 0.05
    y = A * np.sin(k * s + 0.1)
    tr = Track(t=[0.0, 1.0], x=np.stack([s, s + 0.2]), y=np.stack([y, y]), s=s)
    kh = line_kymograph(tr, "horizontal", 0.0)
    exp = (np.arange(1, 10) * math.pi - 0.1) / k
    exp = exp[(exp > 0) & (exp < 1)]
    got = np.sort(kh.positions[0][np.isfinite(kh.positions[0])])
    assert got.size == exp.size
    # linear interpolation of a sine near its zero: error O(h^3 k^2)
    assert np.max(np.abs(got - exp)) < 1e-4
    got1 = np.sort(kh.positions[1][np.isfinite(kh.positions[1])])
    assert np.allclose(got1, exp + 0.2, atol=1e-4)
    # vertical line x = 0.5 crosses the filament once, at y(0.5)
    kv = line_kymograph(tr, "vertical", 0.5)
    assert kv.counts[0] == 1
    assert kv.positions[0, 0] == pytest.approx(A * math.sin(k * 0.5 + 0.1), abs=1e-4)
    assert kv.s[0, 0] == pytest.approx(0.5, abs=1e-3)


def test_curvature_of_circle_arc():
    R = 0.7
    x, y = c_shape(101, radius=R)
    k = polyline_curvature(x, y)
    assert np.allclose(k, 1 / R, rtol=1e-3)
    bk = body_kymograph(Track(t=[0, 1], x=np.stack([x, x]), y=np.stack([y, y])))
    assert np.allclose(bk.kappa, 1 / R, rtol=1e-3)
    # body-frame tangent angle: turns by the arc step per chord 2 R sin(step/2), zero mean
    step = (2 * math.pi - 0.5) / 100
    assert np.allclose(np.diff(bk.theta[0]) / np.diff(bk.s_mid), step / (2 * R * math.sin(step / 2)), rtol=1e-9)
    assert abs(bk.theta[0].mean()) < 1e-12


def test_kymograph_windows():
    tr = wave_track(envelope=(1e-3, 3.0), duration=8.0, n_frames=2001)
    w = kymograph_windows(tr, n_cycles=3)
    on, lim = w["onset"], w["limit"]
    assert lim[1] <= tr.t[-1] and lim[1] - lim[0] == pytest.approx(1.2, rel=1e-2)
    assert on[1] < lim[0]


def test_body_kymograph_shows_the_shapes_curvature_not_a_given_spontaneous_one():
    # a simulation's Track carries the model's spontaneous curvature, which lags the shape's
    # and is not the shape's at the free end joints; the map must show the shape's (as for a
    # tracked movie), here a circle arc of radius R with a spontaneous curvature of 0 and a
    # jump at the end joint
    R = 0.7
    x, y = c_shape(101, radius=R)
    given = np.zeros((2, x.size))
    given[:, 0] = -3.0
    tr = Track(t=[0, 1], x=np.stack([x, x]), y=np.stack([y, y]), kappa=given)
    assert np.allclose(tr.curvature()[1], given)  # the track keeps what it was given
    assert np.allclose(body_kymograph(tr).kappa, 1 / R, rtol=1e-3)


def test_body_kymograph_of_a_simulation_is_theta_s():
    # the map of a simulated stroke: the shape's theta_s at the interior joints (second-order
    # differences of the segments' angles), whatever its spontaneous curvature
    import flutterswim as fs

    r = fs.simulate(fs.PAPER, 4.5, n_segments=24, frame_dt=0.05)
    bk = body_kymograph(r)
    h = np.diff(r.s)
    theta_s = np.diff(r.theta, axis=1) / h[None, 1:]
    assert np.allclose(bk.kappa[:, 1:-1], theta_s, rtol=1e-6, atol=1e-6 * np.abs(theta_s).max())
    assert not np.allclose(bk.kappa[:, 0], r.kappa[:, 0], rtol=0.05)
