"""The list of targets: every model figure and table of the paper, in build order."""

from __future__ import annotations

from . import figures_fitting as ff
from . import figures_model as fm
from . import figures_stability as fs
from . import figures_steering as fst
from .targets import Target

__all__ = ["TARGETS", "select"]

def _src(label: str, panel: str, number: str) -> str:
    """Where a figure stands in the paper's LaTeX source: its label, the panel, and the number the
    source gives it (figures counted in source order, the equilibrium shapes fig:exp_stat as 4).
    The targets' titles keep the numbering of the issue that specified them, one lower from
    fig:model on."""
    return f"\\ref{{{label}}}" + (f", panel{'s' if '-' in panel else ''} {panel}" if panel else "") + f": Fig. {number} in the source's numbering"


TARGETS: tuple[Target, ...] = (
    Target("table1", "Table 1: model parameters and the derived groups",
           "Model parameters for the selected representative experiment as measured or determined by the "
           "optimization procedure.", fs.build_table1, fs.table1_params, data=("table1_data.nc",), source=r"\ref{MOD:SIM:tab:parameters}: Table 1 in the source too"),
    Target("b_readings", "Two readings of b in ln(2l/b)",
           "mu_par = 4 pi mu/(2 ln(2l/b) - 1), mu_perp = 4 pi mu/ln(2l/b) for semi-axes a, b; the table gives the "
           "width 2b. 'a critical value of kappa_E,cr/kappa_E,fit ~ 0.65'.",
           fs.build_b_readings, fs.b_params, figures=("b_readings.png",), data=("b_readings.nc",)),
    Target("fig6a", "Fig. 6a: stability map",
           "Stability map in the eta_perp - chi parameters plane. In the flutter regions, the swimmer is sketched "
           "according to the swimming direction as determined by the sign of chi.",
           fs.build_fig6a, fs.fig6a_params, figures=("fig6a.png",), data=("fig6a_map.nc", "fig6a_neutral.nc"), source=_src("fig:stability", "a", "7a")),
    Target("fig6b", "Fig. 6b: bifurcation plots",
           "Bifurcation plots varying one parameter at a time, either chi or eta_perp (real part blue, imaginary "
           "part orange, of the leading eigenvalue).", fs.build_fig6b, fs.fig6b_params,
           figures=("fig6b.png",), data=("fig6b.nc",), source=_src("fig:stability", "b", "7b")),
    Target("fig6cd", "Fig. 6c-d: first and second eigenmodes",
           "First and second eigenmode, corresponding to the eigenvalue with largest and second largest real "
           "part. The second eigenvalue has negative real part.", fs.build_fig6cd, fs.fig6cd_params,
           figures=("fig6cd.png",), data=("fig6cd.nc",), source=_src("fig:stability", "c-d", "7c-d")),
    Target("paper_run", "The representative run: onset to limit cycle",
           "Numerical simulation for the fitted parameters of Table 1, straight filament inclined by 0.01 degree.",
           fm.build_paper_run, fm.run_params, data=("paper_run.nc", "paper_orbit.nc")),
    Target("fig4b", "Fig. 4b: the kappa_E sweep (branch of strokes)",
           "Swimming descriptors (advancement per cycle and shape change period) for different values of kappa_E. "
           "The red parts correspond to self-intersecting shape changes. Sharp transition at ~0.65.",
           fm.build_fig4b, fm.fig4b_params, figures=("fig4b.png",), data=("fig4b.nc",), source=_src("fig:model", "b", "5b")),
    Target("fig4c", "Fig. 4c: from onset to the limit cycle",
           "In magenta the trajectory of the filament's tip and in shades of green its configurations over one "
           "cycle of shape change near the onset of the dynamics and at the limit cycle.",
           fm.build_fig4c, fm.fig4c_params, figures=("fig4c.png",), data=("fig4c.nc",), deps=("paper_run",), source=_src("fig:model", "c", "5c")),
    Target("fig4de", "Fig. 4d-e: kymographs near onset and at the limit cycle",
           "Kymographs near the onset of swimming and at the limit cycle; the increase in amplitude is "
           "accompanied by the increase in the average swimmer's velocity (yellow arrow).",
           fm.build_fig4de, fm.fig4de_params, figures=("fig4de.png",), data=("fig4de.nc",), deps=("paper_run",), source=_src("fig:model", "d-e", "5d-e")),
    Target("video_s4", "Video S4: the virtual swimmer",
           "Virtual swimmer from instability onset to steady oscillations.", fm.build_video_s4,
           fm.video_s4_params, figures=("video_s4_poster.png",), videos=("video_s4.mp4",), deps=("paper_run",)),
    Target("fig5", "Fig. 5: control of the swimmer trajectory",
           "By rotating the electric field as described by the time series in the lower panel, it is possible to "
           "drive the robotic swimmer along a circular trajectory (average trajectory in yellow).",
           fst.build_fig5, fst.fig5_params, figures=("fig5.png",), data=("fig5.nc", "fig5_run.nc"), source=_src("fig:trajectories", "", "6")),
    Target("video_s5", "Video S5: steering the virtual swimmer",
           "The swimmer is directed along a circular trajectory by changing the stimulus direction at constant "
           "angular velocity.", fst.build_video_s5, fst.video_s5_params, figures=("video_s5_poster.png",),
           videos=("video_s5.mp4",), deps=("fig5",)),
    Target("fig3e", "Fig. 3e: experimental descriptors against voltage",
           "Average advancement and period per cycle as measured from the experiments (mean and standard error "
           "over the trials at each potential).", ff.build_fig3e, ff.fig3e_params,
           figures=("fig3e.png",), data=("fig3e_data.nc",), source=_src("fig:exp", "e", "3e")),
)


def select(names: list[str] | None) -> list[Target]:
    """The targets named (with the targets they depend on), in build order; all when None."""
    from .._validate import ParameterError

    if not names:
        return list(TARGETS)
    by = {t.name: t for t in TARGETS}
    unknown = [n for n in names if n not in by]
    if unknown:
        raise ParameterError(f"targets={unknown} are unknown; choose from {sorted(by)}")
    want = set(names)
    changed = True
    while changed:
        changed = False
        for n in list(want):
            for d in by[n].deps:
                if d not in want:
                    want.add(d)
                    changed = True
    return [t for t in TARGETS if t.name in want]
