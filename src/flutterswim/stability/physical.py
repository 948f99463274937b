"""Linear stability in physical units for a :class:`flutterswim.params.Parameters` set.

Time unit tau: growth rate = Re omega / tau [1/s], frequency = Im omega / (2 pi tau) [Hz].
The critical field is kappa_E,cr = chi_cr(eta_perp) / l [1/m]; eta_perp depends on l, b, B,
tau, mu only, so the critical value does not depend on the kappa_E stored in the parameters.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .._validate import ParameterError
from ..params import Parameters
from .leading import leading_eigenvalue
from .neutral import critical_chi

__all__ = ["PhysicalStability", "physical_stability"]


@dataclass(frozen=True)
class PhysicalStability:
    """omega: leading eigenvalue [1/tau]; growth_rate [1/s]; frequency [Hz] (of the oscillation,
    Im omega/(2 pi tau)); critical_kappa_E [1/m] (+-, onset of flutter; NaN if none below
    chi_max/l); critical_frequency [Hz] at onset; eta_perp, chi: groups; unstable: Re omega > 0."""

    omega: complex
    growth_rate: float
    frequency: float
    critical_kappa_E: float
    critical_frequency: float
    eta_perp: float
    chi: float

    @property
    def unstable(self) -> bool:
        return self.growth_rate > 0.0


def physical_stability(params: Parameters, *, chi_max: float = 1e4) -> PhysicalStability:
    """Growth rate, frequency and critical kappa_E of the straight state for ``params``."""
    if not isinstance(params, Parameters):
        raise ParameterError(f"params={params!r} must be a flutterswim.Parameters instance")
    g = params.groups
    try:
        om = leading_eigenvalue(g.chi, g.eta_perp).omega
    except ParameterError as exc:  # (named by the groups: say which parameters make them)
        raise ParameterError(f"params (kappa_E={params.kappa_E!r}, B={params.B!r}, tau={params.tau!r}, "
                             f"mu={params.mu!r}) give {exc}") from None
    chi_cr, beta_cr = critical_chi(g.eta_perp, chi_max=chi_max)
    tau = params.tau
    return PhysicalStability(
        omega=om,
        growth_rate=om.real / tau,
        frequency=abs(om.imag) / (2 * math.pi * tau),
        critical_kappa_E=chi_cr / params.l,
        critical_frequency=beta_cr / (2 * math.pi * tau),
        eta_perp=g.eta_perp,
        chi=g.chi,
    )
