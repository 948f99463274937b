"""The self-contained HTML report: every figure embedded (base64 PNG), per target a table of
the paper's statement, our number and the agreement, and the environment (Jinja2). Only rows
compared with the paper (``Comparison.from_paper``) count as agreements with it; the others
are shown as ours only, their checks against our own numbers counted apart."""

from __future__ import annotations

import base64
import os
import platform
import subprocess
import sys
from pathlib import Path

__all__ = ["write_report", "environment"]

_PACKAGES = ("numpy", "scipy", "matplotlib", "xarray", "h5netcdf", "h5py", "numba", "imageio", "imageio-ffmpeg",
             "jinja2", "threadpoolctl")


def environment() -> list[tuple[str, str]]:
    from importlib.metadata import PackageNotFoundError, version

    from .. import __version__

    env = [("flutterswim", __version__)]
    root = Path(__file__).resolve().parents[3]
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                                timeout=5).stdout.strip()
        if commit:
            env.append(("git commit", commit))
    except (OSError, subprocess.SubprocessError):
        pass
    env += [("python", sys.version.split()[0]), ("platform", platform.platform()),
            ("processor", platform.processor() or platform.machine()), ("logical CPUs", str(os.cpu_count()))]
    for p in _PACKAGES:
        try:
            env.append((p, version(p)))
        except PackageNotFoundError:
            env.append((p, "not installed"))
    return env


def _mode_matters(t) -> bool:
    """Whether a target's build depends on --quick / --full (its inputs differ): a figure of data
    alone (fig3e from trials) was still labelled "Quick build: coarse resolution"."""
    from .catalog import TARGETS
    from .targets import Settings

    by_name = {x.name: x for x in TARGETS}
    try:
        if t.params(Settings("quick")) != t.params(Settings("full")):
            return True
    except Exception:  # noqa: BLE001 - unknown: said as before
        return True
    # (a figure drawn from another target's outputs, e.g. fig4c from paper_run's run, is as coarse)
    return any(_mode_matters(by_name[d]) for d in t.deps if d in by_name)


def write_report(out: Path, records: dict, mode: str, *, name: str = "report.html") -> Path:
    """``mode``: this run's; the report gives the folder's (mixed when its targets differ) and
    labels each quick build."""
    import jinja2

    from .. import __version__
    from .._paths import atomic_path
    from .manifest import mode_summary

    rows = []
    for rec in records.values():
        t = rec.target
        imgs = []
        for f in t.figures:
            p = out / f
            if p.is_file():
                imgs.append({"name": f, "data": base64.b64encode(p.read_bytes()).decode("ascii")})
        comps = list(rec.outcome.comparisons)
        paper = [c for c in comps if c.from_paper and c.ok is not None and not c.is_input]
        inputs = [c for c in comps if c.is_input and c.ok is not None]
        ours = [c for c in comps if not c.from_paper and c.ok is not None]
        title = rec.outcome.values.get("title", t.title) if isinstance(rec.outcome.values, dict) else t.title
        rows.append({"name": t.name, "title": title, "caption": t.caption, "status": rec.status, "mode": rec.mode,
                     "mode_matters": _mode_matters(t),
                     "reran": rec.reran, "wall_time": rec.wall_time, "error": rec.error, "images": imgs,
                     "videos": [v for v in t.videos if (out / v).is_file()], "rows": comps,
                     "notes": list(rec.outcome.notes), "files": sorted(rec.outputs.items()),
                     "source": t.source, "disagree": [c.quantity for c in paper if not c.ok],
                     "n_inputs": len(inputs), "n_inputs_ok": sum(c.ok for c in inputs),
                     "n_rows": len(paper), "n_agree": sum(c.ok for c in paper),
                     "n_checks": len(ours), "n_checks_ok": sum(c.ok for c in ours)})
    env = jinja2.Environment(loader=jinja2.PackageLoader("flutterswim.reproduce", "templates"),
                             autoescape=jinja2.select_autoescape(["html", "j2"]), undefined=jinja2.StrictUndefined)
    html = env.get_template("report.html.j2").render(
        generator=f"flutterswim {__version__}", records=rows, run_mode=mode,
        mode=mode_summary({r["name"]: r["mode"] for r in rows if r["status"] == "ok"}),
        n_ok=sum(r["status"] == "ok" for r in rows), n_skipped=sum(r["status"] == "skipped" for r in rows),
        n_failed=sum(r["status"] == "failed" for r in rows), n_reran=sum(r["reran"] for r in rows),
        n_agree=sum(r["n_agree"] for r in rows), n_disagree=sum(r["n_rows"] - r["n_agree"] for r in rows),
        disagree=[(r["title"], q) for r in rows for q in r["disagree"]],
        n_inputs=sum(r["n_inputs"] for r in rows), n_inputs_ok=sum(r["n_inputs_ok"] for r in rows),
        n_checks=sum(r["n_checks"] for r in rows), n_checks_ok=sum(r["n_checks_ok"] for r in rows),
        environment=environment())
    path = out / name
    with atomic_path(path) as tmp:
        tmp.write_text(html, encoding="utf-8")
    return path
