"""Model parameters: physical (SI units) and dimensionless groups.

Scalings follow the paper: length by l, time by tau, forces by B/l^2.
The groups are (eq. MOD:eq:nondim_groups)

    eta_par = mu_par l^4 / (B tau),  eta_perp = mu_perp l^4 / (B tau),  chi = kappa_E l,

with the Koens-Lauga resistive coefficients of a slender ribbon of elliptic
cross-section, semi-axes a << b << l (eq. MOD:eq:resistive_coefficients):

    mu_par = 4 pi mu / (2 ln(2l/b) - 1),   mu_perp = 4 pi mu / ln(2l/b).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass, replace

from ._validate import ParameterError, finite, positive

__all__ = ["Groups", "Parameters", "SlendernessWarning", "PAPER", "preset", "UNITS", "LONG_NAMES"]

#: CF units (UDUNITS spelling) of the physical parameters, the groups and kappa_E_ratio: the one
#: table that runs, sweeps, branches and reproduce's data files label them with.
UNITS = {"l": "m", "a": "m", "b": "m", "B": "N m2", "tau": "s", "kappa_E": "1/m", "mu": "Pa s",
         "eta_par": "1", "eta_perp": "1", "chi": "1", "kappa_E_ratio": "1"}
#: Their long names.
LONG_NAMES = {"l": "filament length", "a": "ribbon half thickness", "b": "ribbon half width",
              "B": "bending stiffness", "tau": "activity relaxation time", "kappa_E": "target curvature",
              "mu": "fluid viscosity", "eta_par": "tangential drag group eta_par",
              "eta_perp": "normal drag group eta_perp", "chi": "activity group chi = kappa_E l",
              "kappa_E_ratio": "kappa_E relative to the base parameter set"}

#: Ratio a/b or b/l above which RFT for a slender ribbon is only a rough guide.
SLENDER_RATIO = 0.2


class SlendernessWarning(UserWarning):
    """Geometry is not slender enough for resistive-force theory to be accurate."""


@dataclass(frozen=True)
class Groups:
    """Dimensionless groups (eta_par, eta_perp, chi); the solution depends only on these."""

    eta_par: float
    eta_perp: float
    chi: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "eta_par", positive("eta_par", self.eta_par))
        object.__setattr__(self, "eta_perp", positive("eta_perp", self.eta_perp))
        object.__setattr__(self, "chi", finite("chi", self.chi))

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    def replace(self, **changes: float) -> "Groups":
        return replace(self, **changes)


@dataclass(frozen=True)
class Parameters:
    """Physical parameters in SI units.

    l: length [m]; a, b: semi-thickness and semi-width [m]; B: bending stiffness [N m^2];
    tau: activity relaxation time [s]; kappa_E: target curvature [1/m] (its sign sets
    the bending direction); mu: fluid viscosity [Pa s].
    """

    l: float
    a: float
    b: float
    B: float
    tau: float
    kappa_E: float
    mu: float

    def __post_init__(self) -> None:
        for name in ("l", "a", "b", "B", "tau", "mu"):
            object.__setattr__(self, name, positive(name, getattr(self, name)))
        object.__setattr__(self, "kappa_E", finite("kappa_E", self.kappa_E))
        if not self.a <= self.b:
            raise ParameterError(
                f"a={self.a!r} m exceeds b={self.b!r} m; the ribbon needs a <= b (a: half thickness, "
                "b: half width)"
            )
        if not self.b < 0.5 * self.l:
            raise ParameterError(
                f"b={self.b!r} m is a half-width of at least half the length l={self.l!r} m: the body "
                "is not slender and resistive-force theory does not apply; b < l/2 is required "
                "(b << l for accuracy)"
            )
        log = math.log(2.0 * self.l / self.b)
        if 2.0 * log - 1.0 <= 0.0:
            raise ParameterError(
                f"b={self.b!r} m with l={self.l!r} m gives 2 ln(2l/b) - 1 = {2 * log - 1:.3g} <= 0, a "
                f"non-positive tangential drag; resistive-force theory needs b < 2 l e^-0.5 = "
                f"{2 * self.l * math.exp(-0.5):.4g} m and, to be accurate, b << l"
            )
        if self.b / self.l > SLENDER_RATIO or self.a / self.b > SLENDER_RATIO:
            warnings.warn(
                f"geometry a={self.a:.3g} m, b={self.b:.3g} m, l={self.l:.3g} m is not slender "
                f"(a/b={self.a / self.b:.3g}, b/l={self.b / self.l:.3g}; resistive-force theory "
                f"assumes both << 1, here above {SLENDER_RATIO})",
                SlendernessWarning,
                stacklevel=3,
            )

    # --- derived quantities -------------------------------------------------
    @property
    def mu_par(self) -> float:
        """Tangential resistive coefficient [Pa s]."""
        return 4.0 * math.pi * self.mu / (2.0 * math.log(2.0 * self.l / self.b) - 1.0)

    @property
    def mu_perp(self) -> float:
        """Normal resistive coefficient [Pa s]."""
        return 4.0 * math.pi * self.mu / math.log(2.0 * self.l / self.b)

    @property
    def force_scale(self) -> float:
        """B / l^2 [N]."""
        return self.B / self.l**2

    @property
    def groups(self) -> Groups:
        scale = self.l**4 / (self.B * self.tau)
        return Groups(self.mu_par * scale, self.mu_perp * scale, self.kappa_E * self.l)

    @property
    def eta_par(self) -> float:
        return self.groups.eta_par

    @property
    def eta_perp(self) -> float:
        return self.groups.eta_perp

    @property
    def chi(self) -> float:
        return self.kappa_E * self.l

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    def replace(self, **changes: float) -> "Parameters":
        return replace(self, **changes)

    @classmethod
    def from_groups(
        cls,
        eta_par: float,
        eta_perp: float,
        chi: float,
        *,
        l: float = 1.0,
        tau: float = 1.0,
        B: float = 1.0,
        a_over_b: float = 0.021,
    ) -> "Parameters":
        """Build a physical parameter set with the given groups and scales (l, tau, B).

        The ratio eta_perp/eta_par = (2L - 1)/L with L = ln(2l/b) fixes b, which needs
        1 < eta_perp/eta_par < 2; then mu follows from eta_perp.
        """
        g = Groups(eta_par, eta_perp, chi)
        ratio = g.eta_perp / g.eta_par
        if not 1.0 < ratio < 2.0:
            raise ParameterError(
                f"eta_perp/eta_par={ratio:.6g} cannot come from the Koens-Lauga coefficients, which "
                "need 1 < eta_perp/eta_par < 2; use flutterswim.Groups directly for other drag ratios"
            )
        log = 1.0 / (2.0 - ratio)
        b = 2.0 * l * math.exp(-log)
        mu = g.eta_perp * B * tau * log / (4.0 * math.pi * l**4)
        return cls(l=l, a=a_over_b * b, b=b, B=B, tau=tau, kappa_E=g.chi / l, mu=mu)


#: Table "Model parameters for the selected representative experiment", in SI units.
PAPER = Parameters(
    l=3.70e-3,
    a=0.5 * 8.30e-6,
    b=0.5 * 3.96e-4,
    B=1.94e-14,
    tau=0.375,
    kappa_E=19.1e3,
    mu=8.0e-4,
)

_PRESETS = {"paper": PAPER}


def preset(name: str) -> Parameters:
    """Return a named parameter set (``"paper"``)."""
    try:
        return _PRESETS[name]
    except (KeyError, TypeError):  # (TypeError: a list or other unhashable name)
        raise ParameterError(f"preset={name!r} is unknown; choose one of {sorted(_PRESETS)}") from None
