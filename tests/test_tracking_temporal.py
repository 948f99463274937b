"""Checks and smoothing across frames (flutterswim.tracking.temporal), against the simulated
centrelines of the paper's settled stroke at 50 fps (14 um per pixel): the smoothing's bias
without noise, its noise reduction on known injected offsets, its refusal on an undersampled
stroke, and tip outliers (injected, known) found and reported by track."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.analysis.descriptors import describe
from flutterswim.analysis.track import Track
from flutterswim.tracking.temporal import (frames_per_stroke, smooth_offsets, smoothing_allowed,
                                           smoothing_gain_error, tip_outliers)
from flutterswim.tracking.tips import resample

FPS = 50.0
UM_PER_PX = 14.0
KEYS = ("period_s", "advance_per_cycle_mm", "leading_lateral_p2p_mm", "trailing_lateral_p2p_mm")


@pytest.fixture(scope="module")
def sim():
    r = fs.simulate(fs.PAPER, 10.0, n_segments=24, frame_dt=1.0 / FPS)
    sl = slice(r.t.size - 101, r.t.size)
    return SimpleNamespace(t=r.t[sl], x=r.x[sl], y=r.y[sl])


@pytest.fixture(scope="module")
def truth(sim):
    """The simulated centrelines in pixels, 49 equal arc-length samples per frame."""
    k = 1e6 / UM_PER_PX
    X, Y = np.empty((sim.t.size, 49)), np.empty((sim.t.size, 49))
    for i in range(sim.t.size):
        x, y = sim.x[i] * k, sim.y[i] * k
        L = float(np.sum(np.hypot(np.diff(x), np.diff(y))))
        X[i], Y[i] = resample(x, y, 0.0, L, 49)
    return X, Y


def _describe(X, Y, t):
    mm = UM_PER_PX / 1000.0
    return describe(Track(t=t, x=X * mm, y=Y * mm, units="mm", length=3.7))


def test_frames_per_stroke_and_the_gate(sim, truth):
    X, Y = truth
    ok = np.ones(X.shape[0], bool)
    period = _describe(X, Y, sim.t).period_s * FPS
    assert frames_per_stroke(X, Y, ok) == pytest.approx(period, rel=0.03)
    assert smoothing_allowed(7, 4, period)
    # every third frame: 6.3 frames per stroke, a quartic over 7 frames would flatten it
    p3 = frames_per_stroke(X[::3], Y[::3], ok[::3])
    assert p3 == pytest.approx(period / 3, rel=0.05)
    assert not smoothing_allowed(7, 4, p3)
    # the gain error is that of the Savitzky-Golay filter: exact on polynomials, < 1 otherwise
    assert smoothing_gain_error(7, 4, 0.0) < 1e-12
    assert 0 < smoothing_gain_error(7, 4, 1 / 19) < 1e-4


def test_smoothing_bias_without_noise_is_far_below_the_limits(sim, truth):
    """On the noise-free stroke the ends move < 0.02 px and every descriptor by < 0.05 %
    (lateral amplitudes < 0.1 % required; the acceptance limit is 0.5 %)."""
    X, Y = truth
    ok = np.ones(X.shape[0], bool)
    Xs, Ys, shift = smooth_offsets(X, Y, ok)
    assert np.abs(shift).max() < 0.02
    assert np.hypot(Xs - X, Ys - Y).max() < 0.03
    d0, d1 = _describe(X, Y, sim.t), _describe(Xs, Ys, sim.t)
    for k in KEYS:
        assert abs(getattr(d1, k) / getattr(d0, k) - 1) < 5e-4, k


def test_smoothing_removes_injected_offsets_along_the_body(truth):
    """Each frame slid along its own curve by a known random offset (sd 0.5 px, as the tips'
    noise at SNR 3): the smoothing returns them with the Savitzky-Golay noise gain (0.75 for
    a quartic over 7 frames; more at the movie's ends)."""
    from scipy.signal import savgol_coeffs

    X, Y = truth
    T = X.shape[0]
    rng = np.random.default_rng(5)
    h = rng.normal(0.0, 0.5, T)
    Xn, Yn = X.copy(), Y.copy()
    for i in range(T):
        L = float(np.sum(np.hypot(np.diff(X[i]), np.diff(Y[i]))))
        Xn[i], Yn[i] = resample(X[i], Y[i], h[i], L + h[i], 49)
    _, _, shift = smooth_offsets(Xn, Yn, np.ones(T, bool))
    left = h + shift  # the offset that remains
    gain = float(np.linalg.norm(savgol_coeffs(7, 4)))
    assert np.sqrt(np.mean(left**2)) < 1.15 * gain * np.sqrt(np.mean(h**2))
    assert np.corrcoef(shift, -h)[0, 1] > 0.5


def _bend_end(x, y, n_last: int, angle: float):
    """The last n_last samples rotated by angle [rad] about the sample before them."""
    x, y = x.copy(), y.copy()
    j = x.size - n_last - 1
    c, s = math.cos(angle), math.sin(angle)
    dx, dy = x[j + 1:] - x[j], y[j + 1:] - y[j]
    x[j + 1:], y[j + 1:] = x[j] + c * dx - s * dy, y[j] + s * dx + c * dy
    return x, y


def test_tip_outliers_finds_an_injected_bent_end_and_nothing_else(truth):
    X, Y = truth
    T = X.shape[0]
    ok = np.ones(T, bool)
    assert tip_outliers(X, Y, ok) == []
    rng = np.random.default_rng(1)
    Xn = X + rng.normal(0, 0.3, X.shape)
    Yn = Y + rng.normal(0, 0.3, Y.shape)
    assert tip_outliers(Xn, Yn, ok) == []
    # (0.3 px on every sample gives residuals of 0.5 px sd: the threshold is 6 sd, 3.1 px)
    # frame 40's s = l end bent by 0.6 rad over its last 2 samples (11 px): the tip moves 6.2 px
    Xn[40], Yn[40] = _bend_end(Xn[40], Yn[40], 2, 0.6)
    out = tip_outliers(Xn, Yn, ok)
    assert [(i, e) for i, e, _, _ in out] == [(40, 1)]
    assert abs(out[0][2]) == pytest.approx(11 * math.sin(0.6), rel=0.35)
    # a second one, at the other end, next to the first
    Xn[42], Yn[42] = (a[::-1] for a in _bend_end(Xn[42][::-1], Yn[42][::-1], 2, -0.6))
    assert sorted((i, e) for i, e, _, _ in tip_outliers(Xn, Yn, ok)) == [(40, 1), (42, 0)]


def test_track_reports_a_tip_outlier_frame_with_its_reason(sim):
    pytest.importorskip("skimage")
    from flutterswim.tracking import failures, render, track

    sub = SimpleNamespace(t=sim.t[:30].copy(), x=sim.x[:30].copy(), y=sim.y[:30].copy())
    # frame 17: the last of 25 nodes (11 px) bent by 0.4 rad (tip 4.4 px off its path); same
    # length, so only the check across frames can see it
    sub.x[17], sub.y[17] = _bend_end(sub.x[17], sub.y[17], 1, 0.4)
    mv = render(sub, um_per_px=UM_PER_PX, snr=8.0, seed=3)
    tr = track(mv, px_per_mm=mv.px_per_mm, fps=FPS)
    f = failures(tr)
    assert [i for i, _, _ in f] == [17], f
    assert f[0][2].startswith("tip outlier: the s = l end")
    assert tr.meta["temporal"]["tip_check"].startswith("done")
    # with the check off the frame is kept
    tr0 = track(mv, px_per_mm=mv.px_per_mm, fps=FPS, tip_check=False)
    assert failures(tr0) == [] and tr0.meta["temporal"]["tip_check"] == "off"


def test_bad_temporal_parameters_are_parameter_errors():
    from flutterswim._validate import ParameterError
    from flutterswim.tracking import track

    for kw, name in ((dict(smooth_frames=3), "smooth_frames"), (dict(smooth_frames=7.5), "smooth_frames"),
                     (dict(tip_k=0), "tip_k"), (dict(tip_floor_px=-1), "tip_floor_px")):
        with pytest.raises(ParameterError, match=name):
            track(np.zeros((3, 32, 32)), px_per_mm=10, fps=50, **kw)
