"""flutterswim: soft active filaments that swim by flutter instability."""

from importlib.metadata import PackageNotFoundError, version

from ._validate import ParameterError
from .params import PAPER, Groups, Parameters, SlendernessWarning, preset

try:
    __version__ = version("flutterswim")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

__all__ = [
    "PAPER",
    "Groups",
    "ParameterError",
    "Parameters",
    "SlendernessWarning",
    "__version__",
    "preset",
]
