"""Reference paths for path following: polylines (square, waypoints) and closed curves
(circle, figure eight), sampled densely; the signed cross-track error and the progress along
a path. Lengths in metres."""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._paths import check_text_file
from .._validate import ParameterError, positive

__all__ = ["RefPath", "square", "circle", "figure8", "waypoints_csv", "min_radius"]


@dataclass(frozen=True)
class RefPath:
    """Points (P, 2) along the path (dense), arc length s (P,), corners (indices of vertices
    where the direction turns by more than 30 degrees), closed or not, and a name."""

    points: np.ndarray
    s: np.ndarray
    corners: np.ndarray
    closed: bool
    name: str

    @property
    def length(self) -> float:
        return float(self.s[-1])

    def tangent(self, i: int) -> np.ndarray:
        j = min(i + 1, len(self.points) - 1)
        k = max(j - 1, 0)
        d = self.points[j] - self.points[k]
        return d / (np.linalg.norm(d) + 1e-300)

    def project(self, p: np.ndarray, near: int | None = None, window: int = 400) -> tuple[int, float]:
        """Index of the closest path point (searched near ``near`` if given: the path may cross
        itself) and the signed cross-track error (positive: left of the path direction). On a
        closed path the search near ``near`` runs on through its start (a second lap)."""
        pts = self.points
        if near is None:
            idx = np.arange(len(pts))
        elif self.closed:
            # (the last point is the first again: the search steps over it)
            idx = np.arange(near - window // 4, near + window) % (len(pts) - 1)
        else:
            lo = max(0, near - window // 4)
            idx = np.arange(lo, min(len(pts), near + window))
        d = np.hypot(pts[idx, 0] - p[0], pts[idx, 1] - p[1])
        i = int(idx[np.argmin(d)])
        t = self.tangent(i)
        r = p - pts[i]
        return i, float(t[0] * r[1] - t[1] * r[0])


#: the most points a polyline is sampled at (100 m at the 10 um step: a path far longer than
#: an hour of swimming, ~3.6 m, which ``steer`` refuses anyway; a waypoint 1e9 body lengths away
#: ran out of memory here)
MAX_PATH_POINTS = 10_000_000


def _polyline(vertices: np.ndarray, closed: bool, name: str, step: float) -> RefPath:
    v = np.asarray(vertices, float)
    if closed:
        v = np.vstack([v, v[:1]])
    total = float(np.sum(np.hypot(*np.diff(v, axis=0).T)))
    if not total <= MAX_PATH_POINTS * step:
        raise ParameterError(f"{name}: the path is {total:.4g} m long; at most {MAX_PATH_POINTS * step:g} m "
                             f"(sampled every {step:g} m) is allowed")
    if not total >= 0.1 * step:  # (points 1e-12 m apart are merged: a path of 1e-11 m had none left)
        raise ParameterError(f"{name}: the path is {total:.4g} m long; at least {0.1 * step:g} m is needed")
    pts, corners = [v[0]], []
    for a, b in zip(v[:-1], v[1:]):
        n = max(2, int(math.ceil(np.linalg.norm(b - a) / step)))
        seg = a + np.outer(np.linspace(0, 1, n + 1)[1:], b - a)
        corners.append(len(pts) - 1)
        pts.extend(seg)
    pts = np.array(pts)
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(pts, axis=0).T))]
    # vertices where the direction turns by more than 30 degrees (the start is not a corner)
    cs = []
    for c in corners[1:] + ([len(pts) - 1] if closed else []):
        if 0 < c < len(pts) - 1:
            d0, d1 = pts[c] - pts[c - 1], pts[c + 1] - pts[c]
            ang = abs(math.atan2(d0[0] * d1[1] - d0[1] * d1[0], d0 @ d1))
            if ang > math.radians(30):
                cs.append(c)
    return RefPath(pts, s, np.array(cs, int), closed, name)


