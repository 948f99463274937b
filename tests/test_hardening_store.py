"""Sweep stores: nothing that is not provably ours is replaced, own damaged stores are not
silently recomputed, and the store is an ordinary xarray Zarr dataset."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import flutterswim as fs
from flutterswim._validate import ParameterError
from flutterswim.sweep import SweepStoreError, sweep
from flutterswim.sweep.store import SweepStore

CALLS = []


def point(task):
    CALLS.append(dict(task["values"]))
    v = task["values"]
    return {"a": math.sin(v["chi"]) + v.get("tau", 0.0), "b": v["chi"] ** 2}


point.variables = ["a", "b"]


def _user_files(d):
    d.mkdir(exist_ok=True)
    (d / "notes.txt").write_text("my notes")
    (d / "data.csv").write_text("1,2,3\n")
    (d / "sub").mkdir(exist_ok=True)
    (d / "sub" / "run.nc").write_bytes(b"x" * 100)
    return {p.relative_to(d): p.read_bytes() for p in d.rglob("*") if p.is_file()}


def _same(d, before):
    after = {p.relative_to(d): p.read_bytes() for p in d.rglob("*") if p.is_file()}
    return after == before


def test_overwrite_refuses_a_directory_of_user_files(tmp_path):
    d = tmp_path / "mine"
    before = _user_files(d)
    with pytest.raises(fs.ParameterError, match="not a flutterswim store"):
        sweep({"chi": [1.0, 2.0]}, out=str(d), overwrite=True, backend="serial", point_fn=point, progress=False)
    with pytest.raises(fs.ParameterError, match="not a flutterswim store"):
        sweep({"chi": [1.0, 2.0]}, out=str(d), backend="serial", point_fn=point, progress=False)
    assert _same(d, before)


def test_cli_overwrite_of_the_current_directory_keeps_every_file(tmp_path):
    d = tmp_path / "work"
    before = _user_files(d)
    for out in (".", str(d), ".."):
        r = subprocess.run([sys.executable, "-m", "flutterswim", "sweep", "chi=60,70", "--out", out, "--overwrite",
                            "--backend", "serial", "--no-progress"], cwd=d, capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
        assert "current directory" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert _same(d, before)


def test_a_file_is_refused(tmp_path):
    f = tmp_path / "sweep.zarr"
    f.write_text("not a store")
    with pytest.raises(fs.ParameterError, match="existing file"):
        sweep({"chi": [1.0]}, out=str(f), overwrite=True, backend="serial", point_fn=point, progress=False)
    assert f.read_text() == "not a store"


def test_zarr_store_of_another_tool_is_refused_not_replaced(tmp_path):
    other = tmp_path / "other.zarr"
    xr.Dataset({"temperature": ("x", np.arange(4.0))}).to_zarr(str(other))
    before = {p.relative_to(other): p.read_bytes() for p in other.rglob("*") if p.is_file()}
    for overwrite in (False, True):
        with pytest.raises(fs.ParameterError, match="Zarr store written by another tool"):
            sweep({"chi": [1.0]}, out=str(other), overwrite=overwrite, backend="serial", point_fn=point,
                  progress=False)
    assert _same(other, before)
    np.testing.assert_array_equal(xr.open_zarr(str(other))["temperature"].values, np.arange(4.0))


def test_own_incomplete_store_is_not_recomputed_silently(tmp_path):
    out = tmp_path / "s.zarr"
    sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    import zarr

    g = zarr.open_group(str(out), mode="r+")
    attrs = dict(g.attrs)
    del attrs["fingerprint"]
    g.attrs.clear()
    g.attrs.update(attrs)
    zarr.consolidate_metadata(str(out))
    CALLS.clear()
    with pytest.raises(SweepStoreError, match="incomplete.*fingerprint.*overwrite"):
        sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    assert CALLS == []
    # a missing variable
    out2 = tmp_path / "t.zarr"
    sweep({"chi": [1.0, 2.0]}, out=str(out2), backend="serial", point_fn=point, progress=False)
    import shutil

    shutil.rmtree(out2 / "b")
    CALLS.clear()
    with pytest.raises(SweepStoreError, match="variable"):
        sweep({"chi": [1.0, 2.0]}, out=str(out2), backend="serial", point_fn=point, progress=False)
    assert CALLS == []
    # the user asks for it: replaced
    ds = sweep({"chi": [1.0, 2.0]}, out=str(out2), overwrite=True, backend="serial", point_fn=point, progress=False)
    assert ds["done"].all() and len(CALLS) == 2


def test_overwrite_replaces_own_store_and_resume_recomputes_nothing(tmp_path):
    out = tmp_path / "s.zarr"
    sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    CALLS.clear()
    sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    assert CALLS == []
    sweep({"chi": [1.0, 2.0, 3.0]}, out=str(out), overwrite=True, backend="serial", point_fn=point, progress=False)
    assert len(CALLS) == 3


def test_xarray_reads_the_store_without_flutterswim(tmp_path):
    out = tmp_path / "g.zarr"
    chi, tau = [1.0, 2.0, 3.0], [0.1, 0.4]
    sweep({"chi": chi, "tau": tau}, base=fs.PAPER, out=str(out), backend="serial", point_fn=point,
          progress=False)
    code = (
        "import sys, xarray as xr, json\n"
        "ds = xr.open_zarr(sys.argv[1])\n"
        # and on to NetCDF (a nested attribute had made to_netcdf fail)
        "ds.to_netcdf(sys.argv[1] + '.nc', engine='h5netcdf')\n"
        "assert xr.open_dataset(sys.argv[1] + '.nc', engine='h5netcdf').a.shape == ds.a.shape\n"
        "print(json.dumps({'dims': dict(ds.sizes), 'chi': ds.chi.values.tolist(), 'tau': ds.tau.values.tolist(),"
        " 'a': ds.a.values.tolist(), 'a_dims': list(ds.a.dims), 'reason': [str(r) for r in ds.reason.values.ravel()],"
        " 'attrs': {k: ds[k].attrs for k in list(ds.variables)}, 'spec': ds.attrs['sweep_spec']}))\n"
    )
    # a fresh interpreter that never imports flutterswim
    r = subprocess.run([sys.executable, "-c", code, str(out)], capture_output=True, text=True, timeout=120,
                       env={"PATH": "/usr/bin:/bin"})
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    assert got["a_dims"] == ["chi", "tau"] and got["dims"]["chi"] == 3 and got["dims"]["tau"] == 2
    assert got["chi"] == chi and got["tau"] == tau
    expect = [[math.sin(c) + t for t in tau] for c in chi]
    np.testing.assert_allclose(got["a"], expect, rtol=0, atol=1e-15)
    assert got["reason"] == [""] * 6
    for name, attrs in got["attrs"].items():
        assert "units" in attrs and "long_name" in attrs, name
    assert got["attrs"]["tau"]["units"] == "s" and got["attrs"]["wall_time_s"]["units"] == "s"
    assert json.loads(got["spec"])["axes"][0]["name"] == "chi"


def test_real_sweep_variables_have_units_and_failure_reasons_are_strings(tmp_path):
    out = tmp_path / "r.zarr"
    kw = dict(base=fs.PAPER.replace(kappa_E=0.0), out=str(out), backend="serial", progress=False,
              settings={"n_segments": 8, "t_cap": 2.0, "chunk": 1.0, "n_cycles": 1})
    # a bad axis value is refused before the store is created (the checks a point makes)
    with pytest.raises(ParameterError, match="tau=-1.0"):
        sweep({"tau": [0.375, -1.0]}, **kw)
    assert not out.exists()
    sweep({"tau": [0.375, 0.5]}, **kw)
    ds = xr.open_zarr(str(out))
    assert list(ds["period_s"].dims) == ["tau"]
    for name in ds.variables:
        assert ds[name].attrs.get("units") is not None and ds[name].attrs.get("long_name"), name
    assert ds["period_s"].attrs["units"] == "s" and ds["frequency_hz"].attrs["units"] == "Hz"
    reasons = [str(r) for r in ds["reason"].values]  # strings: what each point settled into
    assert all(isinstance(r, str) and "straight" in r for r in reasons) and not ds["failed"].values.any(), reasons


def test_continuation_store_has_a_branch_dimension(tmp_path):
    out = tmp_path / "c.zarr"
    sweep({"chi": [1.0, 2.0, 3.0]}, out=str(out), continuation=True, backend="serial", point_fn=point,
          progress=False)
    ds = xr.open_zarr(str(out))
    assert list(ds["a"].dims) == ["branch", "chi"] and list(ds["branch"].values) == ["up", "down"]
    np.testing.assert_allclose(ds["b"].values, [[1.0, 4.0, 9.0]] * 2)


def test_done_is_written_last(tmp_path):
    """A point whose ``done`` write did not happen counts as not computed (resume redoes it)."""
    out = tmp_path / "d.zarr"
    spec = fs.sweep.SweepSpec.build({"chi": [1.0, 2.0]})
    st = SweepStore.open(out, spec, ["a", "b"], 3)
    try:
        st.write_point(0, {"a": 1.0, "b": 2.0}, failed=False, message="", wall_time=0.1, done=False)
        assert not st.done_mask().any()
        st.write_point(1, {"a": 1.0, "b": 2.0}, failed=False, message="", wall_time=0.1)
        np.testing.assert_array_equal(st.done_mask(), [False, True])
    finally:
        st.close()


def _tree(d):
    return {str(p.relative_to(d)): (p.read_bytes() if p.is_file() else None) for p in sorted(d.rglob("*"))}


@pytest.mark.parametrize("continuation", [False, True])
def test_overwrite_refuses_an_own_store_holding_user_files(tmp_path, continuation):
    """--overwrite deleted the whole store folder once the marker was there, with the notes and
    figures the user had put into it; now it is refused, and nothing is touched."""
    out = tmp_path / "s.zarr"
    sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=point, progress=False,
          continuation=continuation)
    from flutterswim.sweep.store import foreign_entries

    assert foreign_entries(out) == []  # everything a finished store holds is its own
    (out / "NOTES.txt").write_text("my notes")
    (out / "myfigs").mkdir()
    (out / "myfigs" / "f.png").write_bytes(b"png")
    (out / "a" / "mine.txt").write_text("inside an array folder")
    before = _tree(out)
    CALLS.clear()
    with pytest.raises(fs.ParameterError, match=r"NOTES\.txt.*never deletes"):
        sweep({"chi": [1.0, 2.0, 3.0]}, out=str(out), overwrite=True, backend="serial", point_fn=point,
              progress=False, continuation=continuation)
    assert CALLS == [] and _tree(out) == before
    assert foreign_entries(out) == ["NOTES.txt", "a/mine.txt", "myfigs"]
    # without the user's files the store is replaced as before
    for f in ("NOTES.txt", "myfigs/f.png", "a/mine.txt"):
        (out / f).unlink()
    (out / "myfigs").rmdir()
    ds = sweep({"chi": [1.0, 2.0, 3.0]}, out=str(out), overwrite=True, backend="serial", point_fn=point,
               progress=False, continuation=continuation)
    assert ds["done"].all() and ds.sizes["chi"] == 3


def test_a_store_left_by_a_killed_write_is_still_ours(tmp_path):
    """zarr writes each file under a temporary '<name>.<hex>.partial' name: a leftover is the store's own."""
    out = tmp_path / "s.zarr"
    sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    (out / "a" / "c" / ("0." + "ab" * 16 + ".partial")).write_bytes(b"half")
    from flutterswim.sweep.store import foreign_entries

    assert foreign_entries(out) == []
    (out / "a" / "c" / "notes.txt").write_text("mine")
    assert foreign_entries(out) == ["a/c/notes.txt"]


