"""``steer``: follow a path on the full model by turning the field, in closed loop (the
:class:`.control.Controller` observing at 50 fps with tracking noise and a one-frame delay) or
open loop (a pre-planned schedule of the same path at the reduced model's speed). Metrics:
cross-track error of the cycle-averaged centroid, corner overshoot, time to reacquire after a
corner, waypoint arrivals, and whether the filament was trapped."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

import numpy as np

from .._validate import ParameterError, positive, positive_int, within
from ..field import Constant, Field
from ..params import Parameters
from .control import Controller, wrap
from .path import RefPath, corner_arcs, fillet, min_radius
from .reduced import ReducedModel

__all__ = ["SteerResult", "steer", "metrics"]


@dataclass(frozen=True)
class SteerResult:
    """The run (SimulationResult, commanded field in ``field_angle``), the path placed at the
    swimmer's averaged position when control starts, the metrics, and the settings."""

    run: object
    path: RefPath
    metrics: dict
    closed_loop: bool
    control_start: float


#: most tracking noise [px] a steered run may be given (the body is about 260 px at 14 um/px)
MAX_NOISE_PX = 100.0
#: the NetCDF title of a steered run (steer replaces only these; a plain run is not one)
STEER_TITLE = "flutterswim simulation of an active filament steered along a path"


def steer_dataset(res: SteerResult, reduced=None):
    """The run as an xarray Dataset (``SimulationResult.to_xarray``) with what scores it on its
    own: the reference path as placed (``path_x``, ``path_y`` [m] along ``path_point``, with
    the corner indices), the time control started, closed or open loop, and the reduced model
    the controller used. ``flutterswim.load`` reads it as the run."""
    import json

    ds = res.run.to_xarray()
    units = {"units": "m"}
    ds["path_x"] = ("path_point", np.asarray(res.path.points[:, 0], float),
                    {**units, "long_name": "reference path, x (as placed when control started)"})
    ds["path_y"] = ("path_point", np.asarray(res.path.points[:, 1], float),
                    {**units, "long_name": "reference path, y (as placed when control started)"})
    ds.attrs.update({"title": STEER_TITLE, "steering_path": res.path.name, "steering_path_closed": int(res.path.closed),
                     "steering_path_closed_units": "1",
                     "steering_path_corners": json.dumps([int(c) for c in res.path.corners]),
                     "steering_closed_loop": int(res.closed_loop), "steering_closed_loop_units": "1",
                     "steering_control_start": float(res.control_start), "steering_control_start_units": "s"})
    if reduced is not None:
        ds.attrs["steering_reduced_model"] = json.dumps(
            {"U_m_s": reduced.U, "period_s": reduced.period, "k_per_s": reduced.k,
             "omega_max_rad_s": reduced.omega_max, "r_min_m": reduced.r_min})
    return ds


def _centroid(run) -> tuple[np.ndarray, np.ndarray]:
    return run.x.mean(axis=1), run.y.mean(axis=1)


# the longest path the closed loop follows in one run: an hour of swimming (3.6 m at the paper's
# ~1 mm/s, ~1000 body lengths; 50 fps frames of N = 24: ~150 MB); a waypoint 1e9 m away ran out
# of memory
_MAX_DURATION_S = 3600.0
# a run goes on past the time its path's length takes, up to this many times that, until done
_CAP_FACTOR = 3.0


def check_duration(path: RefPath, U: float, period: float, laps: float = 1.0, what: str = "path") -> float:
    """The time ``laps`` of ``path`` take at the speed ``U`` [m/s] (ParameterError beyond an hour):
    needs only the swimmer's periodic orbit, so that a command line checks it before identifying
    the reduced model (about 50 s)."""
    est = 1.1 * laps * path.length / U + 3 * period
    if not est <= _MAX_DURATION_S:
        raise ParameterError(f"{what}: {laps:g} lap(s) at the swimmer's {U * 1e3:.3g} mm/s take {est:.3g} s; at "
                             f"most {_MAX_DURATION_S:g} s is simulated (a shorter path, or fewer laps)")
    return est


