"""A settled stroke filmed at about 13 frames per stroke is a limit cycle. Its cycles hold 12
or 13 frames, and each cycle's Fourier fit took (frames - 1) / 4 harmonics: 2 for some, 3 for
others, so the third harmonic's power, present in some cycles only, read as a change from cycle
to cycle, and describe said "no limit cycle ... record longer" of an exactly periodic record (a
review: the paper's filament in a medium twice as viscous, at 30 fps). The cycles now share one
harmonic count."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.analysis import describe
from flutterswim.analysis.cycles import detect_cycles
from flutterswim.analysis.track import Track
from flutterswim.orbits import periodic_orbit


@pytest.fixture(scope="module")
def orbit():
    return periodic_orbit(fs.PAPER.replace(mu=2 * fs.PAPER.mu), n_segments=24)


@pytest.mark.parametrize("fps, strokes", [(30.0, 6.3), (30.0, 12.0), (50.0, 6.3)])
def test_an_exactly_periodic_record_is_a_limit_cycle_at_any_frame_rate(orbit, fps, strokes):
    dense = orbit.to_result(n_cycles=int(np.ceil(strokes)) + 1, frames_per_cycle=400)
    t = np.arange(0.0, strokes * orbit.period, 1.0 / fps)
    x = np.stack([np.interp(t, dense.t, dense.x[:, j]) for j in range(dense.x.shape[1])], axis=1)
    y = np.stack([np.interp(t, dense.t, dense.y[:, j]) for j in range(dense.y.shape[1])], axis=1)
    tr = Track(t=t, x=x, y=y, units="m", length=fs.PAPER.l, field_angle=0.0)
    cyc = detect_cycles(tr)
    frames = np.diff(np.searchsorted(t, cyc.starts))
    if fps == 30.0:  # (the case: cycles of two frame counts, fitting two harmonic counts before)
        assert set(frames.tolist()) == {12, 13}
    assert cyc.limit_cycle
    d = describe(tr, n_last=4)
    assert d.limit_cycle and not d.note.startswith("no limit cycle")
    assert d.period_s == pytest.approx(orbit.period, rel=2e-3)
