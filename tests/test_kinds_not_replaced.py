"""Each command replaces only its own kind of flutterswim file (a review: `branch --out` and
`steer --out` replaced a tracked experiment or a simulation without a word). Refused before
any computation, the file left as it was."""

import numpy as np
import pytest
import xarray as xr

import flutterswim as fs
from flutterswim import __version__
from flutterswim._paths import check_output_file
from flutterswim.cli import main
from flutterswim.orbits.continuation import BRANCH_TITLE
from flutterswim.stability.stability_map import MAP_TITLE
from flutterswim.steering.steer import STEER_TITLE
from flutterswim.tracking.netcdf import TRACK_TITLE


def _ours(path, title):
    xr.Dataset({"v": ("i", np.arange(3.0), {"units": "1", "long_name": "v"})},
               attrs={"title": title, "source": f"flutterswim {__version__}"}).to_netcdf(path, engine="h5netcdf")
    return path


@pytest.fixture()
def files(tmp_path):
    run = fs.simulate(fs.PAPER, 0.02, n_segments=8).save(tmp_path / "run.nc")
    return {"run": run, "track": _ours(tmp_path / "track.nc", TRACK_TITLE),
            "branch": _ours(tmp_path / "branch.nc", f"{BRANCH_TITLE} in chi"),
            "map": _ours(tmp_path / "map.nc", MAP_TITLE), "steer": _ours(tmp_path / "steer.nc", STEER_TITLE)}


@pytest.mark.parametrize("command,own", [
    (["branch", "kappa_E_ratio=1.5:2", "--points", "3", "--segments", "12", "--quiet"], "branch"),
    (["steer", "--path", "circle", "--segments", "8", "--quiet"], "steer"),
    (["simulate", "--t-end", "0.02", "--segments", "8", "--quiet"], "run"),
])
def test_a_command_refuses_another_kind(files, command, own, capsys):
    for kind, path in files.items():
        if kind == own:
            continue
        before = path.read_bytes()
        assert main(command + ["--out", str(path)]) == 2, kind
        err = capsys.readouterr().err
        assert "another kind of flutterswim result" in err and err.count("\n") == 1
        assert path.read_bytes() == before


def test_the_api_savers_refuse_another_kind_and_replace_their_own(files):
    from flutterswim.stability.stability_map import stability_map

    smap = stability_map(eta_perp=np.array([50.0, 70.0]), chi=np.array([60.0, 70.0]))
    for kind in ("run", "track", "branch", "steer"):
        with pytest.raises(fs.ParameterError, match="another kind"):
            smap.save(files[kind])
    smap.save(files["map"])  # its own kind
    assert xr.open_dataset(files["map"], engine="h5netcdf").attrs["title"] == MAP_TITLE
    # a branch in another parameter is a branch
    assert check_output_file(files["branch"], (".nc",), kind=BRANCH_TITLE) == files["branch"]


def test_a_steered_run_written_before_its_title_is_still_steers_own(files, tmp_path):
    from flutterswim.result import RUN_TITLE
    from flutterswim.steering.cli import _old_steered

    old = tmp_path / "old_steer.nc"
    xr.Dataset({"v": ("i", np.arange(3.0), {"units": "1", "long_name": "v"})},
               attrs={"title": RUN_TITLE, "source": f"flutterswim {__version__}", "steering_path": "circle"}
               ).to_netcdf(old, engine="h5netcdf")
    assert _old_steered(old) and not _old_steered(files["run"]) and not _old_steered(files["track"])
