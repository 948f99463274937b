"""A field turning faster than the swimmer can follow (the paper's swimmer: Omega_max about 0.26
rad/s) loses the stroke and curls the body up until it crosses itself, a shape the model (no
contact between parts of the body) cannot describe. `simulate` said only "completed" and
describe's table showed self_intersecting without a word, with a hint to give the field's
direction though the run's own field was turning. A review's case (stop 35), rerun at N = 24."""

import json

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.cli import main


def _crossing_frames(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Brute force, independent of the package's pruned test: every pair of non-adjacent
    segments of every frame, by the signs of orientation determinants (strict crossings)."""
    px, py = x[:, :-1], y[:, :-1]
    qx, qy = x[:, 1:], y[:, 1:]
    n = px.shape[1]
    i, j = np.triu_indices(n, k=2)

    def orient(ax, ay, bx, by, cx, cy):
        return np.sign((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))

    d1 = orient(px[:, i], py[:, i], qx[:, i], qy[:, i], px[:, j], py[:, j])
    d2 = orient(px[:, i], py[:, i], qx[:, i], qy[:, i], qx[:, j], qy[:, j])
    d3 = orient(px[:, j], py[:, j], qx[:, j], qy[:, j], px[:, i], py[:, i])
    d4 = orient(px[:, j], py[:, j], qx[:, j], qy[:, j], qx[:, i], qy[:, i])
    return np.any((d1 * d2 < 0) & (d3 * d4 < 0), axis=1)


def _run(tmp_path, seconds_per_turn, capsys):
    out = tmp_path / f"turn{seconds_per_turn}.nc"
    status = main(["simulate", "--t-end", "35", "--field-rotate", str(seconds_per_turn), "--field-start", "10",
                   "--segments", "24", "--quiet", "--out", str(out)])
    assert status == 0
    line = capsys.readouterr().out
    assert main(["describe", "--json", str(out)]) == 0
    d = json.loads(capsys.readouterr().out)
    return fs.load(str(out)), line, d


@pytest.mark.parametrize("seconds_per_turn", [8.0])
def test_a_field_turning_too_fast_curls_the_body_and_both_commands_say_so(tmp_path, capsys, seconds_per_turn):
    run, line, d = _run(tmp_path, seconds_per_turn, capsys)
    t = np.asarray(run.t)
    last = t >= t[-1] - 0.2 * (t[-1] - t[0])
    frac = float(np.mean(_crossing_frames(np.asarray(run.x)[last], np.asarray(run.y)[last])))
    assert frac > 0.2  # the independent count: the body is curled up, most of the time
    assert "crosses itself" in line and "--field-start" in line
    stated = float(line.split("crosses itself in ")[1].split(" %")[0])
    assert stated == pytest.approx(100 * frac, abs=1.0)  # (printed to 2 digits)
    assert d["self_intersecting"] and "crosses itself" in d["note"]
    assert "give its direction" not in d["note"]  # the run's field turned: it has no one direction


def test_a_field_turning_slowly_is_followed_without_a_note(tmp_path, capsys):
    run, line, d = _run(tmp_path, 40.0, capsys)
    assert not np.any(_crossing_frames(np.asarray(run.x), np.asarray(run.y))[np.asarray(run.t) > 12.0])
    assert "crosses itself" not in line and "crosses itself" not in d["note"]
    # the swimmer follows: a circle of radius U / Omega with the straight run's speed
    omega = 2 * np.pi / 40.0
    assert d["turning_radius_mm"] == pytest.approx(d["speed_mm_s"] / omega, rel=0.03)
    assert "give its direction" not in d["note"]
