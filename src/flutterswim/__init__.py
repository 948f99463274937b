"""flutterswim: soft active filaments that swim by flutter instability."""

from importlib.metadata import PackageNotFoundError, version

from ._validate import ParameterError
from .field import Constant, Field, Piecewise
from .initial import InitialState
from .params import PAPER, Groups, Parameters, SlendernessWarning, preset
from .result import SimulationResult, load
from .simulate import simulate

_LAZY = {  # imported on first use: the stability package loads numba, plotting matplotlib
    **{name: "flutterswim.stability"
       for name in ("leading_eigenvalue", "neutral_curve", "physical_stability", "spectrum",
                    "stability_figures", "stability_map")},
    **{name: "flutterswim.analysis"
       for name in ("Track", "Cycles", "Descriptors", "describe", "detect_cycles", "self_intersections")},
    **{name: "flutterswim.plotting"
       for name in ("plot_ghosts", "plot_swimmer", "plot_descriptors", "plot_kymographs", "plot_summary",
                    "animate")},
    "run_to_limit_cycle": "flutterswim.limit_cycle",
    "fit": "flutterswim.fitting",
    "periodic_orbit": "flutterswim.orbits",
    "continue_orbits": "flutterswim.orbits",
    # not "sweep": importing flutterswim.sweep binds that name to the subpackage
    "run_sweep": ("flutterswim.sweep", "sweep"),
    "open_sweep": "flutterswim.sweep",
}
#: Subpackages reached as ``fs.tracking.render`` without importing them first (not "sweep": see above)
_SUBPACKAGES = ("tracking", "steering", "fitting", "orbits", "stability", "analysis", "plotting")


def __getattr__(name: str):
    if name in _LAZY or name in _SUBPACKAGES:
        import importlib

        if name in _SUBPACKAGES:
            return importlib.import_module(f"{__name__}.{name}")
        module, attr = _LAZY[name] if isinstance(_LAZY[name], tuple) else (_LAZY[name], name)
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'flutterswim' has no attribute {name!r}")

try:
    __version__ = version("flutterswim")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

__all__ = [
    "PAPER",
    "Constant",
    "Field",
    "Groups",
    "InitialState",
    "ParameterError",
    "Parameters",
    "Piecewise",
    "SimulationResult",
    "SlendernessWarning",
    "__version__",
    "leading_eigenvalue",
    "run_to_limit_cycle",
    "fit",
    "periodic_orbit",
    "continue_orbits",
    "run_sweep",
    "open_sweep",
    "Track",
    "Cycles",
    "Descriptors",
    "describe",
    "detect_cycles",
    "self_intersections",
    "plot_ghosts",
    "plot_swimmer",
    "plot_descriptors",
    "plot_kymographs",
    "plot_summary",
    "animate",
    "load",
    "neutral_curve",
    "physical_stability",
    "preset",
    "simulate",
    "spectrum",
    "stability_figures",
    "stability_map",
]
