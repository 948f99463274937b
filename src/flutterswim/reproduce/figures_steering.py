"""Fig. 5 (steering by a field that turns at a constant rate once the stroke is established)
and Video S5. The mean path is a circle of radius U / Omega (U: the stroke's speed from the
periodic orbit, Omega: the field's rotation rate) when the turn is slow."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..params import PAPER
from .figures_model import _scrub
from .figures_stability import _var
from .io import save_figure, write_netcdf
from .targets import Context, Outcome, Settings, compare, cross_check, verdict

__all__ = ["fit_circle", "cycle_average", "build_fig5", "build_video_s5"]


def fit_circle(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Algebraic (Kasa) least-squares circle: x^2 + y^2 + a x + b y + c = 0. Returns (xc, yc, R)."""
    A = np.c_[x, y, np.ones_like(x)]
    (a, b, c), *_ = np.linalg.lstsq(A, -(x * x + y * y), rcond=None)
    xc, yc = -a / 2, -b / 2
    return float(xc), float(yc), float(math.sqrt(xc * xc + yc * yc - c))


def cycle_average(t: np.ndarray, v: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    """Moving average of v over one period (uniform frames): (t at window centres, averages)."""
    dt = float(t[1] - t[0])
    k = max(1, int(round(period / dt)))
    ker = np.ones(k) / k
    avg = np.convolve(v, ker, mode="valid")
    tc = np.convolve(t, ker, mode="valid")
    return tc, avg


def fig5_params(s: Settings) -> dict:
    return {"n_segments": s.pick(24, 48), "rate": s.pick(0.2, 0.1), "start": 10.0, "turns": 1.0,
            "frame_dt": 0.02, "params": PAPER.to_dict()}


def _direction(rate: float, start: float):
    def direction(t: float) -> float:
        return rate * max(0.0, t - start)

    direction.__name__ = f"turn_at_{rate:g}_rad_per_s_after_{start:g}_s"
    return direction


def build_fig5(ctx: Context) -> Outcome:
    import xarray as xr

    from ..field import Field
    from ..orbits import periodic_orbit
    from ..simulate import simulate
    from .plots import plot_fig5

    prm = fig5_params(ctx.settings)
    rate, start = prm["rate"], prm["start"]
    t_end = start + prm["turns"] * 2 * math.pi / rate
    run = simulate(PAPER, t_end, field=Field(direction=_direction(rate, start)), n_segments=prm["n_segments"],
                   frame_dt=prm["frame_dt"])
    run = dataclasses.replace(run, stats=dataclasses.replace(run.stats, wall_time=0.0), settings=_scrub(run.settings))
    if run.status != "completed":
        raise RuntimeError(f"the steering run stopped: {run.message}")
    run.save(ctx.path("fig5_run.nc"))
    orb = periodic_orbit(PAPER, n_segments=prm["n_segments"])
    xc, yc = run.x.mean(axis=1), run.y.mean(axis=1)
    ta, xa = cycle_average(run.t, xc, orb.period)
    _, ya = cycle_average(run.t, yc, orb.period)
    # after a quarter turn the heading lag has settled
    sel = ta > start + 0.25 * 2 * math.pi / rate
    circle = fit_circle(xa[sel], ya[sel])
    rfit = np.hypot(xa[sel] - circle[0], ya[sel] - circle[1])
    predicted = orb.speed / rate
    # heading of the averaged path vs the field direction (lag), in the settled turn
    vx, vy = np.gradient(xa, ta), np.gradient(ya, ta)
    heading = np.unwrap(np.arctan2(vy, vx))
    field_at = np.interp(ta, run.t, run.field_angle)
    lag = np.angle(np.exp(1j * (field_at - heading)))
    lag_mean = float(np.degrees(np.mean(lag[sel])))
    fig = plot_fig5(run, ta, xa, ya, circle, start)
    save_figure(fig, ctx.path("fig5.png"))
    ds = xr.Dataset({
        "centroid_x": _var(("t",), xc, "m", "centroid x"), "centroid_y": _var(("t",), yc, "m", "centroid y"),
        "field_angle": _var(("t",), run.field_angle, "rad", "field direction phi_E"),
        "avg_x": _var(("t_avg",), xa, "m", "centroid averaged over one period, x"),
        "avg_y": _var(("t_avg",), ya, "m", "centroid averaged over one period, y"),
        "avg_in_fit": (("t_avg",), sel.astype("i1"), {"units": "1", "long_name": "point used in the circle fit (0/1)",
                                                      "flag_values": np.array([0, 1], "i1"),
                                                      "flag_meanings": "not_fitted fitted"}),
    }, coords={"t": ("t", run.t, {"units": "s", "long_name": "time"}),
               "t_avg": ("t_avg", ta, {"units": "s", "long_name": "centre of the averaging window"})},
        attrs={"title": "flutterswim reproduce: Fig. 5, steering by a rotating field",
               "rate_rad_s": rate, "start_s": start, "orbit_speed_m_s": orb.speed, "orbit_period_s": orb.period,
               "circle_xc_m": circle[0], "circle_yc_m": circle[1], "circle_radius_m": circle[2],
               "predicted_radius_m": predicted})
    write_netcdf(ctx.path("fig5.nc"), ds)
    rows = (
        cross_check("radius of the mean circular path vs U / Omega", predicted * 1e3, circle[2] * 1e3, unit="mm",
                    rtol=3e-2, reference=f"circular (U/Omega = {predicted * 1e3:.3f} mm)"),
        compare("roundness: spread of the distance to the centre / R", None, float(np.std(rfit) / circle[2]),
                paper_text="circular", fmt="{:.2e}"),
        verdict("the swimmer's axis follows the field", "the axis continuously aligns to the field",
                f"mean angle field - heading {lag_mean:.1f} deg in the settled turn", abs(lag_mean) < 30 or abs(abs(lag_mean) - 180) < 30),
    )
    notes = (f"Field turns at Omega = {rate} rad/s from t = {start} s (after onset: a turn during onset can trap "
             f"the filament in a bent equilibrium); N = {prm['n_segments']}; U from the periodic orbit at the same N.",)
    return Outcome("ok", rows, notes, {"radius_mm": circle[2] * 1e3, "predicted_mm": predicted * 1e3, "lag_deg": lag_mean})


def video_s5_params(s: Settings) -> dict:
    # one video frame per speed / fps s of the run: a quarter of the stroke (0.377 s) or less, so
    # the stroke is seen as it is (6x at 15 fps, a frame per 0.4 s, 1.06 strokes, showed a slow
    # false undulation: stroboscopic aliasing)
    return {"fps": s.pick(15, 25), "speed": s.pick(1.25, 2.0), "size": s.pick([480, 480], [720, 720])}


def build_video_s5(ctx: Context) -> Outcome:
    from ..plotting.animation import animate
    from ..plotting.figures import plot_swimmer
    from ..result import load

    prm = video_s5_params(ctx.settings)
    run = load(ctx.path("fig5_run.nc"))
    animate(run, ctx.path("video_s5.mp4"), fps=prm["fps"], speed=prm["speed"], size=tuple(prm["size"]))
    fig = plot_swimmer(run, None, figsize=(5.0, 5.0))
    save_figure(fig, ctx.path("video_s5_poster.png"))
    step = prm["speed"] / prm["fps"]
    return Outcome("ok", (), (f"{run.t[-1]:.0f} s at {prm['speed']:g}x real speed, {prm['fps']} fps: a frame every "
                              f"{step:.3g} s of the run.",), {"frame_interval_s": step})
