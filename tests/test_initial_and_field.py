import numpy as np
import pytest

import flutterswim as fs
from flutterswim.field import Piecewise


def test_profiles_from_numbers_callables_and_samples():
    n = 20
    s_mid = (np.arange(n) + 0.5) / n
    s_nodes = np.arange(n + 1) / n
    linear = fs.InitialState(theta=np.linspace(0.0, 2.0, 11), kappa=lambda s: s**2, position=(1.0, 2.0))
    y = linear.state(n)
    np.testing.assert_allclose(y[:2], [1.0, 2.0])
    np.testing.assert_allclose(y[2 : n + 2], 2.0 * s_mid, rtol=1e-14)  # exact for a linear profile
    np.testing.assert_allclose(y[n + 2 :], s_nodes**2, rtol=1e-14)
    on_grid = fs.InitialState(theta=np.cos(s_mid)).state(n)
    np.testing.assert_array_equal(on_grid[2 : n + 2], np.cos(s_mid))


@pytest.mark.parametrize("bad, name", [({"theta": [[1.0, 2.0]]}, "theta"), ({"kappa": [0.0, np.nan]}, "kappa"),
                                       ({"position": (0.0, np.inf)}, "position")])
def test_bad_profiles_are_named(bad, name):
    with pytest.raises(fs.ParameterError, match=name):
        fs.InitialState(**bad).state(8)


def test_piecewise_schedules():
    hold = Piecewise([0.0, 1.0, 2.0], [0.0, 1.0, 3.0])
    lin = Piecewise([0.0, 1.0, 2.0], [0.0, 1.0, 3.0], kind="linear")
    assert [hold(t) for t in (-1.0, 0.5, 1.0, 1.5, 9.0)] == [0.0, 0.0, 1.0, 1.0, 3.0]
    assert lin(1.5) == pytest.approx(2.0)
    assert hold.scaled(2.0).breakpoints == (0.0, 0.5, 1.0)
    with pytest.raises(fs.ParameterError, match="increasing"):
        Piecewise([0.0, 0.0], [1.0, 2.0])
