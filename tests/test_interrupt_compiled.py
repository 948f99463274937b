"""Ctrl-C reaches a long quiet run: a signal is seen only when compiled code returns to
Python, and a constant-field run without progress or check was one compiled call (a 30 s
run ignored Ctrl-C until its end). The compiled NDF now returns every few hundred steps and
continues exactly (the same frames bit for bit)."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np

import flutterswim as fs


def test_returning_to_python_changes_nothing(monkeypatch):
    from flutterswim import integrators

    a = fs.simulate(fs.PAPER, 3.0, n_segments=12)
    monkeypatch.setattr(integrators, "YIELD_STEPS", 7)
    b = fs.simulate(fs.PAPER, 3.0, n_segments=12)
    assert a.stats.n_steps > 50  # many returns
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.kappa, b.kappa)


def test_ctrl_c_stops_a_quiet_constant_field_run_promptly(tmp_path):
    script = tmp_path / "long.py"
    script.write_text(textwrap.dedent('''
        import signal, sys, time
        signal.signal(signal.SIGINT, signal.default_int_handler)  # as from a terminal
        import flutterswim as fs
        p = fs.PAPER
        fs.simulate(p, 2 * p.tau, n_segments=48)  # compiled (or loaded) before the clock starts
        t0 = time.perf_counter()
        fs.simulate(p, 4 * p.tau, n_segments=48)
        per_tau = (time.perf_counter() - t0) / 4
        print(per_tau, flush=True)
        try:
            fs.simulate(p, 40.0 / per_tau * p.tau, n_segments=48, frame_dt=50 * p.tau)  # about 40 s
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            sys.exit(130)
    '''))
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    per_tau = float(proc.stdout.readline())
    assert per_tau > 0
    time.sleep(1.0)
    t0 = time.perf_counter()
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    latency = time.perf_counter() - t0
    assert proc.returncode == 130 and "interrupted" in out, err
    assert latency < 5.0, latency  # the run had about 39 s left
