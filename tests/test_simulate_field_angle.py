"""``simulate --field-angle A`` starts the filament along the field (tilted 0.01 degree from
it), so the run is the default run rotated by A (rotation invariance). It started along e1,
across a field at 90 degrees, and was trapped in a bent equilibrium at once (a review)."""

import math

import numpy as np

import flutterswim as fs
from flutterswim.cli import main


def test_a_constant_field_angle_rotates_the_whole_run(tmp_path):
    a, b = tmp_path / "a.nc", tmp_path / "b.nc"
    common = ["simulate", "--t-end", "10", "--segments", "16", "--quiet"]
    assert main([*common, "--out", str(a)]) == 0
    assert main([*common, "--field-angle", "90", "--out", str(b)]) == 0
    ra, rb = fs.load(str(a)), fs.load(str(b))
    c, s = math.cos(math.pi / 2), math.sin(math.pi / 2)
    xa, ya = ra.x[-1], ra.y[-1]  # the last frame's centreline, rotated by 90 degrees
    xr, yr = c * xa - s * ya, s * xa + c * ya
    scale = fs.PAPER.l
    np.testing.assert_allclose(rb.x[-1], xr, atol=2e-3 * scale)
    np.testing.assert_allclose(rb.y[-1], yr, atol=2e-3 * scale)
    # and it swims along the field: the centroid moved mostly in +y
    d = np.array([rb.x[-1].mean() - rb.x[0].mean(), rb.y[-1].mean() - rb.y[0].mean()])
    assert d[1] > 0.1 * scale and abs(d[0]) < 0.1 * d[1]


def test_the_api_starts_along_the_field_too():
    """The default start is the paper's tilt from the field's direction at t_start, in the API
    as on the command line: the run in a field at 90 degrees is the default run rotated."""
    from flutterswim.field import Field

    a = fs.simulate(fs.PAPER, 10.0, n_segments=16)
    b = fs.simulate(fs.PAPER, 10.0, n_segments=16, field=Field(direction=math.pi / 2))
    np.testing.assert_allclose(b.x[-1], -a.y[-1], atol=2e-3 * fs.PAPER.l)
    np.testing.assert_allclose(b.y[-1], a.x[-1], atol=2e-3 * fs.PAPER.l)
