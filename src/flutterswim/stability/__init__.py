"""Linear stability of the straight filament aligned with the field (paper section LIN).

Dimensionless problem (s in [0, 1], time in tau): r'''' - kappa'' + eta_perp r_t = 0,
kappa_t + kappa + chi r' = 0, free ends. Entry points:

- :func:`char_f`, :func:`reduced_char`, :func:`quartic_roots`: characteristic function
- :func:`spectrum`: Chebyshev collocation (whole spectrum, no guess)
- :func:`newton_root`, :func:`follow_root`: Newton and root following
- :func:`leading_eigenvalue`, :func:`physical_stability`: omega_max; SI growth rate, frequency,
  critical kappa_E
- :func:`stability_map`, :func:`neutral_curve`, :func:`bifurcation`: maps and curves
- :func:`eigenmodes`, :func:`animate_mode`, and :mod:`.plots`
- :func:`stability_figures`: all panels of the paper's stability figure in one call
"""

from .characteristic import boundary_matrix, char_f, quartic_roots, reduced_char
from .figures import StabilityFigures, stability_figures
from .leading import LeadingEigenvalue, leading_eigenvalue
from .modes import Bifurcation, Eigenmode, animate_mode, bifurcation, eigenmodes, mode_shape
from .neutral import NeutralCurve, critical_chi, neutral_curve
from .newton import PathResult, RootResult, follow_root, newton_root
from .physical import PhysicalStability, physical_stability
from .spectral import Spectrum, spectrum
from .stability_map import StabilityMap, load_map, stability_map

__all__ = [
    "Bifurcation", "Eigenmode", "LeadingEigenvalue", "NeutralCurve", "PathResult", "PhysicalStability",
    "RootResult", "Spectrum", "StabilityMap", "animate_mode", "bifurcation", "boundary_matrix", "char_f",
    "critical_chi", "eigenmodes", "follow_root", "leading_eigenvalue", "load_map", "mode_shape",
    "neutral_curve", "newton_root", "physical_stability", "quartic_roots", "reduced_char", "spectrum",
    "stability_map", "StabilityFigures", "stability_figures",
]
