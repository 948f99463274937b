"""Serial, process-pool and Dask runs of the same sweep give identical datasets."""

import numpy as np
import pytest
import xarray as xr

from flutterswim.sweep import sweep

SMALL = {"n_segments": 12, "rtol": 1e-3, "atol": 1e-5, "t_cap": 30.0, "n_cycles": 3, "chunk": 5.0}
AXES = ["kappa_E_ratio=0.4,1.0,1.6"]


def _clean(ds):
    return ds.drop_vars("wall_time_s")


@pytest.fixture(scope="module")
def serial_result():
    return sweep(AXES, backend="serial", settings=SMALL, progress=False)


def test_serial_result_is_meaningful(serial_result):
    ds = serial_result
    assert not ds["failed"].any() and ds["done"].all()
    assert bool(ds["straight"].sel(kappa_E_ratio=0.4)) and not bool(ds["limit_cycle"].sel(kappa_E_ratio=0.4))
    assert bool(ds["limit_cycle"].sel(kappa_E_ratio=1.0)) and bool(ds["limit_cycle"].sel(kappa_E_ratio=1.6))
    assert np.isfinite(ds["period_s"].sel(kappa_E_ratio=1.0))
    assert np.isnan(ds["period_s"].sel(kappa_E_ratio=0.4))


def test_process_pool_identical(serial_result, tmp_path):
    ds = sweep(AXES, backend="processes", workers=2, settings=SMALL, progress=False, out=str(tmp_path / "p.zarr"))
    xr.testing.assert_identical(_clean(ds.load()), _clean(serial_result))


def test_dask_identical(serial_result, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            client.wait_for_workers(2)
            assert len(client.scheduler_info()["workers"]) == 2
        ds = sweep(AXES, backend="dask", scheduler=cluster.scheduler_address, settings=SMALL, progress=False,
                   out=str(tmp_path / "d.zarr"))
    xr.testing.assert_identical(_clean(ds.load()), _clean(serial_result))