def square(side: float, start=(0.0, 0.0), heading: float = 0.0, step: float = 1e-5) -> RefPath:
    """A square of ``side`` [m] starting at the middle of its first edge, at ``start``, along
    ``heading``, turning left."""
    side = positive("side", side)
    e = np.array([math.cos(heading), math.sin(heading)])
    n = np.array([-e[1], e[0]])
    p0 = np.asarray(start, float)
    # starting mid-edge: all four vertices are corners, and the lap closes on a straight
    v = [p0, p0 + side / 2 * e, p0 + side / 2 * e + side * n, p0 - side / 2 * e + side * n, p0 - side / 2 * e]
    return _polyline(np.array(v), True, f"square({side:.4g} m)", step)


def circle(radius: float, start=(0.0, 0.0), heading: float = 0.0, n: int = 4000) -> RefPath:
    """A circle of ``radius`` [m] through ``start``, tangent to ``heading`` there, turning left."""
    radius = positive("radius", radius)
    c = np.asarray(start, float) + radius * np.array([-math.sin(heading), math.cos(heading)])
    a = heading - math.pi / 2 + np.linspace(0, 2 * math.pi, n + 1)
    pts = c + radius * np.stack([np.cos(a), np.sin(a)], axis=1)
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(pts, axis=0).T))]
    return RefPath(pts, s, np.array([], int), True, f"circle({radius:.4g} m)")


def figure8(size: float, start=(0.0, 0.0), heading: float = 0.0, n: int = 6000) -> RefPath:
    """A figure eight (lemniscate of Gerono) of overall length ``size`` [m] starting at its
    crossing along ``heading``."""
    size = positive("size", size)
    u = np.linspace(0, 2 * math.pi, n + 1)
    x, y = size / 2 * np.sin(u), size / 4 * np.sin(2 * u)
    c, s_ = math.cos(heading - math.atan2(1, 1)), math.sin(heading - math.atan2(1, 1))
    pts = np.stack([c * x - s_ * y, s_ * x + c * y], axis=1) + np.asarray(start, float)
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(pts, axis=0).T))]
    return RefPath(pts, s, np.array([], int), True, f"figure8({size:.4g} m)")


def parse_number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


# units a waypoints header may give its columns (x_mm, y [um], ...), in metres
_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6}
# the default, named: body lengths
_BODY_LENGTHS = ("bl", "l", "body_lengths", "body lengths", "body length")


# words that name a unit of length, time or angle (or none): a header's word after the name
# that is one of these is read or refused; any other word (x_pos, field_angle) is part of the name
UNIT_WORDS = frozenset(
    "m cm mm um µm μm nm km in inch inches ft feet foot yd mi furlong furlongs px pixel pixels "
    "bl l s sec secs second seconds ms msec us min mins minute minutes h hr hrs hour hours tau frame "
    "frames deg degree degrees ° rad radian radians grad gon turn turns rev revs - 1".split()
    + ["body lengths", "body length", "body_lengths"])


def header_unit(field: str) -> str | None:
    """The unit a CSV header field names after its name (``x_mm``, ``x [um]``, ``t (ms)``,
    ``angle deg``), as written, or None for a bare name (``x``; a name merely ending in a
    unit, ``xm``, names none). Any word after the name counts, so a unit the reader does not
    know (``t_hours``, ``x_furlong``) is refused by the reader, not misread; a word that names no
    unit (``x_pos``, ``field_angle``, ``t_start``) is part of the name."""
    m = re.fullmatch(r"\s*[A-Za-z][\w ]*?\s*[\[(]\s*([^\])]+?)\s*[\])]\s*", field)
    if m is None:
        m = re.fullmatch(r"\s*[A-Za-z]\w*?(?:_|\s+)([A-Za-zµμ]+)\s*", field)
    unit = m.group(1) if m else None
    if unit is None or unit.lower() in ("-", "1") or unit.lower() not in UNIT_WORDS:
        return None  # a name (x_pos, field_angle, t_start) or explicitly no unit
    return unit


