import numpy as np
import pytest

import flutterswim as fs


@pytest.fixture(scope="session")
def paper_groups() -> fs.Groups:
    return fs.PAPER.groups


def crossings(t: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Times of upward zero crossings of d(t), linearly interpolated."""
    i = np.nonzero((d[:-1] < 0) & (d[1:] >= 0))[0]
    return t[i] - d[i] * (t[i + 1] - t[i]) / (d[i + 1] - d[i])


def stroke(res, n_last: int = 4) -> tuple[float, float]:
    """(period, advancement per cycle along x) from the last n_last strokes of a run.

    Section: upward crossings of the tip's lateral offset from the centroid.
    """
    tc = crossings(res.t, res.y[:, -1] - res.y.mean(axis=1))
    xc = np.interp(tc, res.t, res.x.mean(axis=1))
    return float(np.mean(np.diff(tc)[-n_last:])), float(np.mean(np.diff(xc)[-n_last:]))


def rendered_paper_stroke(seed: int, snr: float = 5.0, fps: float = 50.0):
    """The paper's settled stroke as a movie: the last 101 frames of 10 s (N = 24) at ``fps``,
    14 um per pixel, and its truth described over all of them. (movie, Descriptors)"""
    from types import SimpleNamespace

    from flutterswim.analysis.descriptors import describe
    from flutterswim.tracking import render
    from flutterswim.tracking.evaluate import truth_track

    r = fs.simulate(fs.PAPER, 10.0, n_segments=24, frame_dt=1.0 / fps)
    sl = slice(r.t.size - 101, r.t.size)
    mv = render(SimpleNamespace(t=r.t[sl], x=r.x[sl], y=r.y[sl]), um_per_px=14.0, snr=snr, seed=seed)
    return mv, describe(truth_track(mv, 3.7), n_last=100)


@pytest.fixture(autouse=True)
def _close_pyplot_figures():
    """Figures returned for the screen (path None) are pyplot's: close them after each test."""
    yield
    import sys

    plt = sys.modules.get("matplotlib.pyplot")
    if plt is not None:
        plt.close("all")