def steer(params: Parameters, path_factory, reduced: ReducedModel, *, closed_loop: bool = True,
          noise_px: float = 0.2, um_per_px: float = 14.0, fps: float = 50.0, delay_frames: int = 1,
          n_segments: int = 24, onset: float | None = None, laps: float = 1.0, seed: int = 0,
          lookahead_bl: float = 0.0, correction_bl: float = 0.4, rate_fraction: float = 0.8,
          progress: bool = False) -> SteerResult:
    """Swim ``laps`` of the path made by ``path_factory(start_xy, heading)`` [m].

    The controller (:class:`.control.Controller`) tracks the path with its corners rounded to
    the tightest turn it commands, so its turns already begin where the swimmer must start
    turning: ``lookahead_bl`` is 0 by default (0.15 body lengths cut the square's corners early,
    cross-track RMS 0.090 against 0.080 body lengths). Control starts at ``onset`` [s], by
    default the reduced model's ``onset_time``, once the stroke is established (a field turned
    mid-onset can trap the filament: at 0.75 kappa_E a fixed 10 s did, on a gentle circle)."""
    from ..result import concatenate
    from ..simulate import RunFailedWarning, simulate

    if not isinstance(params, Parameters):
        raise ParameterError(f"params={params!r} must be flutterswim.Parameters")
    fps = positive("fps", fps)
    # (1e12 px was taken, and scored)
    noise_px = within("noise_px", noise_px, 0.0, MAX_NOISE_PX, "px of tracking noise on a swimmer the camera sees")
    um_per_px = positive("um_per_px", um_per_px)
    laps = positive("laps", laps)
    rate_fraction = positive("rate_fraction", rate_fraction)
    if not rate_fraction <= 1.0:
        raise ParameterError(f"rate_fraction={rate_fraction!r} must be in (0, 1]: a fraction of the step-out rate")
    if not isinstance(delay_frames, (int, np.integer)) or delay_frames < 0:
        raise ParameterError(f"delay_frames={delay_frames!r} must be an integer >= 0")
    seed = positive_int("seed", seed, minimum=0)  # numpy's generator takes seeds >= 0
    onset = positive("onset", reduced.onset_time if onset is None else onset)
    dt = 1.0 / fps
    # control starts on a camera frame: the onset run's last frame is then the moment control
    # starts (off the grid, 7.44 s was followed by 7.475 s at 50 fps, a frame's step skipped)
    onset = math.ceil(onset * fps - 1e-9) / fps
    rng = np.random.default_rng(seed)
    sigma = noise_px * um_per_px * 1e-6
    # the path's length does not depend on where it starts: too long a path is refused first
    probe = path_factory((0.0, 0.0), 0.0)  # the path's shape and length (not where it starts)
    check_duration(probe, reduced.U, reduced.period, laps)
    # the tightest turn the controller commands, U / (rate_fraction Omega_max), above the
    # swimmer's own U / Omega_max (a circle between the two was called feasible, and followed
    # at the controller's radius: 0.36 body lengths RMS off a circle of 1.1); checked on the
    # path as made at the origin (its shape does not depend on where it starts), before any run
    r_turn = reduced.U / (rate_fraction * reduced.omega_max)
    r_path = min_radius(fillet(probe, r_turn), r_turn)
    if r_path < 0.95 * r_turn:
        warnings.warn(f"the path bends with a radius down to {r_path / params.l:.2f} body lengths, below the "
                      f"tightest turn the controller makes, U/({rate_fraction:g} Omega_max) = {r_turn / params.l:.2f} "
                      f"(the swimmer's own U/Omega_max = {reduced.r_min / params.l:.2f}): it cannot be followed "
                      "there (scale the path up)", stacklevel=2)
    cut = corner_cut(probe, r_turn)
    if cut > ARRIVAL_BL * params.l:
        warnings.warn(f"a corner of the path is passed {cut / params.l:.2f} body lengths inside its waypoint by the "
                      f"controller's tightest turn ({r_turn / params.l:.2f} body lengths): its waypoint is not arrived "
                      f"at (within {ARRIVAL_BL:g}); turn by less at a waypoint, or scale the path up", stacklevel=2)
    # onset along the initial field direction (0), then control
    first = simulate(params, onset, n_segments=n_segments, frame_dt=dt)
    cx, cy = _centroid(first)
    m = first.t > onset - reduced.period
    start = np.array([cx[m].mean(), cy[m].mean()]) + reduced.U * reduced.period / 2 * np.array([1.0, 0.0])
    path: RefPath = path_factory(start, 0.0)
    # the time the path takes (corners slow it down); the run goes on past it, up to three times
    # as long, until an open path's end is reached or the laps are swum (a path starting behind
    # the swimmer, or across its heading, needs a turn first: it ended a quarter of the way)
    duration = 1.1 * laps * path.length / reduced.U + 3 * reduced.period
    cap = min(_CAP_FACTOR * duration, max(duration, _MAX_DURATION_S))
    # the controller tracks the path with its corners rounded to the tightest turn it commands
    tracked = fillet(path, r_turn)
    ctrl = Controller(tracked, reduced.period, reduced.U, reduced.omega_max, lookahead_bl * params.l,
                      correction_bl * params.l, rate_fraction=rate_fraction, fps=fps)
    for t, x, y in zip(first.t, cx, cy):  # the camera has watched the onset too
        ctrl.observe(t, np.array([x, y]) + sigma * rng.standard_normal(2))
    parts = [first]
    state = first.final_state()
    t = onset
    pending = deque_of(delay_frames, 0.0)
    n = int(round(duration / dt))
    n_cap = int(round(cap / dt))
    check = max(int(round(2 * reduced.period / dt)), int(round(0.1 * duration / dt)), 1)
    true_t, true_x, true_y = list(first.t), list(cx), list(cy)
    done, covered = False, 0.0
    plan = _open_loop_plan(path, reduced, onset, rate_fraction, fps) if not closed_loop else None
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=n, desc="steer", unit="frame", leave=False)
    trapped_at = math.nan
    k = 0
    while k < n_cap:
        cmd = pending.popleft()
        # (Constant: the commanded angle is unwrapped, more than a turn is no unit mix-up)
        with warnings.catch_warnings():  # (a failure is raised below)
            warnings.simplefilter("ignore", RunFailedWarning)
            part = simulate(params, t + dt, t_start=t, initial=state, field=Field(direction=Constant(cmd)),
                            n_segments=n_segments, n_frames=2)
        if not part.ok:
            raise RuntimeError(f"the simulation failed at t={t:.4g} s: {part.message}")
        parts.append(part)
        state, t = part.final_state(), t + dt
        true_t.append(t)
        true_x.append(float(part.x[-1].mean()))
        true_y.append(float(part.y[-1].mean()))
        xy = np.array([true_x[-1], true_y[-1]]) + sigma * rng.standard_normal(2)
        ctrl.observe(t, xy)
        pending.append(ctrl.update(t) if closed_loop else plan(t))
        if bar is not None:
            bar.update(1)
        if k % int(10 * fps) == 0 and k > 0 and _stalled(parts, reduced):
            trapped_at = t
            break
        k += 1
        if k >= n and (k - n) % check == 0:
            done, covered = _completed(true_t, true_x, true_y, path, reduced.period, onset, params.l, laps)
            if done:
                break
            if bar is not None and k == n:
                bar.total = n_cap
                bar.refresh()
    if bar is not None:
        bar.close()
    if not done and not math.isfinite(trapped_at):
        done, covered = _completed(true_t, true_x, true_y, path, reduced.period, onset, params.l, laps)
        if not done:
            what = (f"{laps:g} lap(s) of the path were not swum" if path.closed else
                    f"the path's end was not reached (the swimmer never came within {ARRIVAL_BL:g} body length of it)")
            warnings.warn(f"{what} in {t - onset:.3g} s of control, {cap / duration:.3g} times the {duration:.3g} s its "
                          f"length takes ({100 * covered:.0f} % of {'the laps' if path.closed else 'it'} covered): the "
                          "swimmer cannot follow it (a path starting behind it or across its heading, bends tighter "
                          "than it turns, or too much tracking noise)", stacklevel=2)
    run = concatenate(parts)
    run = replace(run, settings={**run.settings, "field": (
        f"{'closed' if closed_loop else 'open'}-loop steering from t = {onset:.6g} s: the direction set every frame "
        f"({fps:g} fps) by the {'controller' if closed_loop else 'planned schedule'}, held in field_angle "
        f"(before: {parts[0].settings.get('field')})")})
    met = metrics(run, path, reduced, onset, params.l)
    met["path_min_radius_bl"] = r_path / params.l
    met["period_s"] = reduced.period  # (the stroke the figure averages over; it assumed 0.38 s)
    met["path_feasible"] = bool(r_path >= 0.95 * r_turn)
    met["controller_min_radius_bl"] = r_turn / params.l
    met["corner_cut_max_bl"] = cut / params.l
    met["trapped"] = bool(math.isfinite(trapped_at)) or met["trapped"]
    met["trapped_at_s"] = trapped_at  # when the run was stopped for it (NaN: not stopped)
    met["completed"] = bool(done)  # the open path's end reached, or the laps swum
    met["laps"] = float(laps) if path.closed else 1.0
    met.update(closed_loop=closed_loop, noise_px=noise_px, um_per_px=um_per_px, fps=fps, delay_frames=delay_frames,
               path=path.name, lookahead_bl=lookahead_bl, correction_bl=correction_bl)
    return SteerResult(run, path, met, closed_loop, onset)


