"""The README's Python block runs unchanged in structure (only sizes made small), saved as a
script without a __main__ guard and piped into ``python -``: the sweep's workers must not
re-run it, and every output opens in the standard tools."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

README = Path(__file__).resolve().parents[1] / "README.md"

SMALL = {
    "fs.simulate(p, 10.0)": "fs.simulate(p, 1.0, n_segments=12)",
    "run_to_limit_cycle(p, n_cycles=15)": "run_to_limit_cycle(p, n_cycles=2, n_segments=12)",
    "fs.simulate(p, 30.0, field=turn)": "fs.simulate(p, 1.0, field=turn, n_segments=12)",
    "fs.stability_map()": "fs.stability_map(step=10.0)",
    'out="sweep.zarr")': 'out="sweep.zarr", workers=2,\n'
                         '                  settings={"n_segments": 8, "t_cap": 2.0, "chunk": 1.0, "n_cycles": 1})',
}


def _block() -> str:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "README has no python block"
    code = blocks[0]
    for big, small in SMALL.items():
        assert big in code, f"README block changed: {big!r} not found (update SMALL)"
        code = code.replace(big, small)
    assert "__main__" not in code  # the point: no guard
    return code


def _check_outputs(d: Path, stdout: str) -> None:
    # the first print ran once: workers did not re-execute the script
    assert stdout.count("eta_par=") == 1, stdout
    import flutterswim as fs
    from flutterswim.stability import load_map

    run = fs.load(d / "run.nc")
    assert run.t[-1] == pytest.approx(1.0)
    m = load_map(d / "map.nc")
    assert m.omega.shape == (36, 27) and np.isfinite(m.omega[1:]).all()
    with xr.open_dataset(d / "map.nc", engine="h5netcdf") as ds:
        assert ds["re_omega"].encoding["dtype"] == np.float32 and ds["re_omega"].attrs["scaled_units"] == "1/tau"
    ds = xr.open_zarr(str(d / "sweep.zarr"))
    assert list(ds["period_s"].dims) == ["kappa_E_ratio"]
    assert ds["done"].values.all()


@pytest.mark.parametrize("how", ["file", pytest.param("stdin", marks=pytest.mark.slow)])
def test_readme_python_block_runs(tmp_path, how):
    code = _block()
    if how == "file":
        script = tmp_path / "readme_example.py"
        script.write_text(code)
        r = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    else:
        r = subprocess.run([sys.executable, "-"], input=code, cwd=tmp_path, capture_output=True, text=True,
                           timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    _check_outputs(tmp_path, r.stdout)
