"""The reproduce engine: up-to-date targets are skipped, changed outputs rebuilt, a SIGKILL
keeps every finished target, foreign files are never overwritten, the CLI's exit codes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from flutterswim import ParameterError
from flutterswim.reproduce.io import write_json
from flutterswim.reproduce.manifest import Manifest
from flutterswim.reproduce.targets import Outcome, Settings, Target, build_targets, compare

pytest.importorskip("xarray")
pytest.importorskip("jinja2")


def _counter_target(name, calls, value=1.0, deps=()):
    def build(ctx):
        calls.append(name)
        write_json(ctx.path(f"{name}_data.json"), {"value": value})
        return Outcome("ok", (compare("x", 1.0, value, rtol=0.1),))

    return Target(name, name, "", build, lambda s: {"value": value}, data=(f"{name}_data.json",), deps=deps)


def test_rerun_skips_up_to_date_and_rebuilds_changed(tmp_path):
    calls: list[str] = []
    ts = [_counter_target("a", calls), _counter_target("b", calls, deps=("a",))]
    rec = build_targets(ts, tmp_path, Settings())
    assert calls == ["a", "b"] and all(r.status == "ok" and r.reran for r in rec.values())
    man = json.loads((tmp_path / "manifest.json").read_text())
    e = man["targets"]["a"]
    assert set(e["outputs"]) == {"a_data.json", "a.json"} and e["wall_time_s"] >= 0 and e["version"]
    calls.clear()
    rec = build_targets(ts, tmp_path, Settings())
    assert calls == [] and not any(r.reran for r in rec.values())
    # a damaged output makes its target (and the one reading it) rebuild
    (tmp_path / "a_data.json").write_text("{}")
    rec = build_targets(ts, tmp_path, Settings())
    # a rebuilds; b reads a's outputs, which come back byte-identical, so b stays up to date
    assert calls == ["a"] and rec["a"].reran and not rec["b"].reran
    # a changed source file of the code that built it makes a target out of date
    man = Manifest.load(tmp_path)
    e = man.targets["a"]
    assert any(k.startswith("reproduce/") for k in e["code"])
    assert man.up_to_date("a", e["key"])
    e["code"][next(iter(e["code"]))] = "0" * 64
    assert not man.up_to_date("a", e["key"])
    # changed inputs rebuild
    calls.clear()
    build_targets([_counter_target("a", calls, value=2.0)], tmp_path, Settings())
    assert calls == ["a"]


def test_failure_is_recorded_and_dependents_fail(tmp_path):
    def boom(ctx):
        raise RuntimeError("no convergence")

    calls: list[str] = []
    ts = [Target("bad", "bad", "", boom, lambda s: {}), _counter_target("c", calls, deps=("bad",)),
          _counter_target("d", calls)]
    rec = build_targets(ts, tmp_path, Settings())
    assert rec["bad"].status == "failed" and "no convergence" in rec["bad"].error
    assert rec["c"].status == "failed" and rec["d"].status == "ok" and calls == ["d"]
    assert Manifest.load(tmp_path).targets["bad"]["status"] == "failed"


def _kernel_interrupted(ctx):
    """Ctrl-C inside a numba kernel: a SystemError whose context is the interrupt."""
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt:
        raise SystemError("CPUDispatcher(<function jacobian>) returned a result with an exception set")  # noqa: B904 - the implicit context, as numba leaves it


def test_interrupt_inside_a_compiled_kernel_stops_the_build(tmp_path):
    """It was recorded as the target's failure ("FAILED: SystemError") and the next targets were
    built; now the run stops as on any Ctrl-C, and the later target is not built."""
    calls: list[str] = []
    ts = [Target("k", "k", "", _kernel_interrupted, lambda s: {}), _counter_target("d", calls)]
    with pytest.raises(KeyboardInterrupt):
        build_targets(ts, tmp_path, Settings())
    assert calls == []
    man = Manifest.load(tmp_path)  # not recorded as failed (nor done): as interrupted while building
    assert man.targets.get("k", {}).get("status", "building") == "building" and not man.up_to_date("k", "")


def test_interrupt_inside_a_compiled_kernel_stops_a_sweep_point():
    """A sweep point records any failure and goes on, but an interrupt inside a kernel stops it."""
    from flutterswim.sweep.point import timed

    with pytest.raises(KeyboardInterrupt):
        timed(_kernel_interrupted, None)
    assert timed(lambda task: 1 / 0, None)[1].startswith("ZeroDivisionError")


SCRIPT = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    from flutterswim.reproduce.io import write_json
    from flutterswim.reproduce.targets import Outcome, Settings, Target, build_targets

    def fast(ctx):
        write_json(ctx.path("fast_data.json"), {"v": 1})
        return Outcome()

    def slow(ctx):
        from flutterswim._paths import atomic_path
        with atomic_path(ctx.path("slow_data.json")) as tmp:
            tmp.write_text("partial")
            print("slow started", flush=True)
            time.sleep(60)
        return Outcome()

    build_targets([Target("fast", "", "", fast, lambda s: {}, data=("fast_data.json",)),
                   Target("slow", "", "", slow, lambda s: {}, data=("slow_data.json",))],
                  Path(sys.argv[1]), Settings())
""")


