"""Stop 46: items left at stop 45 (bad brackets, reasons in CSV files)."""

import pytest

import flutterswim as fs
from flutterswim._validate import ParameterError
from flutterswim.orbits.linear import hopf_point


@pytest.mark.parametrize("bracket", [(float("nan"), 1.0), (1.0,), "ab", (0.5, 0.5), (0.5, float("inf"))])
def test_a_bad_bracket_names_the_bracket(bracket):
    """(nan, 1) had been reported as kappa_E_ratio=nan, a value the user never gave."""
    with pytest.raises(ParameterError, match=r"^bracket="):
        hopf_point(fs.PAPER, bracket=bracket, n_segments=12)


def test_continuing_across_zero_field_names_the_mirror_branch():
    """From chi = -70.67 towards +100 the branch from -48 cannot get there; the error named only
    that Hopf point, although the mirror branch from +48 holds chi = 100."""
    from flutterswim.orbits.continuation import continue_orbits
    from flutterswim.orbits.linear import hopf_point
    from flutterswim.params import Groups

    g = Groups(eta_par=41.49, eta_perp=71.52, chi=-70.67)
    hp = hopf_point(g, "chi", n_segments=16)
    with pytest.raises(ParameterError) as e:
        continue_orbits(g, "chi", 100.0, n_points=3, n_segments=16)
    assert f"mirror branch from {-hp.value:.6g}" in str(e.value)
    with pytest.raises(ParameterError) as e:  # on its own side: no mirror to name
        continue_orbits(g, "chi", -10.0, n_points=3, n_segments=16)
    assert "mirror" not in str(e.value)


def test_a_truncated_avi_says_so(tmp_path):
    """ffmpeg estimates a cut AVI's length from its size, so 140 of 200 frames were read as a
    whole movie of 140. The header's count tells."""
    import warnings

    import imageio_ffmpeg
    import numpy as np

    from flutterswim.tracking.io import open_frames

    W, H, n = 128, 96, 200
    rng = np.random.default_rng(0)
    full = tmp_path / "full.avi"
    w = imageio_ffmpeg.write_frames(str(full), (W, H), fps=50, codec="ffv1", pix_fmt_in="gray",
                                    pix_fmt_out="gray", macro_block_size=1)
    w.send(None)
    for i in range(n):
        a = rng.integers(0, 60, (H, W)).astype(np.uint8)
        a[:, i % W] = 200
        w.send(a.tobytes())
    w.close()
    cut = tmp_path / "cut.avi"
    data = full.read_bytes()
    cut.write_bytes(data[: len(data) * 7 // 10])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(open_frames(full)) == n
    with pytest.warns(UserWarning, match=rf"header lists {n} frames, (\d+) can be read") as rec:
        m = len(open_frames(cut))
    assert 0 < m < n and f"{m} can be read" in str(rec[0].message)


def test_field_start_after_the_run_is_refused(tmp_path, capsys):
    """--field-start 50 with --t-end 5 ran, its field never turning, without a word."""
    from flutterswim.cli import main

    out = tmp_path / "r.nc"
    assert main(["simulate", "--t-end", "5", "--field-rotate", "10", "--field-start", "50", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--field-start=50.0" in err and "--t-end=5.0" in err and not out.exists()


def test_describe_of_a_turning_field_says_why_there_is_no_limit_cycle():
    """A field turning at a changing rate over the cycles described: no limit cycle, and the
    advice is not to simulate longer (a longer run turns on) but that the field turns."""
    import numpy as np

    from flutterswim.analysis.descriptors import describe
    from flutterswim.field import Field, Piecewise

    f = Field(direction=Piecewise(np.array([0, 9, 11, 13, 16.0]), np.radians([0, 0, 20, 25, 60.0]), kind="linear"))
    d = describe(fs.simulate(fs.PAPER, 16.0, n_segments=16, field=f))
    assert not d.limit_cycle
    assert d.note.startswith("no limit cycle: the field turns by") and "simulate longer" not in d.note


def test_describe_of_a_field_step_says_why_the_turning_figures_are_nan():
    import math

    from flutterswim.analysis.descriptors import describe
    from flutterswim.steering.schedules import _step

    d = describe(fs.simulate(fs.PAPER, 14.0, n_segments=16, field=_step(math.radians(10), 11.0, 0.0)))
    assert math.isnan(d.turning_radius_mm)
    assert "the field turns by 10 deg in the record, but not steadily" in d.note
