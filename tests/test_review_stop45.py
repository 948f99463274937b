"""Stop 45: the descriptors figure names the end whose lateral peak-to-peak it draws."""

import dataclasses

import numpy as np
import pytest

import flutterswim as fs


@pytest.fixture(scope="module")
def settled():
    from flutterswim.analysis.track import as_track

    return as_track(fs.simulate(fs.PAPER, 12.0, n_segments=24))


def _flipped(tr):
    """The same swimmer with s counted from the other end."""
    return dataclasses.replace(tr, x=tr.x[:, ::-1], y=tr.y[:, ::-1], s=None, theta=None, kappa=None)


@pytest.mark.parametrize("flip", [False, True])
def test_descriptors_figure_names_the_end_it_draws(settled, flip):
    """The panel had read "tip lateral p-p" for the end s = l, leading or trailing by the run.
    Its legend must name the end whose values it draws: describe's leading and trailing ends
    differ threefold on the paper's stroke, so the named one must match within 2 %."""
    from flutterswim.plotting.figures import plot_descriptors

    tr = _flipped(settled) if flip else settled
    d = fs.describe(tr)
    ax = plot_descriptors(tr).axes[2]
    (line,) = [ln for ln in ax.get_lines() if "lateral p-p" in ln.get_label()]
    label = line.get_label()
    which = "leading" if "leading" in label else "trailing" if "trailing" in label else None
    assert which is not None, label
    assert ("s = 0" in label) == (d.leading_end == ("s=0" if which == "leading" else "s=l")), (label, d.leading_end)
    last = float(np.asarray(line.get_ydata())[-1])
    named = getattr(d, f"{which}_lateral_p2p_mm")
    other = getattr(d, f"{'trailing' if which == 'leading' else 'leading'}_lateral_p2p_mm")
    assert abs(last - named) < 0.02 * named < abs(last - other)


def test_both_tolerances_are_named_as_typed(tmp_path, capsys):
    """`simulate --rtol 1e-13 --atol 1e-14` named its second option `atol=`; each named option
    must be one the command parses."""
    import re

    from flutterswim.cli import build_parser, main

    assert main(["simulate", "--rtol", "1e-13", "--atol", "1e-14", "--out", str(tmp_path / "r.nc")]) == 2
    err = capsys.readouterr().err.strip()
    named = re.findall(r"(--[\w-]+)=", err)
    assert named == ["--rtol", "--atol"], err
    build_parser().parse_args(["simulate"] + [f"{o}=1e-6" for o in named])  # both parse
    assert not (tmp_path / "r.nc").exists()