def test_sigkill_loses_no_finished_target(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "slow started"
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait(timeout=30)
    man = Manifest.load(out)  # a valid manifest with the finished target
    assert man.targets["fast"]["status"] == "ok"
    # the target being built records no output hashes (its files are ours, not edits) and is not up to date
    assert man.targets.get("slow", {}).get("status", "building") == "building"
    assert "outputs" not in man.targets.get("slow", {}) and not man.up_to_date("slow", "")
    assert json.loads((out / "fast_data.json").read_text())["v"] == 1
    assert not (out / "slow_data.json").exists()  # never a half-written output under its name
    assert man.up_to_date("fast", man.targets["fast"]["key"])


def test_out_folder_safety(tmp_path):
    from flutterswim.reproduce import reproduce

    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("user data")
    with pytest.raises(ParameterError, match="not a flutterswim (store|reproduce folder)"):
        reproduce(foreign, targets=["table1"])
    assert (foreign / "notes.txt").read_text() == "user data"
    ours = tmp_path / "ours"
    reproduce(ours, targets=["table1"])
    import xarray as xr

    xr.Dataset({"x": ("x", [1.0])}).to_netcdf(ours / "table1_data.nc", engine="h5netcdf")  # no signature
    with pytest.raises(ParameterError, match=r"^output=.*table1_data.nc' exists and was not written by flutterswim"):
        reproduce(ours, targets=["table1"])
    # an output edited after we wrote it keeps our signature (xarray keeps the attributes, a JSON
    # its generator): it was replaced without a word (a review); its hash tells
    edited = tmp_path / "edited"
    reproduce(edited, targets=["table1"])
    f = edited / "table1_data.nc"
    with xr.open_dataset(f, engine="h5netcdf") as ds:
        ds = ds.load()
    ds.attrs["my_note"] = "checked by hand"
    ds.to_netcdf(f, engine="h5netcdf")
    with pytest.raises(ParameterError, match="changed after flutterswim wrote it"):
        reproduce(edited, targets=["table1"])
    with xr.open_dataset(f, engine="h5netcdf") as ds:
        assert ds.attrs["my_note"] == "checked by hand"
    f.unlink()  # deleted: rebuilt
    reproduce(edited, targets=["table1"])
    with xr.open_dataset(f, engine="h5netcdf") as ds:
        assert "my_note" not in ds.attrs
    with pytest.raises(ParameterError, match="unknown"):
        reproduce(tmp_path / "x", targets=["fig99"])
    with pytest.raises(ParameterError, match="mode"):
        reproduce(tmp_path / "y", mode="fast")


def test_cli_exit_codes(tmp_path, capsys):
    from flutterswim.cli import main

    assert main(["reproduce", "--out", str(tmp_path / "r"), "--only", "table1", "--quiet"]) == 0
    assert "1 of 1 targets ok (1 built, 0 up to date)" in capsys.readouterr().out
    t0 = time.perf_counter()
    assert main(["reproduce", "--out", str(tmp_path / "r"), "--only", "table1", "--quiet"]) == 0
    assert time.perf_counter() - t0 < 30
    # the summary says what the rerun did (it said "ok, 0 skipped" either way)
    assert "1 of 1 targets ok (0 built, 1 up to date)" in capsys.readouterr().out
    assert main(["reproduce", "--out", str(tmp_path / "r"), "--trials", str(tmp_path / "none.csv")]) == 2
    (tmp_path / "file").write_text("x")
    assert main(["reproduce", "--out", str(tmp_path / "file")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "none.csv" in err
    with pytest.raises(SystemExit) as exc:
        main(["reproduce", "--out", str(tmp_path / "q"), "--quick", "--full"])
    assert exc.value.code == 2


def test_fig3e_from_a_trials_csv(tmp_path):
    pytest.importorskip("flutterswim.fitting")
    from flutterswim.reproduce import reproduce

    import numpy as np

    rows = ["voltage_V,sample,period_s,advance_mm,lateral_mm"]
    data = {80: [(0.5, 0.30, 1.0), (0.7, 0.34, 1.2)], 85: [(0.40, 0.40, 1.1), (0.44, 0.38, 1.3), (0.36, 0.42, 1.0)]}
    for v, trials in data.items():
        rows += [f"{v},s{i},{p},{a},{lat}" for i, (p, a, lat) in enumerate(trials)]
    csv = tmp_path / "trials.csv"
    csv.write_text("\n".join(rows) + "\n")
    res = reproduce(tmp_path / "r", targets=["fig3e"], trials=csv)
    assert res.records["fig3e"].status == "ok"
    # the count of trials is stated beside the paper's, not scored against it ("agreement -90 %")
    (count,) = [c for c in res.records["fig3e"].outcome.comparisons if c.quantity == "trials"]
    assert count.ok is None and not count.from_paper and "%" not in count.agreement
    html = res.report.read_text()
    assert "Quick build" not in html  # (a figure of data alone: no resolution to be coarse)
    import xarray as xr

    with xr.open_dataset(res.out / "fig3e_data.nc", engine="h5netcdf") as ds:
        assert ds.attrs["data_source"] == "trials" and ds.attrs["Conventions"].startswith("CF-")
        assert ds["voltage"].values.tolist() == list(data) and ds["voltage"].attrs["units"] == "V"
        for k, v in enumerate(data):
            x = np.array(data[v])
            assert int(ds["n_trials"][k]) == len(x)
            for j, (name, unit) in enumerate((("period", "s"), ("advance", "mm"), ("lateral", "mm"))):
                assert ds[f"{name}_mean"].attrs["units"] == ds[f"{name}_sem"].attrs["units"] == unit
                assert float(ds[f"{name}_mean"][k]) == pytest.approx(x[:, j].mean(), rel=1e-12)
                assert float(ds[f"{name}_sem"][k]) == pytest.approx(x[:, j].std(ddof=1) / np.sqrt(len(x)), rel=1e-12)



def test_report_counts_only_rows_compared_with_the_paper(tmp_path):
    """The report counted every row with an ok among the agreements with the paper, also a
    simulation checked against our own periodic orbit (its "paper" column our number): only rows
    against a value or statement printed in the paper count now; the others say ours only."""
    from flutterswim.reproduce.report import write_report
    from flutterswim.reproduce.targets import TargetRecord, cross_check, verdict

    rows = (compare("a printed value", 2.0, 3.0, rtol=0.1),  # disagrees with the paper
            verdict("a printed statement", "it swims", "it swims", True),  # agrees with it
            cross_check("simulation vs orbit", 1.0, 1.001, rtol=0.01, reference="orbit: 1 s"),
            cross_check("discrete vs continuum", 1.0, 1.5, rtol=0.01, reference="linear theory: 1"),
            compare("a number the paper does not give", None, 4.0))
    assert [c.from_paper for c in rows] == [True, True, False, False, False]
    t = Target("t", "T", "", lambda ctx: None, lambda s: {})
    rec = TargetRecord(t, "ok", True, 0.0, Outcome("ok", rows), mode="quick")
    html = write_report(tmp_path, {"t": rec}, "quick").read_text()
    assert "Comparisons with the paper: 1 agree, 1 disagree." in html
    assert "1 of their 2 checks within tolerance" in html
    assert "<td>1 / 2</td><td>1 / 2</td>" in html  # per target: paper 1 of 2, ours only 1 of 2
    assert html.count('<span class="na">ours only</span> (') == 3


def test_every_data_output_is_netcdf():
    """Table 1, the paper's orbit and Fig. 3e wrote JSON (no units, xarray cannot open it); the
    outcome <name>.json files are bookkeeping, not data."""
    from flutterswim.reproduce import TARGETS

    data = [f for t in TARGETS for f in t.data]
    assert {"table1_data.nc", "paper_orbit.nc", "fig3e_data.nc"} <= set(data)
    assert all(f.endswith(".nc") for f in data), data


def test_a_bad_trials_csv_is_refused_before_building(tmp_path, capsys):
    """A trials CSV without data rows was found only by the last target (Fig. 3e), after every
    other target had been built (80 s in quick mode), and the run exited 1; it is bad input:
    one line, exit 2, nothing built."""
    pytest.importorskip("flutterswim.fitting")
    from flutterswim.cli import main

    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n")
    out = tmp_path / "r"
    assert main(["reproduce", "--out", str(out), "--only", "table1", "fig3e", "--trials", str(bad), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "bad.csv" in err and "Traceback" not in err and err.count("\n") == 1
    assert not out.exists()

@pytest.mark.slow
def test_quick_run_end_to_end(tmp_path):
    """The whole ``--quick`` run through the CLI: every target ok, videos decodable, report written."""
    out = tmp_path / "q"
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "flutterswim", "reproduce", "--out", str(out), "--quick", "--quiet"],
                          capture_output=True, text=True, timeout=900)
    wall = time.perf_counter() - t0
    assert proc.returncode == 0, proc.stderr
    man = json.loads((out / "manifest.json").read_text())
    from flutterswim.reproduce import TARGETS

    assert {t.name for t in TARGETS} <= set(man["targets"])
    assert all(e["status"] in ("ok", "skipped") for e in man["targets"].values())
    import imageio_ffmpeg

    for v in ("video_s4.mp4", "video_s5.mp4"):
        frames = imageio_ffmpeg.count_frames_and_secs(str(out / v))[0]
        assert frames > 50
    print(f"--quick end to end: {wall:.1f} s")


def test_report_keeps_targets_of_earlier_runs(tmp_path):
    """``--only a`` then ``--only b``: the report showed b alone, though a's files and manifest
    entry stayed in the folder; now it shows both, a marked as built by an earlier run."""
    from flutterswim.reproduce import reproduce

    reproduce(tmp_path / "r", targets=["table1"])
    res = reproduce(tmp_path / "r", targets=["b_readings"])
    html = res.report.read_text()
    assert 'id="table1"' in html and 'id="b_readings"' in html
    assert html.count("built by an earlier run") == 1
    assert list(res.records) == ["b_readings"]  # this run's own records (its exit status)


def test_mode_is_per_target_and_a_quick_build_is_rebuilt_for_full(tmp_path):
    """A folder built quick, then one target --full: that target is rebuilt (even when its
    inputs do not depend on the mode), the manifest and the report say the folder is mixed and
    name the quick builds, not "full" for all; a --full run of all then rebuilds the rest."""
    from flutterswim.reproduce.report import write_report
    from flutterswim.reproduce.targets import with_earlier

    calls: list[str] = []
    ts = [_counter_target(n, calls) for n in ("a", "b", "c")]
    build_targets(ts, tmp_path, Settings("quick"))
    calls.clear()
    rec = build_targets(ts[2:], tmp_path, Settings("full"))
    assert calls == ["c"] and rec["c"].reran and rec["c"].mode == "full"
    run = json.loads((tmp_path / "manifest.json").read_text())["run"]
    assert run["mode"] == "mixed" and run["quick_targets"] == ["a", "b"] and run["full_targets"] == ["c"]
    assert run["mode_summary"] == "mixed: c full; the other 2 quick" and run["this_run_mode"] == "full"
    html = write_report(tmp_path, with_earlier(ts, tmp_path, rec), "full").read_text()
    assert "Mode <b>mixed: c full; the other 2 quick</b> (this run: full)" in html
    # (these targets' inputs do not depend on the mode: no "coarse resolution" note on them, which a
    # figure of data alone had carried; a target whose inputs do depend on it has the note)
    assert html.count("Quick build:") == 0 and html.count('class="mode-quick">quick<') == 2
    coarse = Target("d", "d", "", ts[0].build, lambda s: {"step": 0.5 if s.quick else 0.1}, data=("a_data.json",))
    (tmp_path / "d").mkdir()
    rec_d = build_targets([coarse], tmp_path / "d", Settings("quick"))
    assert write_report(tmp_path / "d", rec_d, "quick").read_text().count("Quick build:") == 1
    calls.clear()
    rec = build_targets(ts, tmp_path, Settings("full"))
    assert calls == ["a", "b"] and not rec["c"].reran  # c is a full build already
    assert json.loads((tmp_path / "manifest.json").read_text())["run"]["mode"] == "full"
    html = write_report(tmp_path, rec, "full").read_text()
    assert "Mode <b>full</b>" in html and "Quick build" not in html
    calls.clear()
    rec = build_targets(ts, tmp_path, Settings("quick"))  # a full build serves --quick: not replaced
    assert calls == [] and all(r.mode == "full" and not r.reran for r in rec.values())
    assert json.loads((tmp_path / "manifest.json").read_text())["run"]["mode"] == "full"


def test_reproduce_rebuilds_a_quick_target_for_full(tmp_path):
    from flutterswim.reproduce import reproduce

    reproduce(tmp_path / "r", targets=["table1"])
    res = reproduce(tmp_path / "r", targets=["table1"], mode="full")
    assert res.records["table1"].reran and res.records["table1"].mode == "full"
    assert Manifest.load(tmp_path / "r").targets["table1"]["mode"] == "full"
    assert "Mode <b>full</b>" in res.report.read_text()


def test_a_full_build_whose_inputs_depend_on_the_mode_serves_a_quick_run(tmp_path):
    """A target whose inputs differ between the modes (a grid step), built --full: a quick run
    keeps it (it had rebuilt it coarser, replacing the full results), and reports it as full;
    changed full inputs still rebuild it."""
    calls: list[str] = []

    def build(ctx):
        calls.append("g")
        write_json(ctx.path("g_data.json"), {"step": ctx.settings.mode})
        return Outcome("ok", (compare("x", 1.0, 1.0, rtol=0.1),))

    step = {"full": 0.1}
    g = Target("g", "g", "", build, lambda s: {"step": step["full"] if s.mode == "full" else 1.0},
               data=("g_data.json",))
    build_targets([g], tmp_path, Settings("full"))
    calls.clear()
    rec = build_targets([g], tmp_path, Settings("quick"))
    assert calls == [] and rec["g"].mode == "full" and not rec["g"].reran
    assert json.loads((tmp_path / "g_data.json").read_text())["step"] == "full"
    step["full"] = 0.05  # the full build is no longer what --full would make: rebuilt, quick
    rec = build_targets([g], tmp_path, Settings("quick"))
    assert calls == ["g"] and rec["g"].mode == "quick"
