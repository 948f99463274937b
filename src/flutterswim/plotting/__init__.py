"""Figures and animations of swimming filaments (matplotlib/imageio imported lazily)."""

from .animation import animate
from .figures import plot_descriptors, plot_ghosts, plot_kymographs, plot_summary, plot_swimmer

__all__ = ["animate", "plot_descriptors", "plot_ghosts", "plot_kymographs", "plot_summary", "plot_swimmer"]
