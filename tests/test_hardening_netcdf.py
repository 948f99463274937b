"""Runs are CF-style NetCDF: Conventions, units and long_name everywhere, parameters and groups
as numeric attributes with units, arrays labelled in the units they are in; saves are atomic."""

import numpy as np
import pytest
import xarray as xr

import flutterswim as fs


@pytest.fixture(scope="module")
def run():
    return fs.simulate(fs.PAPER, 0.5, n_segments=8, forces=True)


def test_cf_attributes(run, tmp_path):
    p = run.save(tmp_path / "r.nc")
    with xr.open_dataset(p, engine="h5netcdf") as ds:
        assert ds.attrs["Conventions"].startswith("CF-")
        for name in ds.variables:
            assert ds[name].attrs.get("units") is not None and ds[name].attrs.get("long_name"), name
        for k, v in fs.PAPER.to_dict().items():
            assert ds.attrs[f"parameter_{k}"] == v and ds.attrs[f"parameter_{k}_units"]
        assert ds.attrs["parameter_l_units"] == "m" and ds.attrs["parameter_tau_units"] == "s"
        for k, v in fs.PAPER.groups.to_dict().items():
            assert ds.attrs[f"group_{k}"] == pytest.approx(v) and ds.attrs[f"group_{k}_units"] == "1"
        assert ds["x"].attrs["units"] == "m" and ds["t"].attrs["units"] == "s"


def test_state_final_is_labelled_in_its_own_units(run, tmp_path):
    """The integrator state is dimensionless (r0/l, theta, kappa l) even in an SI file: its
    label says so, and the numbers agree with the SI arrays divided by the scales."""
    p = run.save(tmp_path / "r.nc")
    with xr.open_dataset(p, engine="h5netcdf") as ds:
        assert ds["state_final"].attrs["units"] == "1"
        st = ds["state_final"].values
        n = run.n_segments
        L = fs.PAPER.l
        np.testing.assert_allclose(st[:2], [ds["r0_x"].values[-1] / L, ds["r0_y"].values[-1] / L], rtol=1e-12)
        np.testing.assert_allclose(st[2 : n + 2], ds["theta"].values[-1], rtol=1e-12)
        np.testing.assert_allclose(st[n + 2 :], ds["kappa"].values[-1] * L, rtol=1e-12, atol=1e-12)


def test_interrupted_save_leaves_the_old_file(run, tmp_path, monkeypatch):
    p = run.save(tmp_path / "r.nc")
    before = p.read_bytes()

    def boom(path, data):
        with open(path, "wb") as f:
            f.write(bytes(data[:96]))  # a truncated start, then the "crash"
        raise KeyboardInterrupt

    import importlib

    monkeypatch.setattr(importlib.import_module("flutterswim._paths"), "_write_bytes", boom)
    with pytest.raises(KeyboardInterrupt):
        run.save(p)
    assert p.read_bytes() == before
    assert [q.name for q in tmp_path.iterdir()] == ["r.nc"]  # no temporary left behind


def test_dimensionless_run_is_labelled_in_scaled_units(tmp_path):
    r = fs.simulate(fs.PAPER.groups, 0.5, n_segments=8)
    p = r.save(tmp_path / "g.nc")
    with xr.open_dataset(p, engine="h5netcdf") as ds:
        assert ds["x"].attrs["units"] == ds["t"].attrs["units"] == "1"  # CF: "l" is the litre, "tau" unknown
        assert ds["x"].attrs["scaled_units"] == "l" and ds["t"].attrs["scaled_units"] == "tau"
        assert "parameter_l" not in ds.attrs and ds.attrs["group_chi"] == pytest.approx(fs.PAPER.groups.chi)
    back = fs.load(p)
    np.testing.assert_array_equal(back.x, r.x)


def test_output_through_a_link_replaces_its_target_and_keeps_the_link(run, tmp_path):
    """A link to one of our files at --out was replaced by a regular file (its target left
    stale); a link to nothing, or a pipe, at the output path are refused, not replaced."""
    import os

    from flutterswim._paths import check_output_file

    target = tmp_path / "data" / "run.nc"
    target.parent.mkdir()
    run.save(target)
    link = tmp_path / "latest.nc"
    link.symlink_to(target)
    before = target.stat().st_ino
    assert check_output_file(link, (".nc",)) == target.resolve()
    run.save(link)
    assert link.is_symlink() and target.stat().st_ino != before  # the target replaced (atomically)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".latest")]  # no temporary left
    dangling = tmp_path / "gone.nc"
    dangling.symlink_to(tmp_path / "nowhere" / "x.nc")
    with pytest.raises(fs.ParameterError, match="symbolic link.*does not exist"):
        check_output_file(dangling, (".nc",))
    fifo = tmp_path / "pipe.nc"
    os.mkfifo(fifo)
    with pytest.raises(fs.ParameterError, match="not a regular file"):
        check_output_file(fifo, (".nc",))


def test_output_link_named_by_its_format_may_point_to_any_name(tmp_path):
    """The name given decides the format: a link a.nc to a blob without a suffix (a
    content-addressed store) is not refused for its target's suffix; an empty target is written."""
    from flutterswim._paths import check_output_file

    blob = tmp_path / "b" / "blob"
    blob.parent.mkdir()
    blob.write_bytes(b"")
    link = tmp_path / "hashed.nc"
    link.symlink_to(blob)
    assert check_output_file(link, (".nc",)) == blob.resolve()
    with pytest.raises(fs.ParameterError, match="suffix"):
        check_output_file(tmp_path / "x.txt", (".nc",))
