"""Omega_max: a field turning faster than the swimmer can follow makes it lose its stroke, but
near Omega_max late (at 1.3 kappa_E, after about a turn). A test of one 0.6-turn run judged on
the mean speed put Omega_max 10 % too high there (a review: the stroke lost 6 s into a run
judged as following)."""

import numpy as np

import flutterswim as fs
from flutterswim.orbits import periodic_orbit
from flutterswim.steering import cycle_average
from flutterswim.steering.reduced import follows, rotating_run


def _final_speed(run, period):
    avg = cycle_average(run.t, run.x.mean(axis=1), run.y.mean(axis=1), run.field_angle, period)
    return float(np.mean(avg.speed[avg.t > avg.t[-1] - 4 * period]))


def test_a_stroke_lost_late_in_the_turn_is_not_following():
    p = fs.PAPER.replace(kappa_E=1.3 * fs.PAPER.kappa_E)
    orb = periodic_orbit(p, n_segments=24)
    U, T = orb.speed, orb.period
    for omega, lost in ((0.548, True), (0.49, False)):
        # independent: is the swimmer still swimming after 3 turns of the field?
        long = rotating_run(p, omega, turns=3.0, onset=12.0, n_segments=24, period=T)
        assert (_final_speed(long, T) < 0.5 * U) == lost, omega
        # the identification's own run and verdict (its default length)
        run = rotating_run(p, omega, onset=12.0, n_segments=24, period=T)
        assert follows(run, omega, U, T, 12.0)[0] == (not lost), omega
