"""Stop 47: items left at stop 46."""

import pytest

import flutterswim as fs
from flutterswim.orbits.linear import hopf_point


@pytest.mark.parametrize("factor", [60.0, 1 / 60.0])
def test_the_hopf_search_finds_the_point_from_far_away(factor):
    """From a sweep point far past onset (kappa_E 60 times the paper's, chi = 4242) the search
    said there was no Hopf point for chi between 84.8 and 212010; the one at 48.3 lies a sixtieth
    below. The Hopf point does not depend on where the search starts."""
    near = hopf_point(fs.PAPER, "chi", n_segments=12).value
    far = hopf_point(fs.PAPER.replace(kappa_E=factor * fs.PAPER.kappa_E), "chi", n_segments=12).value
    assert far == pytest.approx(near, rel=1e-9)


def test_a_file_size_limit_while_saving_is_a_failure_not_a_crash(tmp_path):
    """HDF5 writing onto a full disk or past a file size limit (ulimit -f, a quota) crashed
    Python with a segmentation fault (exit 139) after the OSError: in a notebook the kernel and
    everything in it was lost. The file is now built in memory and written by Python: exit 1,
    one line, no partial file, and the error is an OSError in the API."""
    import resource
    import subprocess
    import sys

    cmd = [sys.executable, "-m", "flutterswim", "simulate", "--t-end", "3", "--segments", "12", "--quiet"]
    full = subprocess.run([*cmd, "--out", str(tmp_path / "full.nc")], capture_output=True, text=True, timeout=300)
    assert full.returncode == 0, full.stderr
    size = (tmp_path / "full.nc").stat().st_size
    (tmp_path / "limited").mkdir()

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (size // 2, size // 2))

    r = subprocess.run([*cmd, "--out", str(tmp_path / "limited" / "r.nc")], capture_output=True, text=True,
                       timeout=300, preexec_fn=limit)
    assert r.returncode == 1, (r.returncode, r.stderr)
    assert len(r.stderr.strip().splitlines()) == 1 and "File too large" in r.stderr
    assert list((tmp_path / "limited").iterdir()) == []
