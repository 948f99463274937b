"""Files a user derived from ours keep our signature (xarray copies the attributes, pandas the
tracked_by column) and were overwritten as ours (a held-out review, stop 44). Ours now means the
data as written: a fingerprint of the NetCDF variables, exact CSV columns and a hash per row."""

import subprocess
import sys

import numpy as np
import pytest

import flutterswim as fs
from flutterswim._paths import FINGERPRINT, is_ours, row_signature
from flutterswim.tracking.batch import CSV_COLUMNS, FAILED_COLUMNS


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    d = tmp_path_factory.mktemp("runs")
    run = fs.simulate(fs.PAPER, 0.3, n_segments=12)
    run.save(d / "run.nc")
    return d / "run.nc"


def test_a_netcdf_derived_from_ours_is_not_ours(saved, tmp_path):
    xr = pytest.importorskip("xarray")
    assert is_ours(saved)
    with xr.open_dataset(saved, engine="h5netcdf") as ds:
        ds = ds.load()
    assert FINGERPRINT in ds.attrs  # (carried into anything derived from it)
    for name, derived in (("sliced", ds.isel(t=slice(0, 5))), ("added", ds.assign(mine=ds["t"] * 2)),
                          ("edited", ds.assign(theta=ds["theta"] + 1e-12))):
        p = tmp_path / f"{name}.nc"
        derived.to_netcdf(p, engine="h5netcdf")
        assert not is_ours(p), name
    same = tmp_path / "copy.nc"
    ds.to_netcdf(same, engine="h5netcdf")  # the same data re-written: still the run we wrote
    assert is_ours(same)


def test_the_cli_refuses_to_overwrite_a_derived_netcdf(saved, tmp_path):
    xr = pytest.importorskip("xarray")
    with xr.open_dataset(saved, engine="h5netcdf") as ds:
        ds = ds.load()
    p = tmp_path / "my_analysis.nc"
    ds.assign(my_analysis=ds["t"] * 2).to_netcdf(p, engine="h5netcdf")
    before = p.read_bytes()
    r = subprocess.run([sys.executable, "-m", "flutterswim", "simulate", "--t-end", "0.1", "--segments", "8",
                        "--quiet", "--out", str(p)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "was not written by flutterswim" in r.stderr, r.stderr
    assert p.read_bytes() == before


def _batch_csv(rows):
    lines = [",".join(CSV_COLUMNS)]
    for r in rows:
        fields = [str(v) for v in r]
        lines.append(",".join(fields + [row_signature(fields)]))
    return "\n".join(lines) + "\n"


def test_a_batch_csv_is_ours_only_as_written(tmp_path):
    row = ["85", "1", "0.377", "0.394", "1.13", "0.39", "0.001", "0.001", "0.002", "0.003", "5", "3.7", "0.004",
           "101", "0", "a.tif"]
    assert len(row) == len(CSV_COLUMNS) - 1
    p = tmp_path / "trials.csv"
    p.write_text(_batch_csv([row]))
    assert is_ours(p)
    edited = list(row)
    edited[2] = "0.4"  # a value changed by hand, its signature copied
    sig = row_signature(row)
    (tmp_path / "e.csv").write_text(",".join(CSV_COLUMNS) + "\n" + ",".join(edited + [sig]) + "\n")
    assert not is_ours(tmp_path / "e.csv")
    # a column added (pandas keeps tracked_by): not ours
    (tmp_path / "a.csv").write_text(",".join(CSV_COLUMNS + ("my_note",)) + "\n" + ",".join(row + [sig, "bad focus"]) + "\n")
    assert not is_ours(tmp_path / "a.csv")
    # the failures file, signed the same way
    (tmp_path / "f.csv").write_text(",".join(FAILED_COLUMNS) + "\n" + ",".join(["a.tif", "no stroke",
                                                                                 row_signature(["a.tif", "no stroke"])]) + "\n")
    assert is_ours(tmp_path / "f.csv")
    assert np.all([is_ours(tmp_path / n) for n in ("trials.csv", "f.csv")])
