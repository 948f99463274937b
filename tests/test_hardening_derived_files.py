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


def _cli(args, cwd):
    return subprocess.run([sys.executable, "-m", "flutterswim", *args], capture_output=True, text=True, timeout=600,
                          cwd=cwd)


def test_a_default_output_of_another_input_is_not_replaced(tmp_path):
    """track's default track.nc and track-batch's trials.csv were replaced by the results of
    another movie or folder without a word. Without --out, such a file is now refused; the same
    input replaces it, and --out names another file."""
    tifffile = pytest.importorskip("tifffile")
    pytest.importorskip("skimage")
    from types import SimpleNamespace

    from flutterswim.tracking import render

    r = fs.simulate(fs.PAPER, 10.0, n_segments=12, frame_dt=0.02)
    for k, name in enumerate(("a", "b")):
        sl = slice(r.t.size - 40 - k, r.t.size - k)
        mv = render(SimpleNamespace(t=r.t[sl], x=r.x[sl], y=r.y[sl]), um_per_px=14.0, snr=8.0, seed=k)
        (tmp_path / name).mkdir()
        tifffile.imwrite(tmp_path / name / "85V_sample1.tif", mv.frames.astype(np.float32))
        tifffile.imwrite(tmp_path / f"{name}.tif", mv.frames.astype(np.float32))
    common = ["--px-per-mm", f"{mv.px_per_mm:.6f}", "--fps", "50", "--quiet"]
    assert _cli(["track", "a.tif", *common], tmp_path).returncode == 0
    first = (tmp_path / "track.nc").read_bytes()
    other = _cli(["track", "b.tif", *common], tmp_path)
    assert other.returncode == 2 and "holds the results of 'a.tif'" in other.stderr, other.stderr
    assert (tmp_path / "track.nc").read_bytes() == first
    assert _cli(["track", "a.tif", *common], tmp_path).returncode == 0  # the same movie again
    assert _cli(["track", "b.tif", *common, "--out", "b.nc"], tmp_path).returncode == 0
    assert _cli(["track-batch", "a", *common], tmp_path).returncode in (0, 1)
    assert (tmp_path / "trials.csv").is_file()
    table = (tmp_path / "trials.csv").read_bytes()
    batch = _cli(["track-batch", "b", *common], tmp_path)
    assert batch.returncode == 2 and "holds the results of 'a'" in batch.stderr, batch.stderr
    assert (tmp_path / "trials.csv").read_bytes() == table


def test_a_large_file_is_fingerprinted_in_blocks(tmp_path):
    """The fingerprint read each variable whole (twice over in memory: 324 MB for a 160 MB run);
    it is now read in blocks, and gives the same result as hashing the whole array."""
    import hashlib

    import h5py

    from flutterswim._paths import _h5_fingerprint

    xr = pytest.importorskip("xarray")
    big = np.arange(3_000_000, dtype=float).reshape(30_000, 100)  # 24 MB: two blocks
    p = tmp_path / "big.nc"
    xr.Dataset({"v": (("t", "p"), big)}).to_netcdf(p, engine="h5netcdf")
    with h5py.File(p, "r") as h:
        got = _h5_fingerprint(h)
        whole = hashlib.sha256()
        for name in sorted(h):
            d = h[name]
            whole.update(f"{name}|{d.dtype.str}|{d.shape}|".encode())
            whole.update(np.ascontiguousarray(d[()]).tobytes())
    assert got == whole.hexdigest()
