"""The steering metrics against made-up trajectories whose answers are known from geometry:
arrivals at a closed square's corners (a review: every corner "reached" when control started,
the first averaged position projecting to the end of the path, a lap ahead), the time to
reacquire the path after each corner, and the cross-track error at a sharp corner (a review: a
search near the last nearest point lost the path at a 150 degree turn, 5.98 body lengths RMS
against the true 0.19)."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

import flutterswim as fs
from flutterswim.steering.path import _polyline, square
from flutterswim.steering.reduced import ReducedModel
from flutterswim.steering.steer import ARRIVAL_BL, metrics
from flutterswim.steering.turning import _moving_average

L = fs.PAPER.l
# a short averaging period: the averaged trajectory is the made-up one to within U T / 8 at corners
RED = ReducedModel(U=1e-3, period=0.02, k=4.0, omega_max=0.26, omega_max_bracket=(0.25, 0.27),
                   r_min=1e-3 / 0.26, onset_time=0.0)


def _run(way: np.ndarray, dt: float = 0.01, t_before: float = 0.0):
    """A centroid moving along the polyline ``way`` at the speed U, sampled every ``dt``; time 0
    is ``t_before`` after it sets off."""
    seg = np.hypot(*np.diff(way, axis=0).T)
    s = np.r_[0.0, np.cumsum(seg)]
    t = np.arange(0.0, s[-1] / RED.U, dt)
    x, y = np.interp(t * RED.U, s, way[:, 0]), np.interp(t * RED.U, s, way[:, 1])
    return SimpleNamespace(t=t - t_before, x=x[:, None], y=y[:, None]), s


def test_closed_square_corners_are_reached_when_passed_and_reacquired_after_each():
    """Around a square of 10 body lengths from 0.2 body lengths behind its start (on its closing
    edge), for 1.2 laps; after each corner the path is cut inside from 0.3 body lengths before
    the vertex back onto the next edge D further on. Arrival: where the trajectory crosses the
    corner's bisector; reacquired when the error 0.3 (1 - sigma / D) falls below 0.1 body length."""
    side, cut, D, back = 10 * L, 0.3 * L, 2.0 * L, 0.2 * L
    path = square(side, (0.0, 0.0), 0.0)
    V = np.array([[0, 0], [side / 2, 0], [side / 2, side], [-side / 2, side], [-side / 2, 0]], float)
    way, arrive, reacq_true, misses = [np.array([-back, 0.0])], [], [], []
    lap_len = 4 * side
    for lap in range(2):
        for k in range(1, 5):
            if lap == 1 and k > 1:
                break
            v = V[k]
            d0 = (V[k] - V[k - 1]) / np.linalg.norm(V[k] - V[k - 1])
            d1 = (V[k % 4 + 1] - V[k]) / np.linalg.norm(V[k % 4 + 1] - V[k])
            A, B = v - cut * d0, v + D * d1
            s_A = np.sum(np.hypot(*np.diff(np.array(way + [A]), axis=0).T))
            sigma_x = cut * D / (D + cut)  # equal distance to both edges: the bisector
            ab = np.linalg.norm(B - A)
            if lap == 0:
                arrive.append((s_A + sigma_x / D * ab) / RED.U)
                u = (B - A) / ab  # the closest approach to the waypoint: its distance to the cut
                misses.append(abs(u[0] * (v - A)[1] - u[1] * (v - A)[0]) / L)
                reacq_true.append((2 / 3 - sigma_x / D) * ab / RED.U)
            way += [A, B]
    way.append(way[-1] + L * np.array([0.0, 1.0]))  # on along the second edge, 1 L further
    way = np.array(way)
    run, s = _run(way)
    m = metrics(run, path, RED, 0.0, L)
    dt = 0.01
    assert m["waypoint_arrival_s"] == pytest.approx(arrive, abs=2 * dt + RED.period)
    assert m["waypoint_miss_bl"] == pytest.approx(misses, abs=0.02) and max(misses) < ARRIVAL_BL
    assert m["reacquire_after_corner_s"] == pytest.approx(reacq_true, abs=2 * dt + RED.period)
    # from 0.2 L behind the start to D + 1 L past the first corner on the second lap
    assert m["path_covered_fraction"] == pytest.approx((back + lap_len + side / 2 + D + L) / lap_len, abs=1e-3)
    # the true error: the largest is where the cut crosses the bisector
    assert m["cross_track_max_bl"] == pytest.approx(cut * D / (D + cut) / L, rel=0.02)