def _header_scale(row: list[str], where: str) -> float | None:
    """Metres per unit named by a header's first two columns (x_mm, y_mm; "x [um]"), or None
    when they name none (body lengths); an unknown unit, or columns naming two units, are errors."""
    named = set()
    for field in row[:2]:
        unit = header_unit(field)
        if unit is None or unit.lower() in _BODY_LENGTHS:
            continue
        if unit not in _UNITS and unit.lower() not in _UNITS:
            raise ParameterError(f"{where}: the header's column {field.strip()!r} is in {unit!r}, which is not "
                                 f"allowed; allowed: {', '.join(u for u in _UNITS if u != 'μm')} "
                                 "(no unit: body lengths)")
        named.add(unit if unit in _UNITS else unit.lower())
    if len({_UNITS[u] for u in named}) > 1:
        raise ParameterError(f"{where}: the header gives x and y different units ({', '.join(sorted(named))}); "
                             "give both in one unit")
    return _UNITS[named.pop()] if named else None


def waypoints_csv(path: str | Path, scale: float, start=(0.0, 0.0)) -> RefPath:
    """Waypoints ``x, y`` from a CSV (in units of ``scale`` metres, e.g. body lengths),
    relative to the first. Blank lines are skipped; a first row none of whose fields is a
    number (``x,y``) is a header, whose columns may name their unit (``x_mm,y_mm``, ``x [um]``,
    m, cm, mm, um; ``bl``: body lengths): the numbers are then in that unit; another unit is refused."""
    p = Path(path)
    if not p.is_file():
        raise ParameterError(f"waypoints={str(p)!r} is not a file")
    rows = []
    check_text_file(p, "waypoints")
    with open(p, newline="", encoding="utf-8-sig") as f:
        reader = csv.reader(f)
        first = True
        for row in reader:
            if not any(field.strip() for field in row):
                continue
            if first and all(parse_number(field) is None for field in row):
                first = False
                unit = _header_scale(row, f"waypoints={str(p)!r}, line {reader.line_num}")
                if unit is not None:
                    scale = unit
                continue
            where = f"waypoints={str(p)!r}, line {reader.line_num}"
            header = " (a header row holds no number, e.g. x,y)" if first else ""
            first = False
            if len(row) < 2:
                raise ParameterError(f"{where}: {','.join(row)!r} has one field; two numbers x, y are "
                                     f"required{header}")
            xy = [parse_number(row[0]), parse_number(row[1])]
            if None in xy:
                bad = row[0] if xy[0] is None else row[1]
                raise ParameterError(f"{where}: {bad.strip()!r} is not a number; two numbers x, y are "
                                     f"required{header}")
            if not all(map(math.isfinite, xy)):
                raise ParameterError(f"{where}: x, y = {row[0].strip()}, {row[1].strip()} "
                                     "are not finite; two finite numbers are required")
            if not rows or xy != rows[-1]:  # a waypoint repeated in a row is one waypoint
                rows.append(xy)
    if len(rows) < 2:
        raise ParameterError(f"waypoints={str(p)!r} needs at least two distinct points")
    v = (np.array(rows) - rows[0]) * scale + np.asarray(start, float)
    return _polyline(v, False, f"waypoints({p.name})", 1e-5)


def corner_arcs(path: RefPath, radius: float) -> list[tuple[int, np.ndarray, np.ndarray, float, float]]:
    """Per corner of ``path``, the arc :func:`fillet` rounds it with: (index, unit edge in, unit
    edge out, signed turn [rad], distance from the vertex to each tangent point). The arc of
    each corner must fit on its edges: at most half of each neighbouring edge (the whole of a
    closed path's edge through its start, which is no corner); where it does not, the tangent
    distance shrinks, and with it the radius (the path is then tighter than ``radius`` there)."""
    pts = path.points
    ends = [0, *path.corners, len(pts) - 1]
    arcs = []
    for m, c in enumerate(path.corners):
        a, b = pts[max(c - 1, 0)], pts[min(c + 1, len(pts) - 1)]
        d0 = (pts[c] - a) / np.linalg.norm(pts[c] - a)
        d1 = (b - pts[c]) / np.linalg.norm(b - pts[c])
        turn = math.atan2(d0[0] * d1[1] - d0[1] * d1[0], d0 @ d1)
        room_in = (path.s[c] - path.s[ends[m]]) * (1.0 if m == 0 and path.closed else 0.5)
        room_out = (path.s[ends[m + 2]] - path.s[c]) * (1.0 if m == len(path.corners) - 1 and path.closed else 0.5)
        arcs.append((int(c), d0, d1, turn, min(radius * math.tan(abs(turn) / 2), room_in, room_out)))
    return arcs


