"""A subcritical Hopf point (l1 > 0 at eta_par = 150, eta_perp = 300, N = 12): the branch leaves
it towards the side where the straight state is stable, as unstable orbits, and folds back at
chi ~ 41 into stable strokes. A review found targets between the fold and the Hopf point
refused ("the stroke branch exists for chi above the Hopf point"), though stable strokes exist
there beside the stable straight state."""

import numpy as np
import pytest

import flutterswim as fs
from flutterswim._validate import ParameterError
from flutterswim.orbits import continue_orbits, hopf_point, normal_form

G = fs.Groups(150.0, 300.0, 47.28)


@pytest.fixture(scope="module")
def hopf():
    h = hopf_point(G, "chi", n_segments=12)
    nf = normal_form(h)
    assert not nf.supercritical and nf.lyapunov_coefficient > 0
    return h


def test_a_target_between_the_fold_and_the_hopf_point_is_reached_on_the_stable_strokes(hopf):
    to = hopf.value - 2.0
    b = continue_orbits(G, "chi", to, n_segments=12, n_points=10)
    v = np.asarray(b.values)
    assert v[-1] == pytest.approx(to) and b.orbits[-1].stable
    assert v.min() < to  # it ran past the target to the fold, then came back
    k = int(np.argmin(v))
    assert 0 < k < v.size - 1
    # the first leg (Hopf point to fold) is unstable, the return leg stable: two strokes at ``to``
    first = [o for o, x in zip(b.orbits[:k], v[:k]) if abs(x - to) < 0.3]
    assert first and not any(o.stable for o in first)
    assert b.orbits[-1].amplitude > max(o.amplitude for o in first)
    # and the straight state there is stable: the branch is bistable with it
    from flutterswim.orbits import leading_pair

    assert leading_pair(G.replace(chi=to) if hasattr(G, "replace") else fs.Groups(G.eta_par, G.eta_perp, to),
                        12).real < 0


def test_a_target_beyond_the_fold_says_so(hopf):
    b = continue_orbits(G, "chi", 30.0, n_segments=12, n_points=10)
    assert "no stroke at chi=30" in b.message and "folds back" in b.message
    fold = float(b.message.split("folds back at chi=")[1].split()[0])
    assert 30.0 < fold < hopf.value and min(b.values) == pytest.approx(fold, rel=1e-5)


def test_a_supercritical_branch_still_refuses_the_stable_side():
    g = fs.Groups(41.5, 71.5, 60.0)
    with pytest.raises(ParameterError, match=r"above the Hopf point .*supercritical"):
        continue_orbits(g, "chi", 40.0, n_segments=12, n_points=10)
