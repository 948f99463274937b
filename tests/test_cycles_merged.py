"""A cycle that holds two strokes (the section missed the crossing between them) on a sparse,
unevenly sampled record: it must not be described as one stroke of twice the period."""

import dataclasses
import importlib
import math
import warnings

import numpy as np
import pytest

from flutterswim._validate import ParameterError
from flutterswim.analysis.descriptors import describe
from flutterswim.analysis.synthetic import wave_track

cycles = importlib.import_module("flutterswim.analysis.cycles")


def _subset(tr, keep):
    def part(a):
        return a if a is None or not np.ndim(a) else np.asarray(a)[keep]

    return dataclasses.replace(tr, t=tr.t[keep], x=tr.x[keep], y=tr.y[keep], field_angle=part(tr.field_angle),
                               theta=part(tr.theta), kappa=part(tr.kappa),
                               field_strength=part(getattr(tr, "field_strength", None)))


def _sine_record(period: float, n_per: int, n_strokes: int):
    t = np.arange(n_per * n_strokes + 1) * period / n_per + 0.013 * period
    return t, np.sin(2 * np.pi * t / period)


@pytest.mark.parametrize("m", [2, 3])
def test_a_cycle_holding_m_strokes_is_merged_and_its_neighbours_are_not(m):
    """Crossings at every period but m - 1 of them removed: only that cycle is merged."""
    P = 0.4
    t, d = _sine_record(P, 9, 12)
    starts = np.arange(1, 12) * P
    keep = np.ones(starts.size, bool)
    keep[4 : 4 + m - 1] = False
    st = starts[keep]
    got = cycles._merged_strokes(t, d, st, np.diff(st), P)
    want = np.zeros(st.size - 1, bool)
    want[3] = True
    assert np.array_equal(got, want)


def test_a_slower_stroke_swings_once_and_is_not_merged():
    """The field changed: the last cycles last twice as long, but each swings once."""
    P = 0.4
    t1 = np.arange(0, 6 * P, P / 9)
    t2 = 6 * P + np.arange(0, 4 * 2 * P, P / 9)
    t = np.r_[t1, t2]
    d = np.where(t < 6 * P, np.sin(2 * np.pi * t / P), np.sin(2 * np.pi * (t - 6 * P) / (2 * P)))
    starts = np.r_[np.arange(0, 6) * P, 6 * P + np.arange(0, 4) * 2 * P]
    got = cycles._merged_strokes(t, d, starts, np.diff(starts), P)
    assert not np.any(got)


def test_sparse_uneven_records_are_never_described_at_a_multiple_of_the_period():
    """Five frames per stroke with half of them dropped at random (about 2.5 left): each record
    is either refused or described at the stroke's own period. Before, one in 40 was described
    as a single 'cycle' of 4.4 periods (the section saw one stroke in four)."""
    P = 0.4
    full = wave_track(period=P, duration=16.0, n_frames=4001, speed=0.05, seed=0)
    base = np.arange(0, full.n_frames, 20)
    described = 0
    for seed in range(40):
        keep = base[np.random.default_rng(seed).random(base.size) < 0.5]
        tr = _subset(full, keep)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                d = describe(tr)
        except ParameterError as e:
            assert "\n" not in str(e)
            continue
        described += 1
        assert math.isclose(d.period_s, P, rel_tol=0.1), (seed, d.period_s)
    assert described >= 10  # most such records still hold enough cycles


def test_the_refusal_names_the_cause():
    """Every cycle of a record at 2.1 frames per stroke holds strokes the section missed."""
    P = 0.4
    full = wave_track(period=P, duration=16.0, n_frames=4001, speed=0.05, seed=0)
    base = np.arange(0, full.n_frames, 20)
    keep = base[np.random.default_rng(28).random(base.size) < 0.5]
    tr = _subset(full, keep)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = cycles.detect_cycles(tr)
        assert np.count_nonzero(c.merged) * 2 >= c.n_cycles
        with pytest.raises(ParameterError, match="hold two or more strokes"):
            describe(tr)


def _thinned(tr0, fps: float, drop: float, seed: int):
    """tr0 seen by a camera at ``fps`` (the frame nearest each grid time, the grid offset by
    0.0037 seed s), with a fraction ``drop`` of those frames dropped at random."""
    grid = np.arange(tr0.t[0] + 0.0037 * seed, tr0.t[-1], 1 / fps)
    idx = np.unique(np.searchsorted(tr0.t, grid))
    keep = np.zeros(tr0.t.size, bool)
    keep[idx[idx < tr0.t.size]] = True
    keep &= np.random.default_rng(seed).random(tr0.t.size) >= drop
    return _subset(tr0, np.flatnonzero(keep))


@pytest.fixture(scope="module")
def onset_run():
    import flutterswim as fs
    from flutterswim.analysis.track import as_track

    return as_track(fs.simulate(fs.PAPER, 12.0, n_segments=24))


@pytest.mark.parametrize("fps, drop, seed", [(10, 0.2, 2), (12, 0.2, 1)])
def test_a_merged_cycle_ends_the_window(onset_run, fps, drop, seed):
    """10-12 fps with a fifth of the frames dropped, from the field's start: a merged cycle that
    the window passed let it run back into the onset (advance 0.08 mm for 0.40); it must end the
    window as a skipped stroke does."""
    thinned = _thinned(onset_run, fps, drop, seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        want = describe(onset_run)
        got = describe(thinned)
    assert got.advance_per_cycle_mm == pytest.approx(want.advance_per_cycle_mm, rel=0.05)
    assert got.period_s == pytest.approx(want.period_s, rel=0.05)


def test_a_window_far_from_the_records_end_says_so(onset_run):
    """10 fps, a fifth dropped, seed 19: every later cycle misses frames and the window falls on
    the onset (advance 0.06 mm for 0.40). Without a limit cycle that must be said."""
    thinned = _thinned(onset_run, 10, 0.2, 19)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = describe(thinned)
    assert onset_run.t[-1] - d.window_end_s > 2 * d.period_s
    assert "before the record's last" in d.note and "may describe an earlier stroke" in d.note


def test_a_window_spread_thin_over_gaps_says_so(onset_run):
    """12 fps, a fifth dropped, seed 9: three described cycles spread over 8 s, the cycles between
    missing frames, the earliest in the onset (advance 0.14 mm for 0.40): said."""
    thinned = _thinned(onset_run, 12, 0.2, 9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = describe(thinned)
    assert d.window_end_s - d.window_start_s > (d.n_cycles_used + 2) * d.period_s
    assert "spread over" in d.note and "may be an earlier stroke" in d.note
