"""Everything flutterswim writes as JSON is strict JSON: NaN (a value not measured) is null.

Python's json writes NaN as a bare token that strict readers (jq, browsers, JSON.parse)
reject, taking the whole document with it."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

import flutterswim as fs
from flutterswim._json import dumps


def _strict(text):
    def refuse(token):
        raise ValueError(f"non-JSON token {token}")

    return json.loads(text, parse_constant=refuse)


def test_dumps_is_strict_and_plain():
    obj = {"a": np.float32("nan"), "b": [np.inf, 1.5, -np.inf], "c": np.arange(3), 4: np.bool_(True),
           "d": (np.int64(7), 1 + 2j)}
    with pytest.raises(ValueError):
        _strict(json.dumps({"a": float("nan")}))  # the parser can tell
    assert _strict(dumps(obj)) == {"a": None, "b": [None, 1.5, None], "c": [0, 1, 2], "4": True,
                                   "d": [7, {"real": 1.0, "imag": 2.0}]}


def test_a_saved_run_keeps_strict_json_attributes(tmp_path):
    import xarray as xr

    run = fs.simulate(fs.PAPER.groups, 0.2, n_segments=8)
    run = replace(run, settings={**run.settings, "step_error": float("nan"), "growth_rate_measured": np.nan})
    path = run.save(tmp_path / "run.nc")
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        for key in ("settings", "stats", "groups", "params"):
            _strict(ds.attrs[key])
        assert _strict(ds.attrs["settings"])["step_error"] is None
    assert fs.load(path).settings["growth_rate_measured"] is None