def corner_cut(path: RefPath, radius: float) -> float:
    """The largest distance from a corner's waypoint to the path rounded at ``radius`` (what
    the controller tracks, :func:`~flutterswim.steering.path.fillet`, with its arcs from
    :func:`~flutterswim.steering.path.corner_arcs`): for a turn by a whose arc touches the
    edges a distance d from the vertex, d tan(a / 4) (0.41 radius at 90 degrees, 1 radius at
    120; near a U-turn the arc is shortened to fit its edges); 0 for a path without corners."""
    return max((dist * math.tan(abs(turn) / 4) for *_, turn, dist in corner_arcs(path, radius)), default=0.0)


def deque_of(n: int, value: float):
    from collections import deque

    return deque([value] * max(1, int(n)))


def _stalled(parts, reduced: ReducedModel) -> bool:
    """Trapped: the centroid moved less than a fifth of the expected distance in 5 periods."""
    recent = parts[-int(5 * reduced.period / (parts[-1].t[-1] - parts[-1].t[0])):]
    if len(recent) < 2:
        return False
    a = np.array([recent[0].x[0].mean(), recent[0].y[0].mean()])
    b = np.array([recent[-1].x[-1].mean(), recent[-1].y[-1].mean()])
    return float(np.hypot(*(b - a))) < 0.2 * reduced.U * 5 * reduced.period


