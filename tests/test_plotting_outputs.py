"""Every figure and animation function writes a non-trivial file of the expected size."""

import time

import numpy as np
import pytest

from flutterswim._validate import ParameterError
from flutterswim.analysis.synthetic import wave_track
from flutterswim.plotting import animate, figures

mpimg = pytest.importorskip("matplotlib.image")


@pytest.fixture(scope="module")
def track():
    # a small paper-sized swimmer growing into a travelling-wave stroke
    return wave_track(envelope=(1e-3, 3.0), duration=4.0, n_frames=401, length=3.7e-3, amplitude=0.3e-3,
                      wavelength=3e-3, speed=0.5e-3, n_points=31)


FIGS = [
    ("plot_ghosts", {}),
    ("plot_swimmer", {"time": 1.0}),
    ("plot_descriptors", {}),
    ("plot_kymographs", {"window": (2.0, 3.5)}),
    ("plot_summary", {}),
]


@pytest.mark.parametrize("name,kw", FIGS)
def test_figure_png_size(track, tmp_path, name, kw):
    func = getattr(figures, name)
    p = func(track, tmp_path / f"{name}.png", figsize=(8.0, 6.0), dpi=30, **kw)
    assert p.exists() and p.stat().st_size > 3_000
    img = mpimg.imread(p)
    assert img.shape[:2] == (180, 240)
    # not blank: several distinct colours
    assert np.unique(img.reshape(-1, img.shape[-1]), axis=0).shape[0] > 10


def test_figure_pdf_and_bad_suffix(track, tmp_path):
    p = figures.plot_ghosts(track, tmp_path / "g.pdf", figsize=(3, 2), dpi=50)
    assert p.read_bytes()[:4] == b"%PDF" and p.stat().st_size > 2_000
    with pytest.raises(ParameterError, match="suffix"):
        figures.plot_ghosts(track, tmp_path / "g.txt")
    with pytest.raises(ParameterError, match="cycle"):
        figures.plot_ghosts(track, cycle=999)


def test_figure_returned_without_path(track):
    fig = figures.plot_swimmer(track)
    assert fig.axes and fig.axes[0].get_xlabel() == "x (mm)"


def test_animation_mp4_and_gif(track, tmp_path):
    iio = pytest.importorskip("imageio.v2")
    pytest.importorskip("imageio_ffmpeg")
    p = animate(track, tmp_path / "a.mp4", fps=10, size=(161, 120))
    assert p.stat().st_size > 5_000
    r = iio.get_reader(str(p))
    frame = r.get_data(5)
    r.close()
    assert frame.shape == (120, 162, 3)  # width made even for yuv420p
    g = animate(track, tmp_path / "a.gif", fps=5, size=(160, 96))
    frames = iio.mimread(str(g))
    assert len(frames) == 21  # 4 s at 5 fps, both ends included
    assert frames[0].shape[:2] == (96, 160)
    with pytest.raises(ParameterError, match="suffix"):
        animate(track, tmp_path / "a.avi")


def test_animation_500_frames_fast(tmp_path):
    """A 10 s run, 500 video frames of 640x360: well under 30 s."""
    pytest.importorskip("imageio_ffmpeg")
    tr = wave_track(duration=10.0, n_frames=1001, n_points=101, length=3.7e-3, amplitude=0.3e-3,
                    wavelength=3e-3, speed=0.5e-3)
    t0 = time.perf_counter()
    p = animate(tr, tmp_path / "long.mp4", fps=50)
    wall = time.perf_counter() - t0
    assert p.stat().st_size > 50_000
    assert wall < 30.0, f"500 frames took {wall:.1f} s"
