"""One call that produces the paper's stability figure panels and data files."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._validate import ParameterError, positive
from ..params import PAPER, Parameters
from .modes import animate_mode, bifurcation, eigenmodes
from .neutral import neutral_curve
from .plots import plot_bifurcation, plot_map, plot_modes
from .stability_map import stability_map

__all__ = ["StabilityFigures", "stability_figures"]

#: Largest chi of the map and of the chi bifurcation plot.
CHI_MAX = 130.0


@dataclass(frozen=True)
class StabilityFigures:
    """Paths of the written files: map (NetCDF, or None without h5py) and PNG/GIF figures."""

    map_netcdf: Path | None
    map_png: Path
    bifurcation_png: Path
    modes_png: Path
    mode_gif: Path


def stability_figures(out_dir, *, params: Parameters = PAPER, step: float = 0.1,
                      netcdf: bool = True, progress: bool = False, dtype: str = "float64") -> StabilityFigures:
    """Map over [0,350]x[-130,130] at ``step`` with the neutral curve and the operating point of
    ``params`` (default: the paper's), bifurcation plots and the first two eigenmodes there,
    plus a GIF of mode 1. The map NetCDF is compressed (``dtype="float32"`` halves it); every
    file is written atomically. The output folder and the grid size are checked first."""
    from .._paths import check_files_in, check_output_dir

    step = positive("step", step)
    # the chi bifurcation plot runs over (0, 130] at this step: it needs two values
    if step > CHI_MAX / 2:
        raise ParameterError(f"step={step!r} is too large; at most {CHI_MAX / 2:g} (the bifurcation plot in chi "
                             f"runs over (0, {CHI_MAX:g}] and needs at least two values)")
    if dtype not in ("float64", "float32"):
        raise ParameterError(f"dtype={dtype!r} is not allowed; use 'float64' or 'float32'")
    out = check_output_dir(out_dir, what="out_dir")
    names = ("stability_map.nc", "stability_map.png", "bifurcation.png", "eigenmodes.png", "mode1.gif")
    from .stability_map import MAP_TITLE

    check_files_in(out, names, what="out_dir", kinds={"stability_map.nc": MAP_TITLE})  # before computing
    from ..defaults import MAX_MAP_POINTS
    from .stability_map import CHI_RANGE, ETA_RANGE

    # (stability_map's grid, which it checks too, but after the folder would be made)
    n_map = (float(np.ptp(ETA_RANGE)) / step + 1.5) * (float(np.ptp(CHI_RANGE)) / step + 1.5)
    if n_map > MAX_MAP_POINTS:  # before the folder is made (a refused grid left an empty one)
        raise ParameterError(f"step={step!r} gives a map of {n_map:.3g} points; at most {MAX_MAP_POINTS} "
                             "(flutterswim.defaults.MAX_MAP_POINTS)")
    out.mkdir(exist_ok=True)  # (its parent exists: check_output_dir)
    from ..simulate import single_blas_thread

    with single_blas_thread():  # small dense eigenproblems: BLAS threads only add overhead
        return _figures(out, params, step, netcdf, progress, dtype)


def _figures(out: Path, params: Parameters, step: float, netcdf: bool, progress: bool, dtype: str):
    from .._paths import atomic_path, mark_gif

    g = params.groups
    smap = stability_map(step=step, progress=progress)
    nc = neutral_curve(step=step)
    nc_path = None
    if netcdf:
        try:
            import h5py  # noqa: F401  (h5netcdf's HDF5 backend)
        except ImportError:
            nc_path = None
        else:
            nc_path = out / "stability_map.nc"
            smap.save(nc_path, dtype=dtype)
    plot_map(smap, neutral=nc, path=out / "stability_map.png", operating_point=(g.eta_perp, g.chi),
             operating_label="operating point" if params != PAPER else "paper's operating point")
    b1 = bifurcation(parameter="chi", values=np.arange(step, CHI_MAX + step / 2, step), fixed=g.eta_perp)
    b2 = bifurcation(parameter="eta_perp", values=np.arange(step, 350.0 + step / 2, step), fixed=g.chi)
    plot_bifurcation([b1, b2], path=out / "bifurcation.png")
    modes = eigenmodes(g.chi, g.eta_perp)
    plot_modes(modes, path=out / "eigenmodes.png")
    with atomic_path(out / "mode1.gif") as tmp:
        animate_mode(modes[0], tmp)
        mark_gif(tmp)
    return StabilityFigures(nc_path, out / "stability_map.png", out / "bifurcation.png",
                            out / "eigenmodes.png", out / "mode1.gif")
