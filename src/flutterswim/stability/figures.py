"""One call that produces the paper's stability figure panels and data files."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validate import positive
from ..params import PAPER, Parameters
from .modes import animate_mode, bifurcation, eigenmodes
from .neutral import neutral_curve
from .plots import plot_bifurcation, plot_map, plot_modes
from .stability_map import stability_map

__all__ = ["StabilityFigures", "stability_figures"]


@dataclass(frozen=True)
class StabilityFigures:
    """Paths of the written files: map (NetCDF, or None without h5py) and PNG/GIF figures."""

    map_netcdf: Path | None
    map_png: Path
    bifurcation_png: Path
    modes_png: Path
    mode_gif: Path


def stability_figures(out_dir, *, params: Parameters = PAPER, step: float = 0.1,
                      netcdf: bool = True) -> StabilityFigures:
    """Map over [0,350]x[-130,130] at ``step`` with the neutral curve, bifurcation plots and
    the first two eigenmodes at ``params`` (default: the paper's), plus a GIF of mode 1."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    step = positive("step", step)
    g = params.groups
    smap = stability_map(step=step)
    nc = neutral_curve(step=step)
    nc_path = None
    if netcdf:
        try:
            import h5py  # noqa: F401  (h5netcdf's HDF5 backend)
        except ImportError:
            nc_path = None
        else:
            nc_path = out / "stability_map.nc"
            smap.save(nc_path)
    plot_map(smap, neutral=nc, path=out / "stability_map.png")
    b1 = bifurcation(parameter="chi", values=np.arange(step, 130.0 + step / 2, step), fixed=g.eta_perp)
    b2 = bifurcation(parameter="eta_perp", values=np.arange(step, 350.0 + step / 2, step), fixed=g.chi)
    plot_bifurcation([b1, b2], path=out / "bifurcation.png")
    modes = eigenmodes(g.chi, g.eta_perp)
    plot_modes(modes, path=out / "eigenmodes.png")
    animate_mode(modes[0], out / "mode1.gif")
    return StabilityFigures(nc_path, out / "stability_map.png", out / "bifurcation.png",
                            out / "eigenmodes.png", out / "mode1.gif")
