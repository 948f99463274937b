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
