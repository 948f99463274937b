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


def test_demo_module_runs(tmp_path):
    out = subprocess.run([sys.executable, "-m", "flutterswim.demo", "--out", str(tmp_path), "--cycles", "3",
                          "--segments", "16"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "advancement per cycle" in out.stdout
    assert (tmp_path / "paper_swimmer.png").stat().st_size > 10_000
    assert fs.load(tmp_path / "paper_run.nc").settings["limit_cycle"] is True
