"""Kill (SIGKILL) and resume: no finished point recomputed, none lost, same final dataset."""

import collections
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import xarray as xr
import zarr

from flutterswim.sweep import sweep

HELPER = textwrap.dedent('''
    import os, time, math
    def slow_point(task):
        x = task["values"]["chi"]
        with open(os.environ["SWEEP_COUNTER"], "a") as f:
            f.write(f"{x!r}\\n")
        time.sleep(0.15)
        return {"a": math.sin(x), "b": x * x}
    slow_point.variables = ["a", "b"]
''')

RUN = textwrap.dedent('''
    import sys
    from sweep_helper import slow_point
    from flutterswim.sweep import sweep
    sweep({"chi": [float(i) for i in range(12)]}, out=sys.argv[1], backend=sys.argv[2], workers=2,
          point_fn=slow_point, progress=False)
''')


def _counts(path):
    with open(path) as f:
        return collections.Counter(float(line) for line in f if line.strip())


def _run_and_kill(tmp_path, backend):
    (tmp_path / "sweep_helper.py").write_text(HELPER)
    out = tmp_path / "s.zarr"
    counter = tmp_path / "counter.txt"
    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
           "SWEEP_COUNTER": str(counter)}
    proc = subprocess.Popen([sys.executable, "-c", RUN, str(out), backend], env=env, start_new_session=True)
    done_at_kill = None
    t0 = time.time()
    try:
        while time.time() - t0 < 60:
            if (out / "zarr.json").exists():
                try:
                    g = zarr.open_group(str(out), mode="r")
                    if "sweep_spec" in g.attrs:
                        d = np.asarray(g["done"][:]) == 1
                        if d.sum() >= 4:
                            os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its workers
                            proc.wait()
                            done_at_kill = np.asarray(zarr.open_group(str(out), mode="r")["done"][:]) == 1
                            break
                except Exception:
                    pass
            time.sleep(0.02)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert done_at_kill is not None, "the sweep did not store 4 points in 60 s"
    assert proc.returncode == -signal.SIGKILL
    assert 4 <= done_at_kill.sum() < 12, "killed too late to test resume"
    # resume with the same command
    r = subprocess.run([sys.executable, "-c", RUN, str(out), backend], env=env, timeout=120)
    assert r.returncode == 0
    return out, counter, env, done_at_kill


def _check(tmp_path, backend):
    out, counter, env, done_at_kill = _run_and_kill(tmp_path, backend)
    counts = _counts(counter)
    for i in range(12):
        if done_at_kill[i]:
            assert counts[float(i)] == 1, f"finished point {i} was recomputed ({counts[float(i)]} runs)"
        else:
            assert counts[float(i)] >= 1
    # uninterrupted run for comparison
    sys.path.insert(0, str(tmp_path))
    try:
        from sweep_helper import slow_point
        os.environ["SWEEP_COUNTER"] = str(tmp_path / "counter2.txt")
        ref = sweep({"chi": [float(i) for i in range(12)]}, out=str(tmp_path / "ref.zarr"), backend="serial",
                    point_fn=slow_point, progress=False)
    finally:
        sys.path.remove(str(tmp_path))
        sys.modules.pop("sweep_helper", None)
        os.environ.pop("SWEEP_COUNTER", None)
    from flutterswim.sweep import open_sweep

    got = open_sweep(str(out))
    assert got["done"].all()
    xr.testing.assert_identical(got.drop_vars("wall_time_s").load(), ref.drop_vars("wall_time_s").load())


def test_kill_and_resume_serial(tmp_path):
    _check(tmp_path, "serial")


def test_kill_and_resume_processes(tmp_path):
    _check(tmp_path, "processes")
