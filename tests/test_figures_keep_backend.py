"""API figure functions must not switch a user's matplotlib backend: they had called
matplotlib.use("Agg"), which replaces an interactive session's backend (a Tk or Qt window stops
updating). A figure saved to a file is an Agg figure, never registered with pyplot (nothing
left open); a figure returned for the screen (path None) is pyplot's, in the session's backend,
so plt.show() and a notebook display it (a review of the first fix: an Agg figure showed as
text in a notebook, and plt.show() showed nothing)."""

import os
import re
import subprocess
import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "flutterswim"

SCRIPT = r"""
import sys
import numpy as np
import matplotlib
assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
from flutterswim.fitting.data import Trials, plot_trials, summarise
from flutterswim.stability.plots import plot_bifurcation, plot_map, plot_modes
from flutterswim.stability.modes import animate_mode, bifurcation, eigenmodes
from flutterswim.stability.stability_map import stability_map
from flutterswim.steering.trap import TrapMap, plot_trap

out = sys.argv[1]
tr = Trials(np.array([80.0, 80.0, 90.0, 90.0]), np.array(["a"] * 4), np.ones((4, 3)))
figs = [plot_trials(summarise(tr), None, trials=tr)]
plot_trials(summarise(tr), out + "/trials.png", trials=tr)
m = stability_map(eta_perp=np.linspace(10, 100, 4), chi=np.linspace(-100, 100, 5))
figs.append(plot_map(m))
plot_map(m, path=out + "/map.png")
figs.append(plot_bifurcation([bifurcation(parameter="chi", values=np.linspace(50, 90, 5), fixed=71.5)]))
modes = eigenmodes(70.7, 71.5, n_points=41)
figs.append(plot_modes(modes))
animate_mode(modes[0], out + "/mode.gif", frames=4)
tm = TrapMap(np.array([0.0, 5.0]), np.array(["limit_cycle", "bent_equilibrium"]), np.array([10.0, 90.0]),
             np.array([1.0, 10.0]), np.array([["limit_cycle"] * 2, ["bent_equilibrium"] * 2]), turn_time_s=1.0)
figs.append(plot_trap(tm))
plot_trap(tm, out + "/trap.png")
assert all(f.axes for f in figs)
import matplotlib.pyplot as plt
shown = sorted(plt.get_fignums())
# every figure returned is pyplot's (shown); none of those saved is
assert all(f.number in shown for f in figs), shown
assert len(shown) == len(figs), (shown, len(figs))
from flutterswim.plotting._common import offscreen
with offscreen():
    assert not hasattr(plot_map(m), "number")  # (a batch job's figures: never pyplot's)
print(matplotlib.get_backend(), len(plt.get_fignums()))
"""


def test_api_figures_keep_the_users_backend(tmp_path):
    env = dict(os.environ, MPLBACKEND="svg")
    res = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path)], env=env, capture_output=True, text=True,
                         timeout=300)
    assert res.returncode == 0, res.stderr[-2000:]
    backend, n_open = res.stdout.split()
    assert backend == "svg"  # not switched to Agg
    assert n_open == "5"  # the five returned for the screen, none of those saved nor offscreen
    for name in ("trials.png", "map.png", "trap.png", "mode.gif"):
        assert (tmp_path / name).stat().st_size > 1000


def test_no_module_switches_the_backend():
    offenders = [str(p.relative_to(SRC)) for p in SRC.rglob("*.py")
                 if re.search(r"matplotlib\.use\(", p.read_text())]
    assert not offenders, offenders
