"""Standard errors of the lateral peak-to-peak: the cycles' spread, and a tracked movie's
periodic-template noise that every cycle shares (which the spread cannot show)."""

import dataclasses
import math

import numpy as np

from flutterswim.analysis.descriptors import describe
from flutterswim.analysis.synthetic import wave_track


def _templated(tr, se_mm):
    # a track as the tracker leaves a templated movie: the coefficient noise at both ends (in
    # the track's units)
    se = se_mm / (tr.scale_m * 1e3)
    return dataclasses.replace(tr, meta={**(tr.meta or {}), "template_coef_se": [se, se],
                                         "template_coef_stderr": [se, se]})


def test_shared_template_noise_of_a_sine_is_twice_the_coefficient_error():
    # every frame on its phase of one sine (x = s + speed t, y = A sin(k s - w t)): the cycles
    # agree exactly, so the spread is 0 and the standard error is the template's alone. The
    # peak-to-peak w(phi+) - w(phi-) of a sine moves by 2 se for coefficient errors se (the
    # harmonics beyond the first hold nothing above the template's noise and are left out)
    tr = wave_track(period=0.4, n_frames=201, duration=4.0, n_points=41)
    plain = describe(tr, n_last=100)
    assert plain.leading_lateral_p2p_se_mm < 1e-9 * plain.leading_lateral_p2p_mm
    se = 1e-3 * plain.leading_lateral_p2p_mm
    d = describe(_templated(tr, se), n_last=100)
    assert math.isclose(d.leading_lateral_p2p_mm, plain.leading_lateral_p2p_mm, rel_tol=1e-8)
    for got in (d.leading_lateral_p2p_se_mm, d.trailing_lateral_p2p_se_mm):
        assert math.isclose(got, 2 * se, rel_tol=1e-3)


def test_the_cycles_spread_adds_in_quadrature():
    # noisy frames: the cycles scatter; with the template's noise as well, the two add in
    # quadrature (the spread's share is what describe reports without a template)
    tr = wave_track(period=0.4, n_frames=201, duration=4.0, n_points=41, noise=2e-3, seed=3)
    spread = describe(tr, n_last=100).leading_lateral_p2p_se_mm
    assert spread > 0
    se = 2 * spread
    both = describe(_templated(tr, se), n_last=100).leading_lateral_p2p_se_mm
    assert math.isclose(both, math.hypot(spread, 2 * se), rel_tol=0.02)


def test_an_odd_harmonic_that_the_waveform_holds_doubles_the_variance():
    # a lateral waveform sin + 0.1 sin 3: peak-to-peak at phases half a period apart, so the
    # 3rd harmonic's coefficient errors move it as much as the first's: 2 sqrt(2) se
    tr = wave_track(period=0.4, n_frames=401, duration=4.0, n_points=41)
    ph = 2 * np.pi * tr.t / 0.4
    y = tr.y + 0.1 * 0.1 * np.sin(3 * ph)[:, None]
    tr3 = dataclasses.replace(tr, y=y)
    se = 1e-4 * describe(tr3, n_last=100).leading_lateral_p2p_mm
    d = describe(_templated(tr3, se), n_last=100)
    assert math.isclose(d.leading_lateral_p2p_se_mm, 2 * math.sqrt(2) * se, rel_tol=0.02)