def test_cross_track_error_is_the_distance_to_the_path_at_a_sharp_corner():
    """Waypoints (0, 0) -> 15 body lengths -> a 150 degree turn onto another 15; the trajectory
    rounds the corner on an arc of 1.2 body lengths (the controller's turn is 1.39: 1.03 body
    lengths off the path at the bisector), passes the last waypoint and swims on 3 body lengths.
    The error is the brute-force distance to every path point; the corner's waypoint is missed
    by 3.4 body lengths, so it is not arrived at; the whole path is covered, and scored up to
    its end."""
    turn = math.radians(150)
    v = np.array([[0.0, 0.0], [15 * L, 0.0], [15 * L + 15 * L * math.cos(turn), 15 * L * math.sin(turn)]])
    path = _polyline(v, False, "wp150", 1e-5)
    r = 1.2 * L
    dist = r * math.tan(turn / 2)
    centre = v[1] + np.array([-dist, r])
    ang = -math.pi / 2 + np.linspace(0.0, turn, 400)
    arc = centre + r * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    d2 = (v[2] - v[1]) / np.linalg.norm(v[2] - v[1])
    way = np.vstack([v[:1], arc, v[2:], v[2] + 3 * L * d2])  # on past the end, which is not scored
    run, s = _run(way)
    m = metrics(run, path, RED, 0.0, L)
    t_end = s[-2] / RED.U
    assert m["end_arrival_s"] == pytest.approx(t_end, abs=0.02 + RED.period)
    ts, ax = _moving_average(run.t, run.x[:, 0], RED.period)
    _, ay = _moving_average(run.t, run.y[:, 0], RED.period)
    ax, ay = ax[ts <= m["end_arrival_s"]], ay[ts <= m["end_arrival_s"]]
    d = np.array([np.min(np.hypot(path.points[:, 0] - x, path.points[:, 1] - y)) for x, y in zip(ax, ay)])
    assert m["cross_track_rms_bl"] == pytest.approx(np.sqrt(np.mean(d ** 2)) / L, rel=1e-3)
    assert m["cross_track_max_bl"] == pytest.approx(d.max() / L, rel=1e-3)
    # the largest is at the arc's middle: r (1 / sin(15 deg) - 1) from the vertex, sin(15 deg) of it off each edge
    half = (math.pi - turn) / 2
    assert m["cross_track_max_bl"] == pytest.approx(r * (1 / math.sin(half) - 1) * math.sin(half) / L, rel=1e-3)
    # the waypoint is passed r (1 / sin(15 deg) - 1) = 3.4 body lengths away: no arrival there
    # (it was reported at the arc's middle, as for a corner passed close by)
    miss = r * (1 / math.sin(half) - 1) / L
    assert m["waypoint_miss_bl"] == pytest.approx([miss], rel=0.02) and miss > ARRIVAL_BL
    assert math.isnan(m["waypoint_arrival_s"][0])
    assert m["path_covered_fraction"] > 0.99


def test_a_figure_eight_is_followed_through_its_crossing():
    """0.3 body lengths left of a figure eight for one lap: where it crosses itself the other
    branch passes under the swimmer, but the progress stays on the branch followed (one lap
    covered) and the error is the distance to the nearest branch."""
    from flutterswim.steering.path import figure8

    path = figure8(12 * L, (0.0, 0.0), 0.0)
    P = path.points
    t = np.gradient(P, axis=0)
    t /= np.hypot(*t.T)[:, None]
    way = P + 0.3 * L * np.stack([-t[:, 1], t[:, 0]], axis=1)
    run, _ = _run(way)
    m = metrics(run, path, RED, 0.0, L)
    assert m["path_covered_fraction"] == pytest.approx(1.0, abs=0.01)
    ts, ax = _moving_average(run.t, run.x[:, 0], RED.period)
    _, ay = _moving_average(run.t, run.y[:, 0], RED.period)
    d = np.array([np.min(np.hypot(P[:, 0] - x, P[:, 1] - y)) for x, y in zip(ax, ay)])
    assert m["cross_track_max_bl"] == pytest.approx(d.max() / L, rel=1e-3)


