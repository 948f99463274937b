"""The ends refitted across a known curve (flutterswim.tracking.tips.end_offsets) and the
mirror symmetry of the periodic template (flutterswim.tracking.periodic), on the paper's
stroke rendered at 14 um per pixel."""

from __future__ import annotations

import math

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.tracking import render
from flutterswim.tracking.periodic import periodic_shape
from flutterswim.tracking.temporal import frames_per_stroke
from flutterswim.tracking.tips import end_offsets, resample
from flutterswim.tracking.track import track_frame

FPS = 50.0


@pytest.fixture(scope="module")
def run():
    return fs.simulate(fs.PAPER, 10.0, n_segments=24, frame_dt=1.0 / FPS)


def _truth49(mv, i):
    x, y = mv.x_px[i], mv.y_px[i]
    L = float(np.sum(np.hypot(np.diff(x), np.diff(y))))
    return resample(x, y, 0.0, L, 49)


def _across(p, x, y, end):
    """Signed distance of point p from the true end (x, y)[end] across the end's tangent, and along it."""
    j, k = (0, 1) if end == 0 else (-1, -2)
    t = np.array([x[j] - x[k], y[j] - y[k]])
    t /= np.hypot(*t)
    e = np.asarray(p) - np.array([x[j], y[j]])
    return float(e @ np.array([-t[1], t[0]])), float(e @ t)


def test_end_offsets_recover_a_known_shift_without_noise(run):
    """Noise-free frames, the true curve as reference, shifted rigidly across the body by
    0 and 0.6 px: both ends come back onto the true line (within 0.05 px across it), and their
    position along the body is the one given."""
    n = run.t.size
    mv = render(run, um_per_px=14.0, snr=math.inf, frames=slice(n - 20, n))
    for i in (0, 7, 13):
        x, y = _truth49(mv, i)
        tips = np.array([[x[0], y[0]], [x[-1], y[-1]]])
        for shift in (0.0, 0.6):
            # the reference displaced by `shift` along the normal of the chord
            c = np.array([x[-1] - x[0], y[-1] - y[0]])
            nrm = np.array([-c[1], c[0]]) / np.hypot(*c)
            xr, yr = x + shift * nrm[0], y + shift * nrm[1]
            out = end_offsets(mv.frames[i], xr, yr, tips + shift * nrm, sigma=1.2)
            for e in (0, 1):
                across, along = _across(out[e], x, y, -e if e else 0)
                assert abs(across) < 0.05, (i, shift, e, across)
                assert abs(along) < shift + 0.05


def test_end_offsets_halve_the_noise_across_the_body(run):
    """One frame at SNR 3, 40 noise draws: with the true curve as reference, the ends' spread
    across the body is well below that of the per-frame end fit (which must find the end's
    bend from its last few px; 0.36-0.45 px on these movies), and unbiased."""
    n = run.t.size
    across_ref, across_own = [], []
    for seed in range(40):
        mv = render(run, um_per_px=14.0, snr=3.0, seed=seed, frames=slice(n - 9, n - 8))
        x, y = _truth49(mv, 0)
        r = track_frame(mv.frames[0], sigma=1.2)
        assert r["ok"], r["reason"]
        xo, yo = r["x"], r["y"]
        if math.hypot(xo[0] - x[0], yo[0] - y[0]) > math.hypot(xo[0] - x[-1], yo[0] - y[-1]):
            xo, yo = xo[::-1], yo[::-1]
        tips = np.array([[xo[0], yo[0]], [xo[-1], yo[-1]]])
        out = end_offsets(mv.frames[0], x, y, tips, sigma=1.2)
        for e in (0, 1):
            across_ref.append(_across(out[e], x, y, -e if e else 0)[0])
            across_own.append(_across(tips[e], x, y, -e if e else 0)[0])
    a, b = np.array(across_ref), np.array(across_own)
    assert np.std(a) < 0.75 * np.std(b), (np.std(a), np.std(b))
    assert abs(np.mean(a)) < 3 * np.std(a) / math.sqrt(a.size)


def _pixels(run, sl):
    k = 1e6 / 14.0
    xs, ys = run.x[sl], run.y[sl]
    X, Y = np.empty((xs.shape[0], 49)), np.empty((xs.shape[0], 49))
    for i in range(xs.shape[0]):
        x, y = xs[i] * k, ys[i] * k
        L = float(np.sum(np.hypot(np.diff(x), np.diff(y))))
        X[i], Y[i] = resample(x, y, 0.0, L, 49)
    return X, Y


def test_the_mirror_symmetry_is_used_only_when_the_stroke_has_it(run):
    """The settled stroke is symmetric under reflection across its axis with a half-period
    shift (the field lies along the axis): the template uses it. The same stroke with a fixed
    bend added in the body (an asymmetric stroke, as under a tilted field) is refused the
    symmetric template, and the template still reproduces it."""
    n = run.t.size
    X, Y = _pixels(run, slice(n - 101, n))
    ok = np.ones(X.shape[0], bool)
    per = frames_per_stroke(X, Y, ok)
    Xp, Yp, info = periodic_shape(X, Y, ok, per)
    assert info["done"] and info["symmetric"], info["reason"]
    assert np.hypot(Xp - X, Yp - Y).max() < 0.05
    # a fixed bend: every sample moved across the body by 1.5 px (s/l)^2
    Xa, Ya = X.copy(), Y.copy()
    w = 1.5 * np.linspace(0.0, 1.0, 49) ** 2
    for i in range(X.shape[0]):
        tx, ty = np.gradient(X[i]), np.gradient(Y[i])
        h = np.hypot(tx, ty)
        Xa[i] += -ty / h * w
        Ya[i] += tx / h * w
    Xq, Yq, info_a = periodic_shape(Xa, Ya, ok, per)
    assert info_a["done"] and not info_a["symmetric"], info_a["reason"]
    assert info_a["symmetry_f"] > 3.0
    assert np.hypot(Xq - Xa, Yq - Ya).max() < 0.05
    # and forced off
    _, _, info_off = periodic_shape(X, Y, ok, per, symmetric=False)
    assert not info_off["symmetric"]
