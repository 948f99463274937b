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