def test_cli_overwrite_of_an_own_store_with_user_files_exits_2_and_keeps_them(tmp_path):
    out = tmp_path / "s.zarr"
    sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    (out / "NOTES.txt").write_text("my notes")
    before = _tree(out)
    r = subprocess.run([sys.executable, "-m", "flutterswim", "sweep", "chi=60,70", "--out", str(out), "--overwrite",
                        "--backend", "serial", "--no-progress"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "--out=" in lines[0] and "NOTES.txt" in lines[0]
    assert _tree(out) == before


def test_a_link_to_an_own_store_is_never_replaced_through(tmp_path):
    """--overwrite through a symbolic link renamed the user's link and then failed in rmtree."""
    target = tmp_path / "t.zarr"
    sweep({"chi": [1.0, 2.0]}, out=str(target), backend="serial", point_fn=point, progress=False)
    link = tmp_path / "l.zarr"
    link.symlink_to(target.name)
    before = _tree(target)
    with pytest.raises(fs.ParameterError, match="symbolic link"):
        sweep({"chi": [1.0, 2.0, 3.0]}, out=str(link), overwrite=True, backend="serial", point_fn=point,
              progress=False)
    assert link.is_symlink() and link.resolve() == target.resolve() and _tree(target) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["l.zarr", "t.zarr"]  # nothing renamed, no remnant
    # a dangling link is not replaced by a new store either
    dangling = tmp_path / "d.zarr"
    dangling.symlink_to("nowhere.zarr")
    with pytest.raises(fs.ParameterError, match="symbolic link"):
        sweep({"chi": [1.0]}, out=str(dangling), backend="serial", point_fn=point, progress=False)
    assert dangling.is_symlink() and not (tmp_path / "nowhere.zarr").exists()
    # resuming through a link to an own store still works
    CALLS.clear()
    sweep({"chi": [1.0, 2.0]}, out=str(link), backend="serial", point_fn=point, progress=False)
    assert CALLS == []


def test_an_unreachable_scheduler_leaves_no_store_behind(tmp_path, monkeypatch):
    """'sweep ... --scheduler tcp://127.0.0.1:1' said no scheduler answered (exit 2) but left the
    empty store it had created; a store that existed before is kept."""
    pytest.importorskip("distributed")
    from flutterswim import defaults
    from flutterswim.sweep.backends import SchedulerUnreachable

    monkeypatch.setattr(defaults, "SCHEDULER_TIMEOUT_S", 1.0)
    out = tmp_path / "s.zarr"
    with pytest.raises(SchedulerUnreachable, match="no Dask scheduler"):
        sweep({"chi": [1.0, 2.0]}, out=str(out), backend="dask", scheduler="tcp://127.0.0.1:1", point_fn=point,
              progress=False)
    assert list(tmp_path.iterdir()) == []  # no store, no lock file, no remnant
    # an existing store (points saved) is resumed, so it stays as it was
    sweep({"chi": [1.0, 2.0, 3.0]}, out=str(out), backend="serial", point_fn=point, progress=False, max_points=1)
    before = _tree(out)
    with pytest.raises(SchedulerUnreachable):
        sweep({"chi": [1.0, 2.0, 3.0]}, out=str(out), backend="dask", scheduler="tcp://127.0.0.1:1",
              point_fn=point, progress=False)
    assert _tree(out) == before
    # overwrite=True with a mistyped address had deleted the store and left nothing: the store is
    # set aside, and put back when the new run does not start
    for to in ({"chi": [1.0, 2.0, 3.0]}, {"chi": [5.0, 6.0]}):
        with pytest.raises(SchedulerUnreachable):
            sweep(to, out=str(out), backend="dask", scheduler="tcp://127.0.0.1:1", point_fn=point, progress=False,
                  overwrite=True)
        assert _tree(out) == before
        assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]  # no remnant, no lock
    # a run that does start replaces it, and leaves no remnant of the old one
    ds = sweep({"chi": [5.0, 6.0]}, out=str(out), backend="serial", point_fn=point, progress=False, overwrite=True)
    assert list(ds["chi"].values) == [5.0, 6.0] and bool(ds["done"].all())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]


