"""Reproduction of the paper's model figures: targets, a manifest, and an HTML report.

- :func:`reproduce` (:class:`ReproduceResult`): build every target into a folder, skipping
  the up-to-date ones; ``flutterswim reproduce --out DIR [--quick | --full] [--trials CSV]``
- :mod:`.targets`, :mod:`.manifest`: the engine (inputs, version, wall time, output hashes;
  atomic writes); :mod:`.catalog`: the list of targets; :mod:`.report`: the HTML
"""

from .catalog import TARGETS, select
from .run import ReproduceResult, reproduce
from .targets import Comparison, Outcome, Settings, Target, TargetRecord

__all__ = ["Comparison", "Outcome", "ReproduceResult", "Settings", "TARGETS", "Target", "TargetRecord",
           "reproduce", "select"]
