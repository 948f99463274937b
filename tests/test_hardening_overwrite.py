"""An existing file is overwritten only if flutterswim wrote it (it carries our signature):
runs, figures, animations and the stability outputs; our own files are replaced freely."""

import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import flutterswim as fs
from flutterswim._paths import is_ours


@pytest.fixture(scope="module")
def run():
    return fs.simulate(fs.PAPER, 0.3, n_segments=8)


def test_foreign_netcdf_is_never_overwritten(run, tmp_path):
    data = tmp_path / "data.nc"
    xr.Dataset({"temperature": ("x", np.arange(3.0))}).to_netcdf(data, engine="h5netcdf")
    before = data.read_bytes()
    with pytest.raises(fs.ParameterError, match="not written by flutterswim"):
        run.save(data)
    r = subprocess.run([sys.executable, "-m", "flutterswim", "simulate", "--t-end", "1000", "--out", str(data),
                        "--quiet"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "not written by flutterswim" in r.stderr
    assert data.read_bytes() == before


def test_own_files_are_replaced(run, tmp_path):
    p = run.save(tmp_path / "run.nc")
    assert is_ours(p)
    run.save(p)  # again: ours, replaced
    assert fs.load(p).t.size == run.t.size


@pytest.mark.parametrize("suffix", [".png", ".pdf", ".svg"])
def test_foreign_figure_is_refused_own_figure_replaced(run, tmp_path, suffix):
    from flutterswim.plotting import plot_swimmer

    mine = tmp_path / f"mine{suffix}"
    plot_swimmer(run, mine)
    assert is_ours(mine)
    plot_swimmer(run, mine)
    photo = tmp_path / f"photo{suffix}"
    photo.write_bytes(b"user bytes" * 100)
    with pytest.raises(fs.ParameterError, match="not written by flutterswim"):
        plot_swimmer(run, photo)
    assert photo.read_bytes() == b"user bytes" * 100


def test_gif_carries_the_signature_and_stays_readable(run, tmp_path):
    from flutterswim.plotting import animate

    g = animate(run, tmp_path / "a.gif", fps=20, max_frames=5, size=(128, 96))
    assert is_ours(g)
    import imageio.v3 as iio

    frames = iio.imread(g, index=None)
    assert frames.shape[0] == 5
    animate(run, g, fps=20, max_frames=4, size=(128, 96))  # ours: replaced
    assert iio.imread(g, index=None).shape[0] == 4


def test_stability_outputs_checked_before_computing(tmp_path):
    (tmp_path / "eigenmodes.png").write_bytes(b"someone else's figure")
    from flutterswim.stability import stability_figures

    with pytest.raises(fs.ParameterError, match="eigenmodes.png"):
        stability_figures(tmp_path, step=1e-6)  # a huge grid: the check must come first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["eigenmodes.png"]


def test_a_sweep_never_replaces_a_reproduce_folder_nor_reproduce_a_sweep_store(tmp_path):
    """Both carry the store marker, with their kind: ``sweep --overwrite`` deleted a reproduce
    folder (report, manifest, figures) and ``reproduce`` wrote into a sweep's Zarr store and
    relabelled its marker. Each now refuses the other's folder and leaves it as it was."""
    from flutterswim.reproduce import reproduce

    rep = tmp_path / "repro"
    reproduce(rep, targets=["table1"])
    before = sorted(p.name for p in rep.iterdir())
    with pytest.raises(fs.ParameterError, match="reproduce"):
        fs.run_sweep({"kappa_E_ratio": [1.0]}, "paper", out=rep, backend="serial", overwrite=True, progress=False)
    assert sorted(p.name for p in rep.iterdir()) == before

    store = tmp_path / "s.zarr"
    fs.run_sweep({"kappa_E_ratio": [0.5]}, "paper", out=store, backend="serial", progress=False)
    before = sorted(p.name for p in store.iterdir())
    marker = (store / ".flutterswim-store").read_text()
    with pytest.raises(fs.ParameterError, match="sweep"):
        reproduce(store, targets=["table1"])
    assert sorted(p.name for p in store.iterdir()) == before
    assert (store / ".flutterswim-store").read_text() == marker


@pytest.mark.parametrize("suffix", [".nc", ".png", ".pdf", ".svg", ".jpg", ".gif", ".mp4", ".json", ".csv", ".html"])
def test_a_file_that_only_mentions_flutterswim_is_not_ours(tmp_path, suffix):
    """The signature must sit in the format's own metadata: a user's notes, data or figure
    that merely contain the word (as text, as a JSON value, in a CSV cell) were taken for ours
    and replaced by ``simulate --out`` and ``track-batch --out``."""
    f = tmp_path / f"notes{suffix}"
    text = {".json": '{"note": "flutterswim 0.1.0 made the data"}',
            ".csv": "voltage_V,sample,notes\n85,1,compare with flutterswim 0.1.0 later\n"}
    f.write_text(text.get(suffix, "my notes about flutterswim 0.1.0, precious\n" * 3))
    assert not is_ours(f)


def test_simulate_refuses_a_netcdf_path_holding_a_users_notes(tmp_path):
    notes = tmp_path / "notes.nc"
    notes.write_text("my flutterswim notes, precious")
    r = subprocess.run([sys.executable, "-m", "flutterswim", "simulate", "--t-end", "0.1", "--segments", "8",
                        "--out", str(notes), "--quiet"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "not written by flutterswim" in r.stderr, r.stderr
    assert notes.read_text() == "my flutterswim notes, precious"


def test_own_jpeg_json_and_csv_are_recognised(run, tmp_path):
    from flutterswim.plotting import plot_swimmer

    plot_swimmer(run, tmp_path / "f.jpg")
    assert is_ours(tmp_path / "f.jpg")
    (tmp_path / "d.json").write_text('{"generator": "flutterswim 0.1.0", "period_s": 0.4}')
    assert is_ours(tmp_path / "d.json")
    # a failures file of an earlier version (signed without a hash): ours
    (tmp_path / "t.csv").write_text("trial,reason,tracked_by\na.tif,no stroke,flutterswim 0.1.0\n")
    assert is_ours(tmp_path / "t.csv")


def test_a_batch_csv_of_only_its_header_is_ours_a_users_header_is_not(tmp_path):
    """A batch whose trials all failed writes only the header: a rerun must be able to replace it."""
    from flutterswim.tracking.batch import CSV_COLUMNS

    (tmp_path / "t.csv").write_text(",".join(CSV_COLUMNS) + "\n")
    assert is_ours(tmp_path / "t.csv")
    (tmp_path / "u.csv").write_text("voltage_V,sample,tracked_by\n")
    assert not is_ours(tmp_path / "u.csv")