def test_the_default_figure_eight_is_wider_than_the_controllers_tightest_turn():
    """The lemniscate x = a sin u, y = a/2 sin 2u (a: half the CLI's default size) bends with the
    radius (x'^2 + y'^2)^(3/2) / |x' y'' - y' x''|; its smallest must not be below the
    controller's tightest turn U / (0.8 Omega_max) at the paper's point (the default of 10 body
    lengths bent down to 1.04 against 1.39: steer warned that its own default cannot be followed)."""
    from flutterswim.steering.cli import SIZE_OPTION

    size = float(SIZE_OPTION["figure8"][1])
    a = size / 2
    u = np.linspace(0.0, 2 * math.pi, 200_000, endpoint=False) + 1e-6  # (the tangent is never zero)
    xp, yp, xpp, ypp = a * np.cos(u), a * np.cos(2 * u), -a * np.sin(u), -2 * a * np.sin(2 * u)
    r_path = np.min((xp ** 2 + yp ** 2) ** 1.5 / np.abs(xp * ypp - yp * xpp))
    U, omega_max = 1.0582e-3, 0.2578  # identified at the paper's point (0.2578-0.2606 rad/s, N = 24)
    assert r_path >= U / (0.8 * omega_max) / L


def test_corner_cut_is_the_fillets_distance_from_the_waypoint():
    """radius (1 / cos(a / 2) - 1) for a turn by a: a square's corners (90 degrees) 0.414 r, an
    equilateral triangle's (120) r; the largest over the corners; 0 without corners."""
    from flutterswim.steering.path import circle
    from flutterswim.steering.steer import corner_cut

    r = 1.37 * L
    assert corner_cut(square(10 * L, (0.0, 0.0), 0.0), r) == pytest.approx((math.sqrt(2) - 1) * r, rel=1e-6)
    tri = np.array([[0.0, 0.0], [6 * L, 0.0], [3 * L, 6 * L * math.sin(math.pi / 3)]])
    assert corner_cut(_polyline(tri, True, "triangle", 1e-5), r) == pytest.approx(r, rel=1e-6)
    mixed = np.array([[0.0, 0.0], [8 * L, 0.0], [8 * L, 8 * L], [8 * L + 8 * L * math.cos(math.radians(-30)),
                                                                 8 * L + 8 * L * math.sin(math.radians(-30))]])
    assert corner_cut(_polyline(mixed, False, "mixed", 1e-5), r) == pytest.approx(r, rel=1e-6)
    assert corner_cut(circle(2 * L, (0.0, 0.0), 0.0), r) == 0.0


def test_a_u_turns_cut_is_that_of_the_rounded_path():
    """Near a U-turn the rounded path's arc is shortened to fit its edges: the cut is the rounded
    path's distance from the vertex (brute force), at most half the 10 body length edge, not
    r (1 / cos(a / 2) - 1) (1.4e12 at 180 degrees)."""
    from flutterswim.steering.path import fillet
    from flutterswim.steering.steer import corner_cut

    r = 1.37 * L
    for turn in (170.0, 179.0, 180.0):
        a = math.radians(180.0 - turn)
        v = np.array([[0.0, 0.0], [10 * L, 0.0], [10 * L - 10 * L * math.cos(a), 10 * L * math.sin(a)]])
        path = _polyline(v, False, "u-turn", 1e-5)
        cut = corner_cut(path, r)
        brute = np.hypot(*(fillet(path, r).points - v[1]).T).min()
        assert cut == pytest.approx(brute, rel=1e-6) and cut <= 5.0 * L * (1 + 1e-9)


def test_a_corner_cut_on_the_first_lap_is_no_arrival_on_a_later_one():
    """Two laps of a square: the first cuts corner 0 by 1.5 body lengths, the second passes
    within 0.2. Arrival and closest approach are both of the first pass (the miss was the
    second lap's, 0.2, beside the first lap's arrival time)."""
    side = 10 * L
    path = square(side, (0.0, 0.0), 0.0)
    V = np.array([[side / 2, 0], [side / 2, side], [-side / 2, side], [-side / 2, 0]], float)
    way = [np.array([0.0, 0.0])]
    for inset in (1.5 * L, 0.2 * L):
        for k, v in enumerate(V):
            c = inset * math.sqrt(2) if k == 0 else 0.3 * L * math.sqrt(2)
            d0 = (v - way[-1]) / np.linalg.norm(v - way[-1])
            d1 = (V[(k + 1) % 4] - v) / np.linalg.norm(V[(k + 1) % 4] - v)
            way += [v - c * d0, v + c * d1]
        way.append(np.array([0.0, 0.0]))
    run, _ = _run(np.array(way))
    m = metrics(run, path, RED, 0.0, L)
    assert m["waypoint_miss_bl"][0] > 1.0 and math.isnan(m["waypoint_arrival_s"][0])
