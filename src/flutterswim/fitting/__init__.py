"""Parameter identification: (B, tau, kappa_E) from descriptors with uncertainty.

- :func:`fit` (:class:`FitResult`): SEM-weighted least squares in identifiable coordinates
  (default) or the paper's cost and bounds; covariance, correlations, identifiability card,
  profiles, bootstrap
- :func:`fit_voltages`: several voltages at once, kappa_E proportional to the voltage
- :func:`read_trials`, :func:`summarise`, :func:`plot_trials`: the trials CSV and Fig. 3e
- :class:`DescriptorModel`: descriptors from periodic orbits; :class:`LocalSurrogate`
"""

from .data import Summary, Trials, plot_trials, read_trials, summarise
from .fit import PAPER_GUESS, FitResult, fit, paper_cost
from .model import DescriptorModel, NotSwimming, to_identifiable, to_physical
from .surrogate import LocalSurrogate
from .voltages import fit_voltages

__all__ = ["DescriptorModel", "FitResult", "LocalSurrogate", "NotSwimming", "PAPER_GUESS", "Summary", "Trials",
           "fit", "fit_voltages", "paper_cost", "plot_trials", "read_trials", "summarise", "to_identifiable", "to_physical"]
