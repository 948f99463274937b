"""Strokes as periodic orbits of the shape dynamics: Newton shooting, Floquet multipliers,
the discrete model's linear stability and Hopf point, the Hopf normal form, and
pseudo-arclength continuation of the branch.

- :func:`periodic_orbit`: one stroke (:class:`PeriodicOrbit`)
- :func:`continue_orbits`: the branch from the Hopf point (:class:`Branch`, ``.to_dataset()``)
- :func:`hopf_point`, :func:`normal_form`, :func:`discrete_spectrum`, :func:`leading_pair`
"""

from .continuation import Branch, continue_orbits
from .linear import HopfPoint, discrete_spectrum, hopf_point, leading_pair
from .normal_form import NormalForm, normal_form
from .periodic import OrbitNotFound, PeriodicOrbit, periodic_orbit

__all__ = ["Branch", "HopfPoint", "NormalForm", "OrbitNotFound", "PeriodicOrbit", "continue_orbits",
           "discrete_spectrum", "hopf_point", "leading_pair", "normal_form", "periodic_orbit"]
