"""Examples are tests: each example script runs at a small size."""

import subprocess
import sys
from pathlib import Path

import numpy as np

import flutterswim as fs

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_steering_example_follows_the_rotating_field(tmp_path):
    out = subprocess.run([sys.executable, str(EXAMPLES / "steering_circle.py"), "--out", str(tmp_path),
                          "--small", "--rate", "0.4", "--turns", "0.5"],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    png = tmp_path / "steering_circle.png"
    assert png.stat().st_size > 10_000
    run = fs.load(tmp_path / "steering_run.nc")
    # after half a turn of the field the swimmer heads the other way: its displacement over
    # the last seconds points along the field, within the stroke's wobble
    t = run.t
    late = t > t[-1] - 3 * 0.38
    dx = run.x[late].mean(axis=1)[-1] - run.x[late].mean(axis=1)[0]
    dy = run.y[late].mean(axis=1)[-1] - run.y[late].mean(axis=1)[0]
    phi = run.field_angle[late].mean()
    assert np.cos(np.arctan2(dy, dx) - phi) > 0.7
    assert np.cos(phi) < -0.9  # the field has turned by about pi


def test_steering_example_refuses_a_missing_parent_and_files_not_its_own(tmp_path):
    """The house rule for outputs: a missing parent folder is refused, not made (the example
    made every missing folder of --out), and a file there that is not ours is never replaced;
    a rerun replaces the example's own files (its figure is signed)."""
    def example(out):
        return subprocess.run([sys.executable, str(EXAMPLES / "steering_circle.py"), "--out", str(out), "--small",
                               "--rate", "0.4", "--turns", "0.5"], capture_output=True, text=True, timeout=300)

    r = example(tmp_path / "typo" / "deeper" / "out")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "does not exist" in r.stderr and not (tmp_path / "typo").exists()
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "steering_circle.png").write_bytes(b"a figure of mine")
    r = example(mine)
    assert r.returncode == 2 and "never" in r.stderr and not (mine / "steering_run.nc").exists(), r.stderr
    assert (mine / "steering_circle.png").read_bytes() == b"a figure of mine"
    (mine / "steering_circle.png").unlink()
    assert example(mine).returncode == 0
    r = example(mine)  # its own files: replaced
    assert r.returncode == 0, r.stderr


def test_demo_module_runs(tmp_path):
    out = subprocess.run([sys.executable, "-m", "flutterswim.demo", "--out", str(tmp_path), "--cycles", "3",
                          "--segments", "16"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "advancement per cycle" in out.stdout
    assert (tmp_path / "paper_swimmer.png").stat().st_size > 10_000
    assert fs.load(tmp_path / "paper_run.nc").settings["limit_cycle"] is True
