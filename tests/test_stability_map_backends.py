"""The stability map on the sweep backends gives the same map as in-process."""

import numpy as np
import pytest

from flutterswim.stability import stability_map

GRID = dict(eta_perp=np.linspace(10.0, 200.0, 12), chi=np.linspace(-120.0, 120.0, 25))


@pytest.fixture(scope="module")
def reference():
    return stability_map(**GRID)


@pytest.mark.parametrize("executor", ["serial", "processes"])
def test_map_on_local_backends_is_identical(reference, executor):
    m = stability_map(**GRID, executor=executor, workers=2)
    np.testing.assert_array_equal(m.omega, reference.omega)
    assert np.isfinite(m.omega).all()


def test_map_on_a_dask_cluster_is_identical(reference):
    pytest.importorskip("distributed")
    m = stability_map(**GRID, executor="dask-local", workers=2)
    np.testing.assert_array_equal(m.omega, reference.omega)