def _open_loop_plan(path: RefPath, reduced: ReducedModel, t0: float, rate_fraction: float, fps: float):
    """Field direction planned for the path at speed U (no lag compensation: at the rates
    commanded the lag is a few degrees) with the same turn-rate limit (``rate_fraction`` Omega_max, commands at ``fps``): the heading the
    swimmer should have at arc length U (t - t0)."""
    ang = np.unwrap(np.arctan2(np.gradient(path.points[:, 1]), np.gradient(path.points[:, 0])))
    state = {"cmd": 0.0}

    def plan(t: float) -> float:
        s = reduced.U * (t - t0)
        if path.closed:
            s %= path.length
        want = float(np.interp(s, path.s, ang))
        step = rate_fraction * reduced.omega_max / fps
        state["cmd"] += max(-step, min(step, wrap(want - state["cmd"])))
        return state["cmd"]

    return plan


def _distance_to_path(path: RefPath, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The signed distance of the points ``q`` (Q, 2) to the polyline through the path's points
    (positive: left of the path direction) and the index of the nearest path point: a global
    nearest-point search (a k-d tree of every path point), refined onto the two segments
    beside that point. At a vertex (the nearest point of both segments) the sign is taken
    against the mean of the two directions, so the outer side of a corner is the outer side."""
    from scipy.spatial import cKDTree

    pts = path.points
    n = len(pts)
    _, i = cKDTree(pts).query(q)
    i = np.asarray(i, int)
    if path.closed:  # the last point is the first again
        prev = np.where(i == 0, n - 2, i - 1)
        nxt = np.where(i == n - 1, 1, i + 1)
    else:
        prev, nxt = np.maximum(i - 1, 0), np.minimum(i + 1, n - 1)
    best = np.full(len(q), np.inf)
    sign = np.zeros(len(q))
    at_vertex = np.ones(len(q), bool)
    for a, b in ((prev, i), (i, nxt)):
        d = pts[b] - pts[a]
        dd = np.einsum("ij,ij->i", d, d)
        r = q - pts[a]
        u = np.clip(np.einsum("ij,ij->i", r, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
        foot = pts[a] + u[:, None] * d
        dist = np.hypot(*(q - foot).T)
        inside = (u > 0.0) & (u < 1.0) & (dd > 0)
        better = dist < best
        best = np.where(better, dist, best)
        cross = d[:, 0] * (q[:, 1] - foot[:, 1]) - d[:, 1] * (q[:, 0] - foot[:, 0])
        sign = np.where(better & inside, np.sign(cross), sign)
        at_vertex = np.where(better, ~inside, at_vertex)
    # nearest point a vertex of the polyline: the side against the mean direction there
    d0, d1 = pts[i] - pts[prev], pts[nxt] - pts[i]
    t = (d0 / (np.hypot(*d0.T)[:, None] + 1e-300) + d1 / (np.hypot(*d1.T)[:, None] + 1e-300))
    r = q - pts[i]
    sign = np.where(at_vertex, np.sign(t[:, 0] * r[:, 1] - t[:, 1] * r[:, 0]), sign)
    return sign * best, i


def _averaged_progress(t: np.ndarray, cx: np.ndarray, cy: np.ndarray, path: RefPath, period: float, t0: float,
                       bl: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The centroid averaged over a period from ``t0`` on: its times, positions (Q, 2) and
    progress along the path (laps counted, :func:`_progress`)."""
    from .turning import _moving_average

    ts, ax = _moving_average(t, cx, period)
    _, ay = _moving_average(t, cy, period)
    m = ts >= t0
    q = np.stack([ax[m], ay[m]], axis=1)
    return ts[m], q, _progress(path, q, back=0.5 * bl, ahead=2.0 * bl, slack=0.5 * bl)


def _completed(t: list, cx: list, cy: list, path: RefPath, period: float, t0: float, bl: float,
               laps: float) -> tuple[bool, float]:
    """Whether the swimmer has reached an open path's end (passed it, within ``ARRIVAL_BL`` body
    lengths of the end point: passing its perpendicular 2.9 body lengths off had counted) or
    swum ``laps`` of a closed one, and the fraction of the path (of the laps) covered."""
    ts, q, prog = _averaged_progress(np.asarray(t), np.asarray(cx), np.asarray(cy), path, period, t0, bl)
    if prog.size == 0:
        return False, 0.0
    if path.closed:
        covered = float(prog.max() - prog[0]) / (laps * path.length)
        return covered >= 1.0, covered
    near_end = float(np.min(np.hypot(*(q - path.points[-1]).T))) < ARRIVAL_BL * bl
    return bool(prog.max() >= path.s[-1] and near_end), float(prog.max() - prog[0]) / path.length


def _progress(path: RefPath, q: np.ndarray, back: float, ahead: float, slack: float) -> np.ndarray:
    """The arc length along ``path`` reached by the points ``q`` (Q, 2) in order, unwrapped on a
    closed path (laps counted on, from the path's start: a swimmer just behind the start is
    behind it, not a lap ahead).

    Each point's is that of its nearest path point from ``back`` behind the arc length before to
    ``ahead`` beyond it, or, if further, to the middle of the edge after the next corner: a corner
    cut on the inside is passed where the nearest point jumps from one edge to the next (on the
    corner's bisector), however sharp the corner, while a part of the path crossing this one
    (a figure eight's other branch) is not taken for it. Should a point anywhere on the path be
    nearer by more than ``slack`` (the search lost the path), that point is taken, in the lap
    nearest the arc length before."""
    from scipy.spatial import cKDTree

    pts, s = path.points, path.s
    L = path.length
    cs = np.sort(s[path.corners]).astype(float)
    if path.closed:
        back, ahead = min(back, L / 6), min(ahead, L / 3)  # (a path shorter than the window)
        core = slice(0, len(pts) - 1)  # the last point is the first again
        ext_p = np.concatenate([pts[core]] * 3)
        ext_s = np.concatenate([s[core] - L, s[core], s[core] + L])
        cs = np.concatenate([cs + k * L for k in (-1, 0, 1, 2)])
    else:
        ext_p, ext_s = pts, s
        cs = np.r_[cs, L]  # the last edge ends at the path's end
    _, g = cKDTree(pts).query(q)

    def nearest_lap(sv: float, ref: float) -> float:
        return sv + L * round((ref - sv) / L) if path.closed else sv

    out = np.empty(len(q))
    S = 0.0  # the path starts where control starts (a figure eight at its crossing)
    for k, p in enumerate(q):
        base = L * math.floor(S / L) if path.closed else 0.0
        here = S - base
        end = here + ahead
        n = int(np.searchsorted(cs, here, side="right"))
        if n + 1 < cs.size:  # on through the next corner to the middle of the edge after it
            end = max(end, 0.5 * (cs[n] + cs[n + 1]))
        if path.closed:
            end = min(end, here + 0.5 * L)
        lo, hi = np.searchsorted(ext_s, [here - back, end])
        w = slice(lo, max(hi, lo + 1))
        d = np.hypot(ext_p[w, 0] - p[0], ext_p[w, 1] - p[1])
        j = int(np.argmin(d))
        if d[j] <= math.hypot(*(pts[g[k]] - p)) + slack:
            S = base + float(ext_s[lo + j])
        else:
            S = nearest_lap(float(s[g[k]]), S)
        out[k] = S
    return out


#: a waypoint is arrived at when the swimmer passes within this many body lengths of it (the
#: controller rounds a 90 degree corner 0.41 r_turn = 0.57 body lengths inside it, a 120 degree
#: turn r_turn = 1.37 body lengths inside)
ARRIVAL_BL = 1.0


def metrics(run, path: RefPath, reduced: ReducedModel, t0: float, body_length: float) -> dict:
    """Cross-track error of the true cycle-averaged centroid after control starts (RMS, max;
    mm and body lengths), corner overshoot (largest outward excursion near a corner), time to
    reacquire (|error| < 0.1 body length until 1.5 body lengths before the next corner) after each
    corner (NaN: not reacquired), waypoint arrivals (at each corner, NaN where the swimmer passed
    it more than ``ARRIVAL_BL`` body lengths away; an open path's end in ``end_arrival_s``, NaN if
    not reached) and each corner's closest approach (``waypoint_miss_bl``, over the progress
    nearer that corner than its neighbours), trapped. An open path is scored up to where its end
    is reached (the run goes on past it).

    The cross-track error is the distance to the path (its nearest point anywhere: a corner is
    cut on the inside, where the nearest point jumps from one edge to the next). Progress along
    the path (arrivals, the corners' zones, the fraction covered) is the arc length of the
    nearest point, counted on continuously from where control starts (laps counted; see
    ``_progress``): a corner is reached when the swimmer passes its bisector."""
    bl = body_length
    ts, q, prog = _averaged_progress(run.t, *_centroid(run), path, reduced.period, t0, bl)
    ax, ay = q[:, 0], q[:, 1]
    # the whole run's speed: trapped is whether the run ended stalled
    speed_all = np.hypot(np.gradient(ax, ts), np.gradient(ay, ts)) if ts.size > 1 else np.zeros(ts.size)
    end_arrival = math.nan
    # the closest the averaged centroid came to an open path's end, over the whole run (what a
    # run that did not reach it missed by)
    end_miss = (math.nan if path.closed or not prog.size else
                float(np.min(np.hypot(*(q - path.points[-1]).T))) / bl)
    if not path.closed:
        # an open path is scored up to where the swimmer reaches its end (then swims on past it)
        done = np.nonzero(prog >= path.s[-1])[0]
        if done.size:
            end_arrival = float(ts[done[0]])
            ts, ax, ay, q, prog = ts[:done[0] + 1], ax[:done[0] + 1], ay[:done[0] + 1], q[:done[0] + 1], prog[:done[0] + 1]
    e, _ = _distance_to_path(path, q)
    Ls = path.length
    s_c = path.s[path.corners].astype(float)
    # each corner's first pass after control starts, in the order they are passed
    start = prog[0] if prog.size else 0.0
    if path.closed:
        s_c = s_c + Ls * np.ceil((start - s_c) / Ls)
    order = np.argsort(s_c, kind="stable")
    passes = s_c[order]
    nxt = np.r_[passes[1:], passes[0] + Ls if path.closed and passes.size else math.inf]
    over, reacq, arrivals, miss = {}, {}, {}, {}
    prv = np.r_[passes[-1] - Ls if path.closed and passes.size else -math.inf, passes[:-1]]
    for c, sc, s_next, s_prev in zip(order, passes, nxt, prv):
        # outward: to the right of a left turn (e < 0), to the left of a right turn
        v = path.corners[c]
        d0, d1 = path.points[v] - path.points[v - 1], path.points[v + 1] - path.points[v]
        left = d0[0] * d1[1] - d0[1] * d1[0] > 0
        # (every pass of a closed path's corner)
        rel = prog - sc
        if path.closed:
            rel = (rel + Ls / 2) % Ls - Ls / 2
        w = np.abs(rel) < 1.5 * bl
        if w.any():
            over[c] = float(max(0.0, -e[w].min() if left else e[w].max()))
        # time from passing the vertex until the error stays below 0.1 body length, up to where
        # the next corner's zone begins (there the swimmer cuts that corner, on purpose)
        after = np.nonzero((prog > sc) & (prog < s_next - 1.5 * bl))[0]
        if after.size:
            bad = np.nonzero(np.abs(e[after]) >= 0.1 * bl)[0]
            if bad.size == 0:
                reacq[c] = 0.0
            elif bad[-1] + 1 < after.size:
                reacq[c] = float(ts[after[bad[-1] + 1]] - ts[after[0]])
            else:
                reacq[c] = math.nan
        # arrival: the averaged position passes the corner, within 1 body length of the path,
        # having come within ARRIVAL_BL body lengths of the waypoint itself near the pass (a
        # corner cut by more, or a pass the progress jumped to, is no arrival)
        # nearer this corner than the others, on its first pass (the one the arrival times)
        near = (prog - sc > (s_prev - sc) / 2) & (prog - sc < (s_next - sc) / 2)
        miss[c] = float(np.hypot(*(q[near] - path.points[v]).T).min()) if near.any() else math.nan
        hit = np.nonzero((prog >= sc) & (np.abs(e) < bl))[0]
        arrivals[c] = float(ts[hit[0]]) if hit.size and miss[c] < ARRIVAL_BL * bl else math.nan
    speed = np.hypot(np.gradient(ax, ts), np.gradient(ay, ts)) if ts.size > 1 else np.zeros(ts.size)
    covered = float(prog.max() - prog[0]) if prog.size else 0.0
    return {
        "cross_track_rms_mm": float(np.sqrt(np.mean(e ** 2)) * 1e3), "cross_track_rms_bl": float(np.sqrt(np.mean(e ** 2)) / bl),
        "cross_track_max_mm": float(np.abs(e).max() * 1e3), "cross_track_max_bl": float(np.abs(e).max() / bl),
        "corner_overshoot_bl": float(max(over.values()) / bl) if over else 0.0,
        "corner_overshoot_mm": float(max(over.values()) * 1e3) if over else 0.0,
        "reacquire_after_corner_s": [reacq[c] for c in range(len(path.corners)) if c in reacq],
        "waypoint_arrival_s": [arrivals[c] for c in range(len(path.corners))],
        "waypoint_miss_bl": [miss[c] / bl for c in range(len(path.corners))],
        "path_covered_fraction": covered / Ls,
        "mean_speed_mm_s": float(np.mean(speed) * 1e3),
        "end_arrival_s": end_arrival,
        "end_miss_bl": end_miss,
        "trapped": bool(np.mean(speed_all[-max(1, speed_all.size // 10):]) < 0.2 * reduced.U),
    }
