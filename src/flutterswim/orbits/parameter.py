"""A named continuation parameter: read and set any physical or dimensionless parameter.

Names: any field of :class:`Parameters` that enters the dynamics (l, b, B, tau, kappa_E, mu; not
the half thickness a, which the drag does not hold: B carries the thickness) or of :class:`Groups`
(eta_par, eta_perp, chi), and ``kappa_E_ratio`` (kappa_E relative to the base set's, as on
the paper's Fig. 4b axis). For physical parameters, eta_par, eta_perp and chi are changed
through the quantity that carries them alone: chi through kappa_E, eta_par and eta_perp
through the drag coefficients by mu at fixed b (both together) -- so only ``eta_perp`` and
``chi`` are offered for Parameters; for Groups, eta_par and eta_perp are independent.
"""

from __future__ import annotations

from dataclasses import dataclass

from .._validate import ParameterError
from ..params import LONG_NAMES, UNITS, Groups, Parameters

__all__ = ["Axis"]

_PHYSICAL = ("l", "b", "B", "tau", "kappa_E", "mu", "kappa_E_ratio", "chi", "eta_perp")
_GROUPS = ("eta_par", "eta_perp", "chi", "kappa_E_ratio")


@dataclass(frozen=True)
class Axis:
    """The parameter ``name`` of the base set ``base``."""

    base: Parameters | Groups
    name: str

    def __post_init__(self) -> None:
        allowed = _PHYSICAL if isinstance(self.base, Parameters) else _GROUPS
        if not isinstance(self.base, (Parameters, Groups)):
            raise ParameterError(f"params={self.base!r} must be flutterswim.Parameters or flutterswim.Groups")
        if self.name == "a" and isinstance(self.base, Parameters):
            raise ParameterError("parameter='a' (the ribbon's half thickness) does not enter the dynamics: the drag "
                                 "holds the half width b alone, and B the thickness; choose one of "
                                 + ", ".join(allowed))
        if self.name not in allowed:
            raise ParameterError(f"parameter={self.name!r} is not a continuation parameter here; "
                                 f"choose one of {', '.join(allowed)}")

    @property
    def positive(self) -> bool:
        """Only positive values are physical (lengths, moduli, times, viscosities, eta's); the
        field's kappa_E, chi and kappa_E_ratio take either sign (the swimming direction)."""
        return self.name not in ("kappa_E", "chi", "kappa_E_ratio")

    @property
    def units(self) -> str:
        return UNITS[self.name]

    @property
    def long_name(self) -> str:
        return LONG_NAMES[self.name]

    def value(self, params: Parameters | Groups | None = None) -> float:
        p = self.base if params is None else params
        if self.name == "kappa_E_ratio":
            num = p.chi if isinstance(p, Groups) else p.kappa_E
            den = self.base.chi if isinstance(self.base, Groups) else self.base.kappa_E
            return float(num / den)
        if isinstance(p, Parameters) and self.name in ("chi", "eta_perp"):
            return float(getattr(p, self.name))
        return float(getattr(p, self.name))

    def at(self, value: float) -> Parameters | Groups:
        """The base set with this parameter at ``value`` (validated as the constructors do)."""
        b = self.base
        v = float(value)
        if self.name == "kappa_E_ratio":
            return b.replace(chi=b.chi * v) if isinstance(b, Groups) else b.replace(kappa_E=b.kappa_E * v)
        if isinstance(b, Parameters) and self.name == "chi":
            return b.replace(kappa_E=v / b.l)
        if isinstance(b, Parameters) and self.name == "eta_perp":
            return b.replace(mu=b.mu * v / b.eta_perp)
        return b.replace(**{self.name: v})
