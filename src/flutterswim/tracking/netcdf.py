"""A tracked movie as CF-style NetCDF (units on every variable) and back to a :class:`Track`.

Dimensions: frame (every frame of the movie, failed ones included) and point (arc-length
samples). Failed frames have NaN positions, ``tracked = 0`` and their ``failure_reason``.
The dataset goes through :func:`flutterswim._cf.cf_dataset`, as every other NetCDF file
flutterswim writes: the coordinates (time, frame, s) hold no missing values and carry no
``_FillValue``.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from .._validate import ParameterError
from ..analysis.track import Track

__all__ = ["save_track", "load_track", "to_xarray"]


def to_xarray(tr: Track):
    """The tracked movie (``tr.meta["frames"]`` from :func:`track`) as an xarray Dataset."""
    import xarray as xr

    from .. import __version__
    from .._cf import cf_dataset

    info = tr.meta.get("frames")
    if info is None:
        raise ParameterError("track has no per-frame tracking record (meta['frames']); only tracks made by "
                             "flutterswim.tracking.track can be saved here")
    mm = 1.0 / tr.meta["px_per_mm"]
    ok = np.asarray(info["ok"], bool)
    reason = np.array([str(r) for r in info["reason"]], dtype=object)
    # with a region of interest the positions are measured from its corner (a review: the label
    # said the image's axes, 10 px off for an ROI from column 10)
    origin = (" from the region of interest's corner (roi attribute: x0,y0,x1,y1 in px of the image)"
              if tr.meta.get("roi") else " from the image's corner")
    ds = xr.Dataset(
        {
            "x": (("frame", "point"), info["x_px"] * mm,
                  {"units": "mm", "long_name": "centreline x (image column axis)" + origin}),
            "y": (("frame", "point"), info["y_px"] * mm,
                  {"units": "mm", "long_name": "centreline y (image row axis, downwards)" + origin}),
            "body_length": ("frame", info["length_px"] * mm, {"units": "mm", "long_name": "tracked body length"}),
            "contrast": ("frame", info["contrast"], {"units": "1", "long_name": "ridge height over the filtered noise sd"}),
            "tracked": ("frame", ok.astype(np.int8), {"units": "1", "long_name": "frame tracked (1) or failed (0)",
                                                       "flag_values": np.array([0, 1], np.int8),
                                                       "flag_meanings": "failed tracked"}),
            "failure_reason": ("frame", reason, {"units": "1", "long_name": "why the frame failed (empty if tracked)"}),
            "match_distance": ("frame", info["match_px"] * mm,
                               {"units": "mm", "long_name": "mean point distance to the last good frame"}),
        },
        coords={
            "time": ("frame", np.asarray(info["t"], float), {"units": "s", "long_name": "time of the frame " + (
                "(its timestamp, as given)" if tr.meta.get("times_given") else "(index / fps)"),
                                                             "standard_name": "time"}),
            "frame": ("frame", np.arange(ok.size), {"units": "1", "long_name": "frame index"}),
            "s": ("point", np.asarray(tr.s, float), {"units": "mm", "long_name": "arc length from the s = 0 end"}),
        },
    )
    m = tr.meta
    if m.get("frame_files") and len(m["frame_files"]) == ok.size:  # a folder's frames, in the order tracked
        ds["frame_file"] = ("frame", np.asarray(m["frame_files"], dtype=str),
                            {"units": "1", "long_name": "the frame's file in the input folder (frames ordered by the "
                                                        "numbers in their names)"})
    ds.attrs.update({
        "Conventions": "CF-1.10",
        "title": TRACK_TITLE,
        "source": f"flutterswim {__version__} tracking of {m.get('source', '?')}",
        "input": str(m.get("source", "")),
        "px_per_mm": float(m["px_per_mm"]), "px_per_mm_units": "1/mm",
        "fps": float(m["fps"]), "fps_units": "1/s",
        "roi": json.dumps(m.get("roi")),
        "field_angle": float(np.mean(tr.field_angle)), "field_angle_units": "rad",
        "body_length": float(tr.length), "body_length_units": "mm",
        "body_length_std": float(m["length_std_px"]) * mm, "body_length_std_units": "mm",
        "body_length_spread": float(m["length_spread"]), "body_length_spread_units": "1",
        "n_frames": int(m["n_frames"]), "n_failed": int(m["n_failed"]),
        # NetCDF has no boolean attribute: 1 for a line darker than its background
        "dark_line": int(bool(m.get("dark_line", False))), "dark_line_units": "1",
    })
    if math.isfinite(m.get("unchanged_fraction", math.nan)):
        # share of pixels keeping their exact value between frames (a lossy codec's skipped blocks)
        ds.attrs.update({"unchanged_fraction": float(m["unchanged_fraction"]), "unchanged_fraction_units": "1"})
    for key, text in (m.get("temporal") or {}).items():  # what the fits in time did, and why not
        if isinstance(text, str):
            ds.attrs[f"temporal_{key}"] = text
    if "template_coef_se" in m:  # the periodic template's coefficient noise at (s = 0, s = l)
        ds.attrs.update({"template_coef_se": np.asarray(m["template_coef_se"], float),
                         "template_coef_se_units": "mm"})
    if "template_coef_stderr" in m:  # the same with its degrees of freedom and serial correlation
        ds.attrs.update({"template_coef_stderr": np.asarray(m["template_coef_stderr"], float),
                         "template_coef_stderr_units": "mm"})
    return cf_dataset(ds)


#: the NetCDF title of a track (a command writing tracks replaces only these)
TRACK_TITLE = "filament tracked from video by flutterswim"


def save_track(tr: Track, path: str | os.PathLike) -> Path:
    """Write :func:`to_xarray` to NetCDF atomically (never over a file not ours)."""
    from .._paths import check_output_file, write_netcdf

    p = check_output_file(path, (".nc",), what="out", kind=TRACK_TITLE)
    return write_netcdf(to_xarray(tr), p)


def load_track(path: str | os.PathLike) -> Track:
    """The :class:`Track` (tracked frames only) of a file written by :func:`save_track`."""
    import xarray as xr

    p = Path(os.fspath(path))
    if not p.is_file():
        raise ParameterError(f"track={str(p)!r} is not a file")
    try:
        ds = xr.load_dataset(p, engine="h5netcdf")
    except (OSError, ValueError) as exc:
        raise ParameterError(f"track={str(p)!r} is not a readable NetCDF file ({exc})") from None
    if "tracked" not in ds or "px_per_mm" not in ds.attrs:
        raise ParameterError(f"track={str(p)!r} is not a track written by flutterswim track")
    ok = ds["tracked"].values.astype(bool)
    a = ds.attrs
    frames = {"t": ds["time"].values, "x_px": ds["x"].values * a["px_per_mm"], "y_px": ds["y"].values * a["px_per_mm"],
              "length_px": ds["body_length"].values * a["px_per_mm"], "contrast": ds["contrast"].values, "ok": ok,
              "reason": [str(r) for r in ds["failure_reason"].values], "match_px": ds["match_distance"].values * a["px_per_mm"]}
    meta = {"source": a.get("input", ""), "px_per_mm": float(a["px_per_mm"]), "fps": float(a["fps"]),
            "roi": json.loads(a.get("roi", "null")), "dark_line": bool(a.get("dark_line", 0)), "n_frames": int(a["n_frames"]), "n_failed": int(a["n_failed"]),
            "length_px": float(a["body_length"]) * a["px_per_mm"],
            "length_std_px": float(a["body_length_std"]) * a["px_per_mm"],
            "length_spread": float(a["body_length_spread"]), "frames": frames,
            # (the frames' own timestamps: said so again when the track is saved anew)
            "times_given": "timestamp" in str(ds["time"].attrs.get("long_name", ""))}
    temporal = {k[len("temporal_"):]: str(v) for k, v in a.items() if k.startswith("temporal_")}
    if temporal:
        meta["temporal"] = temporal
    if "unchanged_fraction" in a:
        meta["unchanged_fraction"] = float(a["unchanged_fraction"])
    if "template_coef_se" in a:
        meta["template_coef_se"] = [float(v) for v in np.atleast_1d(a["template_coef_se"])]
    if "template_coef_stderr" in a:
        meta["template_coef_stderr"] = [float(v) for v in np.atleast_1d(a["template_coef_stderr"])]
    return Track(t=ds["time"].values[ok], x=ds["x"].values[ok], y=ds["y"].values[ok], s=ds["s"].values,
                 field_angle=float(a["field_angle"]), length=float(a["body_length"]), units="mm", meta=meta)