def test_a_killed_sweeps_lock_file_is_removed_by_the_next_run(tmp_path):
    """A review: after a SIGKILL the lock file (.s.zarr.lock) stayed in the user's folder for
    good, even after the resumed sweep finished. Ours are signed; a file we did not write is
    left alone."""
    from flutterswim.sweep.store import _LOCK_SIGNATURE

    out = tmp_path / "s.zarr"
    sweep({"chi": [1.0, 2.0, 3.0]}, out=str(out), backend="serial", point_fn=point, progress=False, max_points=1)
    lock = tmp_path / ".s.zarr.lock"
    assert not lock.exists()  # a run that ends removes its own
    lock.write_text(_LOCK_SIGNATURE)  # as a killed run leaves it
    sweep({"chi": [1.0, 2.0, 3.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    assert not lock.exists()
    lock.write_text("the user's own notes\n")  # not ours: kept as it is
    sweep({"chi": [1.0, 2.0, 3.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    assert lock.read_text() == "the user's own notes\n"


@pytest.mark.parametrize("server", ["silent", "http"])
def test_a_port_that_is_no_dask_scheduler_is_refused_in_time(server, monkeypatch):
    """An HTTP server or a socket that accepts and never answers on the scheduler's port hung the
    sweep for minutes (the promise: an error within SCHEDULER_TIMEOUT_S naming the address); one
    answering garbage failed as 'out of memory'. A real scheduler still passes the same check."""
    import http.server
    import socket
    import threading
    import time

    from flutterswim.sweep import backends
    from flutterswim.sweep.backends import SchedulerUnreachable

    if server == "silent":
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        s.listen(5)
        port = s.getsockname()[1]
    else:
        srv = http.server.HTTPServer(("127.0.0.1", 0), http.server.BaseHTTPRequestHandler)
        threading.Thread(target=srv.serve_forever, daemon=True).start()
        port = srv.server_address[1]
    t0 = time.perf_counter()
    with pytest.raises(SchedulerUnreachable, match=rf"tcp://127.0.0.1:{port}.*did not answer as a Dask scheduler"):
        backends._reachable(f"tcp://127.0.0.1:{port}", 2.0)
    assert time.perf_counter() - t0 < 6.0
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        backends._reachable(cluster.scheduler_address, 5.0)  # no error


def test_a_store_is_locked_through_a_symbolic_link_too(tmp_path):
    """The lock file was named after the path as given: a run through a link to a store took
    another lock, and two processes wrote one store at once. The lock is the store's own."""
    from flutterswim.sweep.store import SweepLockedError, _acquire

    real = tmp_path / "c.zarr"
    sweep({"chi": [1.0, 2.0]}, out=str(real), backend="serial", point_fn=point, progress=False, max_points=1)
    link = tmp_path / "link.zarr"
    link.symlink_to(real)
    held = _acquire(real)
    try:
        with pytest.raises(SweepLockedError):
            _acquire(link)
        with pytest.raises(SweepLockedError):
            sweep({"chi": [1.0, 2.0]}, out=str(link), backend="serial", point_fn=point, progress=False)
    finally:
        held.close()
    sweep({"chi": [1.0, 2.0]}, out=str(link), backend="serial", point_fn=point, progress=False)  # resumed through it
    assert not (tmp_path / ".link.zarr.lock").exists() and not (tmp_path / ".c.zarr.lock").exists()


def _interrupting(task):
    raise KeyboardInterrupt


_interrupting.variables = ["a"]


def test_an_interrupt_before_any_point_says_nothing_was_saved(tmp_path):
    """Interrupted before a point finished, a sweep removes the empty store it created, but
    said "0 of 2 points are saved in 's.zarr'; rerun the same command to resume"."""
    from flutterswim.sweep import SweepInterrupted

    out = tmp_path / "s.zarr"
    with pytest.raises(SweepInterrupted, match="before any point was saved: nothing was written$"):
        sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=_interrupting, progress=False)
    assert list(tmp_path.iterdir()) == []
    sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    with pytest.raises(SweepInterrupted, match="the store that was there is kept"):
        sweep({"chi": [3.0]}, out=str(out), backend="serial", point_fn=_interrupting, progress=False, overwrite=True)
    assert list(open_sweep_chi(out)) == [1.0, 2.0]


def open_sweep_chi(out):
    from flutterswim.sweep import open_sweep

    return open_sweep(str(out))["chi"].values


def _twice(task):
    return {"a": 2.0 * task["values"]["chi"]}


_twice.variables = ["a"]


def _once(task):
    return {"a": task["values"]["chi"]}


_once.variables = ["a"]


def test_a_store_is_not_resumed_by_other_code(tmp_path):
    """A resume with another point function (or another flutterswim version) mixed the points of
    both in one store without a word (v = 10, 20, 30, 80, 100, 120). It is refused, naming what
    differs; the same code resumes; a store that records no code (made before) resumes."""
    import zarr

    from flutterswim.sweep import SweepDefinitionError

    out = str(tmp_path / "s.zarr")
    axes = {"chi": [1.0, 2.0, 3.0, 4.0]}
    sweep(axes, out=out, backend="serial", point_fn=_once, progress=False, max_points=2)
    with pytest.raises(SweepDefinitionError, match="point function: stored 'test_hardening_store:_once'"):
        sweep(axes, out=out, backend="serial", point_fn=_twice, progress=False)
    g = zarr.open_group(out, mode="r+")
    code = json.loads(g.attrs["code"])
    g.attrs["code"] = json.dumps({**code, "flutterswim": "0.0.1"})
    with pytest.raises(SweepDefinitionError, match="flutterswim version: stored '0.0.1'"):
        sweep(axes, out=out, backend="serial", point_fn=_once, progress=False)
    g.attrs["code"] = json.dumps({**code, "package_source": "0123456789abcdef"})
    with pytest.warns(UserWarning, match="other sources"):
        sweep(axes, out=out, backend="serial", point_fn=_once, progress=False, max_points=1)
    del g.attrs["code"]
    ds = sweep(axes, out=out, backend="serial", point_fn=_once, progress=False)
    assert list(ds["a"].values) == [1.0, 2.0, 3.0, 4.0]


def test_a_full_disk_says_what_is_saved(tmp_path, monkeypatch):
    """A sweep that filled the disk exited with "[Errno 28] No space left on device" alone; the
    points saved and the resume are now said (the error is still an OSError with its errno)."""
    import importlib

    st = importlib.import_module("flutterswim.sweep.store")
    real = st.SweepStore.write_point
    n = []

    def write(self, k, *a, **kw):
        n.append(k)
        if len(n) == 3:
            raise OSError(28, "No space left on device")
        return real(self, k, *a, **kw)

    monkeypatch.setattr(st.SweepStore, "write_point", write)
    with pytest.raises(OSError, match=r"No space left on device: 2 of 4 points are saved in .*resume") as e:
        sweep({"chi": [1.0, 2.0, 3.0, 4.0]}, out=str(tmp_path / "s.zarr"), backend="serial", point_fn=point,
              progress=False)
    assert e.value.errno == 28


def test_an_overwritten_store_goes_once_the_new_one_holds_a_point(tmp_path):
    """Diff review: the store overwrite set aside stayed until the run ended (twice the disk),
    and one a killed run left stayed hidden for good. It goes with the new store's first point;
    a remnant is put back where no store is, else removed, by the next run."""
    import shutil

    out = tmp_path / "s.zarr"
    sweep({"chi": [1.0, 2.0]}, out=str(out), backend="serial", point_fn=point, progress=False)
    seen = []

    def watching(task):
        seen.append(sorted(p.name for p in tmp_path.iterdir() if "replaced" in p.name))
        return point(task)

    watching.variables = point.variables
    sweep({"chi": [3.0, 4.0, 5.0]}, out=str(out), backend="serial", point_fn=watching, progress=False, overwrite=True)
    assert len(seen[0]) == 1 and seen[1:] == [[], []]  # gone after the first point
    # a remnant a killed run left: put back where no store is; removed beside one
    shutil.copytree(out, tmp_path / ".s.zarr.replaced-99999")
    sweep({"chi": [3.0, 4.0, 5.0]}, out=str(out), backend="serial", point_fn=watching, progress=False)
    assert not (tmp_path / ".s.zarr.replaced-99999").exists()
    shutil.move(str(out), str(tmp_path / ".s.zarr.replaced-99999"))
    ds = sweep({"chi": [3.0, 4.0, 5.0]}, out=str(out), backend="serial", point_fn=watching, progress=False)
    assert bool(ds["done"].all()) and not (tmp_path / ".s.zarr.replaced-99999").exists()


def _scaled(task, scale=1.0):
    return {"a": scale * task["values"]["chi"]}


class _Scaled:
    variables = ["a"]

    def __init__(self, scale):
        self.scale = scale

    def __call__(self, task):
        return {"a": self.scale * task["values"]["chi"]}


def test_partials_and_callable_objects_are_told_apart(tmp_path):
    """Diff review: partial(f, scale=1) then partial(f, scale=2), or two objects of one class,
    passed as the same point function and mixed in one store."""
    import functools

    from flutterswim.sweep import SweepDefinitionError

    axes = {"chi": [1.0, 2.0, 3.0]}
    for k, (a, b) in enumerate(((functools.partial(_scaled, scale=1.0), functools.partial(_scaled, scale=2.0)),
                                (_Scaled(1.0), _Scaled(2.0)))):
        for f in (a, b):
            f.variables = ["a"]
        out = str(tmp_path / f"s{k}.zarr")
        sweep(axes, out=out, backend="serial", point_fn=a, progress=False, max_points=1)
        with pytest.raises(SweepDefinitionError, match="point function's source"):
            sweep(axes, out=out, backend="serial", point_fn=b, progress=False)
        ds = sweep(axes, out=out, backend="serial", point_fn=a, progress=False)  # the same: resumed
        assert list(ds["a"].values) == [1.0, 2.0, 3.0]