def fillet(path: RefPath, radius: float, step: float = 1e-5) -> RefPath:
    """The path with each corner replaced by a circular arc of ``radius`` tangent to both
    edges (what a swimmer with that smallest turning radius can follow); corners are kept
    as the indices of the points nearest the original vertices."""
    if path.corners.size == 0:
        return path
    pts = path.points
    out = [pts[0]]
    k_prev = 0
    for c, d0, d1, turn, dist in corner_arcs(path, radius):
        radius_c = dist / math.tan(abs(turn) / 2)
        p_in = pts[c] - dist * d0
        # straight part up to the arc
        seg = pts[k_prev:c + 1]
        keep = seg[(seg - p_in) @ d0 < 0]
        out.extend(keep)
        nrm = np.array([-d0[1], d0[0]]) * math.copysign(1.0, turn)
        centre = p_in + radius_c * nrm
        a0 = math.atan2(p_in[1] - centre[1], p_in[0] - centre[0])
        n = max(8, int(abs(turn) * radius_c / step))
        ang = a0 + np.linspace(0, turn, n + 1)
        out.extend(centre + radius_c * np.stack([np.cos(ang), np.sin(ang)], axis=1))
        p_out = pts[c] + dist * d1
        beyond = np.nonzero((pts[c:] - p_out) @ d1 > 0)[0]
        k_prev = c + int(beyond[0]) if beyond.size else len(pts)  # the arc may end the path
    out.extend(pts[k_prev:])
    p = np.array(out)
    keep = np.r_[True, np.hypot(*np.diff(p, axis=0).T) > 1e-12]
    p = p[keep]
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(p, axis=0).T))]
    corners = np.array([int(np.argmin(np.hypot(*(p - pts[c]).T))) for c in path.corners], int)
    return RefPath(p, s, corners, path.closed, f"{path.name} filleted r={radius:.3g} m")


def min_radius(path: RefPath, scale: float) -> float:
    """Smallest radius of curvature of ``path`` [m]: circumradius of consecutive points resampled
    every ``scale`` / 20 along it (``scale``: the radius of interest, e.g. the swimmer's
    smallest turning radius; at least 5 of the path's median point spacing), or every 1/20 of
    the path if it is shorter (a circle 1000 times
    smaller than the swimmer's turn read as straight); inf for a straight path."""
    step = min(positive("scale", scale), float(path.s[-1])) / 20.0
    # no finer than 5 of the path's own point spacings: points interpolated on its chords, a few
    # apart, read kinks (a circle of 3 body lengths sampled every 17 um at a scale of 15 um
    # read 2.36; a 0.08 body length fillet 0.07): the relative error is (spacing / 2 step)^2
    step = max(step, 5.0 * float(np.median(np.diff(path.s))))  # (median: a long chord elsewhere hid a hairpin)
    q = np.arange(0.0, path.s[-1], step)
    if q.size < 3:
        return math.inf
    p = np.stack([np.interp(q, path.s, path.points[:, 0]), np.interp(q, path.s, path.points[:, 1])], axis=1)
    a, b, c = p[:-2], p[1:-1], p[2:]
    cross = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    sides = np.linalg.norm(b - a, axis=1) * np.linalg.norm(c - b, axis=1) * np.linalg.norm(c - a, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = sides / (2.0 * np.abs(cross))
    # a path that turns straight back (a cusp) has collinear neighbours, but no radius at all
    back = np.einsum("ij,ij->i", b - a, c - b) < 0
    r = np.where(back & ~(r < math.inf), 0.0, r)
    return float(np.min(r))
