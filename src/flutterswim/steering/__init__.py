"""Steering and path following by turning the field.

- :mod:`.schedules`: rotating, step, ramp and CSV field schedules (and the simulate CLI options)
- :mod:`.turning`: cycle-averaged path and heading, heading lag, turning radius (circle fit)
- :mod:`.reduced`: the unicycle model identified from simulations (U, k, Omega_max, R_min)
- :mod:`.trap`: basin of the swimming state against tilt and field turns
- :mod:`.steer`, :mod:`.control`, :mod:`.path`: closed- and open-loop path following
"""

from .reduced import ReducedModel, identify
from .schedules import Rotation, from_csv, ramp, rotation, step
from .steer import SteerResult, steer
from .turning import cycle_average, describe_turning, fit_circle

__all__ = ["ReducedModel", "Rotation", "SteerResult", "cycle_average", "describe_turning", "fit_circle", "from_csv",
           "identify", "ramp", "rotation", "steer", "step"]
