"""Standard errors of the lateral peak-to-peak: the cycles' spread, and a tracked movie's
periodic-template noise that every cycle shares (which the spread cannot show); and a noisy
record of a filament that does not swim, whose excursions are measured across its body axis."""

import dataclasses
import math

import numpy as np
import pytest

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


def _g(h, delta):
    return 2.0 - 2.0 * np.cos(2 * np.pi * np.asarray(h) * delta)


def test_an_asymmetric_waveform_and_the_harmonics_beyond_the_tested_ones():
    # 40 frames per stroke: each cycle fits 6 harmonics, the 6th untested (always kept). A 2nd
    # harmonic puts the waveform's maximum and minimum delta apart (not half a period): the
    # error is se sqrt(sum_h 2 - 2 cos 2 pi h delta) over h = 1, 2 (held) and 6 (kept untested)
    tr = wave_track(period=0.4, n_frames=401, duration=4.0, n_points=41)
    w = 2 * np.pi / 0.4
    y = tr.y + 0.02 * np.sin(2 * w * tr.t + 0.7)[:, None]
    tr2 = dataclasses.replace(tr, y=y)
    # delta from the leading (s = l) end's own waveform, on a fine grid of one period
    t = np.linspace(0.0, 0.4, 40001, endpoint=False)
    A_end = 0.1 * (0.4 + 0.6)  # wave_track's amplitude at s = l
    q = A_end * np.sin(2 * np.pi * 1.0 / 0.8 - w * t) + 0.02 * np.sin(2 * w * t + 0.7)
    delta = (t[np.argmax(q)] - t[np.argmin(q)]) / 0.4
    assert abs(abs(delta) - 0.5) > 0.05  # not half a period apart
    se = 1e-4 * describe(tr2, n_last=100).leading_lateral_p2p_mm
    d = describe(_templated(tr2, se), n_last=100)
    assert d.leading_end == "s=l"
    want = se * math.sqrt(float(np.sum(_g([1, 2, 6], delta))))
    assert math.isclose(d.leading_lateral_p2p_se_mm, want, rel_tol=0.01)


def test_harmonics_the_pooled_cycles_lend_count_too():
    # 20 frames per stroke: a cycle fits 4 harmonics of its own and borrows the 5th from all
    # the cycles together; with a 5th harmonic in the waveform, both the 1st and the 5th move
    # the peak-to-peak: 2 sqrt(2) se (without the loan, 2 se)
    tr = wave_track(period=0.4, n_frames=201, duration=4.0, n_points=41)
    y = tr.y + 0.01 * np.sin(5 * 2 * np.pi * tr.t / 0.4)[:, None]
    tr5 = dataclasses.replace(tr, y=y)
    se = 1e-4 * describe(tr5, n_last=100).leading_lateral_p2p_mm
    d = describe(_templated(tr5, se), n_last=100)
    assert math.isclose(d.leading_lateral_p2p_se_mm, 2 * math.sqrt(2) * se, rel_tol=0.02)


def test_unknown_error_of_one_cycle_and_a_missing_stderr():
    tr = wave_track(period=0.4, n_frames=201, duration=4.0, n_points=41)
    one = describe(_templated(tr.window(0.3, 1.2), 1e-3), n_last=100)
    assert one.n_cycles_used == 1 and math.isnan(one.leading_lateral_p2p_se_mm)
    # a NaN template_coef_stderr falls back to template_coef_se (a sine: 2 se)
    se = 1e-3 * describe(tr, n_last=100).leading_lateral_p2p_mm
    t = _templated(tr, se)
    t = dataclasses.replace(t, meta={**t.meta, "template_coef_stderr": [math.nan, math.nan]})
    assert math.isclose(describe(t, n_last=100).leading_lateral_p2p_se_mm, 2 * se, rel_tol=1e-3)


def test_a_header_only_batch_csv_written_before_the_standard_errors_is_still_ours(tmp_path):
    # a batch whose trials all failed wrote only its header; the columns before the standard
    # errors must still be recognised, so that a rerun may replace the file
    from flutterswim._paths import is_ours
    from flutterswim.tracking.batch import CSV_COLUMNS

    old = [c for c in CSV_COLUMNS if c not in ("lateral_se_mm", "leading_lateral_se_mm")]
    assert len(old) == len(CSV_COLUMNS) - 2
    p = tmp_path / "trials.csv"
    p.write_text(",".join(old) + "\n", encoding="utf-8")
    assert is_ours(p)
    p.write_text(",".join(old[:-2] + ["tracked_by"]) + "\n", encoding="utf-8")  # not a header we wrote
    assert not is_ours(p)


@pytest.mark.parametrize("noise", [1e-3, 5e-3])
def test_a_noisy_record_of_a_filament_that_does_not_swim_is_still(noise):
    # no advance, positions with noise and no movie's pixel size to judge it by: the cycles'
    # displacements point every which way, so there is no swimming direction, and the lateral
    # excursions are measured across the body axis (as without noise), not across a direction
    # set by the noise (they read 483 / 455 mm for 200 / 80 at noise 1e-3)
    clean = describe(wave_track(period=0.4, n_frames=201, duration=4.0, speed=0.0), n_last=100)
    d = describe(wave_track(period=0.4, n_frames=201, duration=4.0, speed=0.0, noise=noise, seed=1), n_last=100)
    assert "no net swimming" in d.note
    assert math.isclose(d.leading_lateral_p2p_mm, clean.leading_lateral_p2p_mm, rel_tol=0.01)
    assert math.isclose(d.trailing_lateral_p2p_mm, clean.trailing_lateral_p2p_mm, rel_tol=0.05)
    # while the same record swimming slowly, in any direction, swims (turning swimmers: the
    # steering tests)
    for kw in ({"speed": 0.05}, {"speed": 0.05, "field_angle": 0.3}):
        s = describe(wave_track(period=0.4, n_frames=201, duration=4.0, noise=noise, seed=1, **kw), n_last=100)
        assert "no net swimming" not in s.note


def test_a_coarsely_sampled_cycle_borrows_a_3rd_harmonic_the_template_holds():
    # about 10 frames per stroke: each cycle fits 2 harmonics and the pooled cycles lend the
    # 3rd to 5th. A real 3rd harmonic (3 % of the leading end's amplitude) held well above the
    # template's coefficient noise (its rss drop 8 times the noise's, n se^2) is lent although
    # the 4th and 5th hold nothing (their mean with it is under the threshold of 5): the
    # peak-to-peak is that of the true waveform
    period, n_frames, duration = 0.4027, 101, 4.0
    tr = wave_track(period=period, n_frames=n_frames, duration=duration, n_points=41)
    w = 2 * np.pi / period
    a3 = 0.003
    tr3 = dataclasses.replace(tr, y=tr.y + a3 * np.sin(3 * w * tr.t)[:, None])
    t = np.linspace(0.0, period, 40001, endpoint=False)
    A_end = 0.1  # wave_track's amplitude at s = l, the leading end
    q = A_end * np.sin(2 * np.pi * 1.0 / 0.8 - w * t) + a3 * np.sin(3 * w * t)
    truth = float(q.max() - q.min())
    d = describe(_templated(tr3, a3 / 4 * tr3.scale_m * 1e3), n_last=100)
    assert abs(d.leading_lateral_p2p_mm / (truth * tr3.scale_m * 1e3) - 1) < 1e-3
