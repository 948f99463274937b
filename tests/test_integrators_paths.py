"""The integrators' less travelled paths: Python-stepped ROS34PW2, a field that turns between
breakpoints, scipy's methods, and the frames at t_end (from a review of the simulator away
from the paper's point)."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

import flutterswim as fs
from flutterswim import Field, InitialState
from flutterswim.filament import Filament
from flutterswim.integrators import ROS34PW2, integrate

G = fs.PAPER.groups


def test_python_ros34pw2_keeps_its_order_at_repeated_step_sizes():
    """Fixed steps (max_step = first_step = h, tolerances out of play): the LU of the last
    step's J was kept while the stage term used a fresh J, and the method fell to order 1.00."""
    n = 8
    fil = Filament(n, G.eta_par, G.eta_perp, G.chi)
    y0 = fs.simulate(G, 12.0, n_segments=n, initial=InitialState.straight(1.0), rtol=1e-10, atol=1e-12).state_final

    def fun(t, y):
        return fil.rhs(y, 0.0, 1.0)

    def jac(t, y):
        return fil.jacobian(y, 0.0, 1.0)

    T = 0.1
    ref = solve_ivp(fun, (0, T), y0, method="Radau", jac=lambda t, y: fil.jacobian(y, 0.0, 1.0, exact=True),
                    rtol=1e-13, atol=1e-14).y[:, -1]
    errs = []
    for h in (2e-3, 1e-3, 5e-4):
        sol = integrate(fun, jac, (0.0, T), y0, np.array([T]), method=ROS34PW2.name, rtol=1e6, atol=1e6,
                        max_step=h, first_step=h, time_dependent=False)
        assert sol.stats.n_steps == round(T / h)
        errs.append(np.max(np.abs(sol.y_final - ref)))
    slopes = np.diff(np.log2(errs)) * -1
    assert np.all(slopes > 2.4), (errs, slopes)  # W-order 3 (2.7-2.9 here); the defect gave 1.0


def test_a_field_turning_between_breakpoints_is_as_accurate_as_a_steady_one():
    """A callable field is stepped in Python: by the wave-1 ROS34PW2 it was 1.4e-1 off at
    max_step 0.01 where the compiled NDF on the same (constant) field is 5e-5; ``ndf`` now
    takes scipy's BDF, the algorithm it compiles."""
    kw = dict(n_segments=24, initial=InitialState.straight(1.0), n_frames=41, max_step=0.01)
    ref = fs.simulate(G, 20.0, rtol=1e-10, atol=1e-12, **kw)
    steady = fs.simulate(G, 20.0, **kw)
    turning = fs.simulate(G, 20.0, field=Field(direction=lambda t: 0.0), **kw)
    assert turning.settings["method_used"] == "bdf"
    e_steady = np.max(np.abs(steady.theta - ref.theta))
    e_turning = np.max(np.abs(turning.theta - ref.theta))
    assert e_turning < 3.0 * e_steady and e_turning < 1e-3, (e_turning, e_steady)


def test_scipy_methods_stop_on_self_intersection_and_keep_frames():
    """radau and bdf ignored ``stop_on_self_intersection`` (and ``check``): they ran on to t_end
    where ndf and ros34pw2 stop at the first crossing."""
    g = fs.Groups(G.eta_par, 1.72 * G.eta_par, 7 * 0.68 * G.chi)
    stops = {}
    for m in ("ndf", "bdf", "radau"):
        r = fs.simulate(g, 4.0, n_segments=24, method=m, stop_on_self_intersection=True, n_frames=401)
        assert r.status == "stopped" and "self-intersection" in r.message, (m, r.message)
        assert r.t.size >= 2 and np.all(np.isfinite(r.theta)) and r.t[-1] <= r.t_final
        stops[m] = r.t_final
    assert max(stops.values()) - min(stops.values()) < 0.05, stops


def test_the_frame_at_t_end_is_kept():
    """frame_dt: the count's last frame lay past t_end by round-off (7.300000000000001) and was
    dropped; ndf: a step ending within the loop's slack of t_end ended the run 1e-14 short and
    dropped the last frame (eta_perp 1.72 eta_par, 4 chi_c, rtol 1e-10)."""
    r = fs.simulate(G, 7.3, frame_dt=0.1, n_segments=12)
    assert r.t.size == 74 and r.t[-1] == 7.3 and r.status == "completed"
    g = fs.Groups(G.eta_par, 1.72 * G.eta_par, 4 * 0.68 * G.chi)
    r = fs.simulate(g, 30.0, n_segments=48, rtol=1e-10, atol=1e-12, n_frames=301)
    assert r.status == "completed" and r.t.size == 301 and math.isclose(r.t[-1], 30.0) and r.t_final == 30.0


def test_a_finely_sampled_continuous_field_is_not_a_restart_at_each_sample():
    """A linear Piecewise (as --field-csv builds) is continuous: scipy's BDF restarted at each
    of its 1001 points (order 1 each time) was 8.1e-2 off in 7694 steps; stepping through its
    kinks it is as accurate as with 41 points (a review of this stop's diff)."""
    from flutterswim import Piecewise

    kw = dict(n_segments=12, initial=InitialState.straight(1.0), n_frames=21)
    errs = {}
    for n in (41, 1001):
        t = np.linspace(0.0, 10.0, n)
        fld = Field(direction=Piecewise(tuple(t), tuple(0.3 * np.sin(2 * np.pi * t / 10.0)), kind="linear"))
        ref = fs.simulate(G, 10.0, field=fld, method="bdf", rtol=1e-9, atol=1e-11, **kw)
        run = fs.simulate(G, 10.0, field=fld, **kw)
        errs[n] = (np.max(np.abs(run.theta - ref.theta)), run.stats.n_steps)
    assert errs[1001][0] < 3.0 * errs[41][0] and errs[1001][1] < 2 * errs[41][1], errs
