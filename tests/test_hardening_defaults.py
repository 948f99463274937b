"""One place for the defaults: the API, the CLI, the demo and the sweeps read flutterswim.defaults;
the sweeps' coarser resolution meets the accuracy it states."""

import inspect

import pytest

import flutterswim as fs
from flutterswim import defaults


def _cli_defaults(cmd):
    from flutterswim.cli import build_parser

    ap = build_parser()
    sub = next(a for a in ap._actions if a.__class__.__name__ == "_SubParsersAction")
    return {a.dest: a.default for a in sub.choices[cmd]._actions}


def test_api_cli_demo_and_sweep_share_the_defaults():
    sig = inspect.signature(fs.simulate).parameters
    assert (sig["n_segments"].default, sig["rtol"].default, sig["atol"].default) == (
        defaults.N_SEGMENTS, defaults.RTOL, defaults.ATOL)
    cli = _cli_defaults("simulate")
    assert (cli["segments"], cli["rtol"], cli["atol"]) == (defaults.N_SEGMENTS, defaults.RTOL, defaults.ATOL)
    # describe's cycles by what it reads: a run N_CYCLES, a tracked movie N_CYCLES_MOVIE (as track's)
    assert _cli_defaults("describe")["last"] is None
    assert _cli_defaults("track")["last"] == _cli_defaults("track-batch")["last"] == defaults.N_CYCLES_MOVIE
    import flutterswim.demo as demo

    src = inspect.getsource(demo.main)
    assert "defaults.N_CYCLES" in src and "defaults.N_SEGMENTS" in src and "defaults.RTOL" in src
    st = fs.sweep.PointSettings()
    assert (st.n_cycles, st.rtol, st.atol, st.n_segments) == (defaults.N_CYCLES, defaults.RTOL, defaults.ATOL,
                                                              defaults.SWEEP_N_SEGMENTS)
    # frames per tau of simulate's default output
    run = fs.simulate(fs.Groups(40.0, 70.0, 0.0), 2.0, n_segments=8)
    assert run.t.size == 2 * defaults.FRAMES_PER_TAU + 1


@pytest.mark.slow
def test_sweep_resolution_meets_its_stated_accuracy():
    """Paper point: N = SWEEP_N_SEGMENTS against a fine run (N = 96, rtol 1e-7) of the same job."""
    from flutterswim.analysis.descriptors import describe

    def job(n, rtol, atol):
        r = fs.simulate(fs.PAPER, 14.0, n_segments=n, rtol=rtol, atol=atol,
                        frame_dt=fs.PAPER.tau / defaults.SWEEP_FRAMES_PER_TAU)
        d = describe(r, n_last=15)
        assert d.limit_cycle
        return d.period_s, d.advance_per_cycle_mm

    p_ref, a_ref = job(96, 1e-7, 1e-9)
    p, a = job(defaults.SWEEP_N_SEGMENTS, defaults.RTOL, defaults.ATOL)
    assert abs(p / p_ref - 1) < defaults.SWEEP_PERIOD_ERROR
    assert abs(a / a_ref - 1) < defaults.SWEEP_ADVANCE_ERROR
    # and the stated figure is not loose by an order of magnitude
    assert abs(a / a_ref - 1) > 0.1 * defaults.SWEEP_ADVANCE_ERROR
