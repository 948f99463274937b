"""Synthetic movies of a filament seen edge-on, with known truth, from a simulation.

The ribbon's 8 um thickness is below a pixel, so it images as a thin bright line: the
centreline convolved with a Gaussian point-spread function. Intensity model per frame::

    I(x, y) = b(x, y) + A * L(x, y),     L = sum_j w_j G_sigma(x - X_j, y - Y_j)

with X_j, Y_j points spaced ``h`` (<= 0.25 px) along the centreline, G_sigma(r) =
exp(-r^2 / (2 sigma^2)) and weights ``w_j = h / (sqrt(2 pi) sigma)`` so that L is 1 on the middle of a straight line and 1/2 at
its true ends; b is a linear background gradient. Camera: shot noise Poisson(I) plus
Gaussian read noise. SNR = A / sqrt(b_mean + read^2): the line's peak over the noise of the
background.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from .._validate import ParameterError, finite, finite_array, non_negative, positive, positive_int

__all__ = ["Movie", "render", "line_image"]

#: sub-frames of one exposure at most (0.5 px apart up to a 128 px sweep of the fastest point)
_MAX_SUBFRAMES = 256


@dataclass(frozen=True, eq=False)
class Movie:
    """A rendered movie and its truth.

    frames: (T, H, W) float32 (or uint16) intensities; t: (T,) s.
    x_px, y_px: (T, P) true centreline in pixel coordinates (x = column, y = row, pixel
    centres at integers), ordered s = 0 -> s = l; um_per_px, fps; snr as requested.
    origin_m: (2,) the point (metres, simulation frame) at pixel (0, 0); pixel rows grow
    with the simulation's y (no flip).
    """

    frames: np.ndarray
    t: np.ndarray
    x_px: np.ndarray
    y_px: np.ndarray
    um_per_px: float
    fps: float
    snr: float
    origin_m: np.ndarray
    meta: dict = field(default_factory=dict)

    @property
    def px_per_mm(self) -> float:
        return 1000.0 / self.um_per_px


def line_image(x: np.ndarray, y: np.ndarray, shape: tuple[int, int], sigma: float,
               spacing: float = 0.25) -> np.ndarray:
    """Unit-height image of a polyline (P,) in pixel coordinates, blurred by a Gaussian.

    The centreline is interpolated by a cubic spline in arc length and sampled every
    ``spacing`` px from s = 0 to s = L; each sample adds ``h/(sqrt(2 pi) sigma)`` times
    exp(-r^2/(2 sigma^2)), so the plateau is 1 and the true ends are at 1/2. Returns (H, W).
    """
    H, W = shape
    ds = np.hypot(np.diff(x), np.diff(y))
    s = np.concatenate([[0.0], np.cumsum(ds)])
    L = float(s[-1])
    n = max(2, int(math.ceil(L / spacing)) + 1)
    # midpoint rule on [0, L]: n samples at the centres of n equal cells
    h = L / n
    sq = (np.arange(n) + 0.5) * h
    cx, cy = CubicSpline(s, x)(sq), CubicSpline(s, y)(sq)
    r = int(math.ceil(4 * sigma))
    off = np.arange(-r, r + 1)
    ix0, iy0 = np.rint(cx).astype(int), np.rint(cy).astype(int)
    gx = np.exp(-0.5 * ((ix0[:, None] + off[None, :] - cx[:, None]) / sigma) ** 2)  # (n, K)
    gy = np.exp(-0.5 * ((iy0[:, None] + off[None, :] - cy[:, None]) / sigma) ** 2)
    amp = h / (math.sqrt(2 * math.pi) * sigma)
    patch = amp * gy[:, :, None] * gx[:, None, :]  # (n, K, K)
    rows = iy0[:, None, None] + off[None, :, None]
    cols = ix0[:, None, None] + off[None, None, :]
    rows, cols = np.broadcast_to(rows, patch.shape), np.broadcast_to(cols, patch.shape)
    ok = (rows >= 0) & (rows < H) & (cols >= 0) & (cols < W)
    img = np.bincount((rows[ok] * W + cols[ok]), weights=patch[ok], minlength=H * W)
    return img.reshape(H, W)


def render(result: Any, *, um_per_px: float = 14.0, snr: float = 5.0, psf_sigma: float = 1.2,
           defocus: float = 0.0, background: float = 100.0, gradient: float = 0.3,
           read_noise: float = 3.0, margin_px: int = 24, shape: tuple[int, int] | None = None,
           dtype: str = "float32", seed: int | None = 0, frames: slice | None = None,
           exposure: float = 0.0) -> Movie:
    """Render a simulation (any object with t, x, y in metres, e.g. a SimulationResult or
    ``PeriodicOrbit.to_result(n_cycles, frames_per_cycle)``) as a noisy movie, one frame per
    time of the result (the frame rate is that of the result's times).

    um_per_px: pixel size; snr: line peak over background noise (inf: noiseless);
    psf_sigma: Gaussian PSF sigma [px]; defocus: extra Gaussian blur sigma [px] (the total
    blur is sqrt(psf^2 + defocus^2), photons conserved, so the peak drops); background: mean
    background [photons]; gradient: relative background change across the frame (linear, along
    the diagonal); read_noise: camera read noise [photons]; shape: (H, W) or None to fit the
    path plus ``margin_px``; dtype: "float32" or "uint16" (rounded, clipped); exposure:
    the shutter's open time as a fraction of the frame interval (0: instantaneous, 1: open
    all the time), centred on each frame's time: the line is averaged over it (motion blur;
    the result's centrelines interpolated in time by cubic splines, sub-frames at most 0.5 px
    apart at the fastest point, up to 256 of them; the first and last frames' exposures reach
    past the result's times, where the splines' end cubics extrapolate the motion). The truth
    (``x_px``, ``y_px``) stays the centreline at the frame's time.
    """
    um_per_px = positive("um_per_px", um_per_px)
    psf_sigma = positive("psf_sigma", psf_sigma)
    defocus = non_negative("defocus", defocus)
    background = positive("background", background)
    read_noise = non_negative("read_noise", read_noise)
    if isinstance(snr, (bool, np.bool_)) or not isinstance(snr, numbers.Real) or not snr > 0:
        raise ParameterError(f"snr={snr!r} must be a number > 0 (math.inf for a noiseless movie)")
    gradient = finite("gradient", gradient)
    if not abs(gradient) < 2.0:  # the background 1 + gradient (u - 1/2), u in [0, 1], stays > 0
        raise ParameterError(f"gradient={gradient!r} must satisfy -2 < gradient < 2 (the background stays positive)")
    margin_px = positive_int("margin_px", margin_px, 0)
    if seed is not None:
        seed = positive_int("seed", seed, 0)
    if dtype not in ("float32", "uint16"):
        raise ParameterError(f"dtype={dtype!r} is unknown; choose 'float32' or 'uint16'")
    exposure = non_negative("exposure", exposure)
    if exposure > 1.0:
        raise ParameterError(f"exposure={exposure!r} must be in [0, 1] (a fraction of the frame interval)")
    t = np.asarray(result.t, float)
    x = np.asarray(result.x, float)
    y = np.asarray(result.y, float)
    if exposure > 0.0:
        if t.size < 4:
            raise ParameterError(f"exposure={exposure!r} needs a result of 4 or more times to interpolate; it has {t.size}")
        if not np.all(np.diff(t) > 0):
            raise ParameterError("exposure: the result's times must increase strictly to interpolate the motion")
        # the whole result's motion (before frames are picked), for the times inside each exposure
        path_x, path_y = CubicSpline(t, x, axis=0), CubicSpline(t, y, axis=0)
        picked = t[frames] if frames is not None else t
        # the movie's frame interval (every second time picked: twice the result's)
        dt_frame = float(np.median(np.diff(picked if picked.size > 1 else t)))
    if t.ndim != 1 or x.ndim != 2 or x.shape != y.shape or x.shape[0] != t.size:
        raise ParameterError(f"result must hold t (T,) and x, y (T, P) of one shape; t has shape {t.shape}, "
                             f"x {x.shape} and y {y.shape}")
    if frames is not None:
        t, x, y = t[frames], x[frames], y[frames]
    if t.size < 1:
        raise ParameterError("result must hold t (T,) and x, y (T, P) with T >= 1")
    for name, a in (("t", t), ("x", x), ("y", y)):
        finite_array(f"result.{name}", a)
    if t.size > 1 and not np.all(np.diff(t) > 0):
        raise ParameterError("result.t must increase strictly (the frames' times; the frame rate is taken from them)")
    px = um_per_px * 1e-6
    origin = np.array([x.min() - margin_px * px, y.min() - margin_px * px])
    xp, yp = (x - origin[0]) / px, (y - origin[1]) / px
    if shape is None:
        shape = (int(math.ceil(yp.max())) + margin_px + 1, int(math.ceil(xp.max())) + margin_px + 1)
    H, W = int(shape[0]), int(shape[1])
    if H < 8 or W < 8:
        raise ParameterError(f"shape={shape!r} is too small; at least 8 x 8 pixels are required")
    sigma = math.hypot(psf_sigma, defocus)
    # the unit-height line of the PSF alone; defocus spreads the same light wider
    height = psf_sigma / sigma
    noise_sd = math.sqrt(background + read_noise**2)
    A = 0.0 if math.isinf(snr) else snr * noise_sd
    if math.isinf(snr):
        A = 10.0 * noise_sd
    rr, cc = np.mgrid[0:H, 0:W]
    bg = background * (1 + gradient * ((cc / max(W - 1, 1) + rr / max(H - 1, 1)) / 2 - 0.5))
    rng = np.random.default_rng(seed)
    out = np.empty((t.size, H, W), dtype=np.float32 if dtype == "float32" else np.uint16)
    for i in range(t.size):
        if exposure > 0.0:
            half = 0.5 * exposure * dt_frame
            # the longest path of a node during the exposure (sampled at 9 times: a stroke may
            # turn back within a long exposure)
            probe = t[i] + np.linspace(-half, half, 9)
            gx, gy = path_x(probe) / px, path_y(probe) / px  # (9, P)
            sweep = float(np.max(np.sum(np.hypot(np.diff(gx, axis=0), np.diff(gy, axis=0)), axis=0)))
            k = int(min(max(math.ceil(sweep / 0.5), 2), _MAX_SUBFRAMES))
            sub = t[i] + half * (2 * (np.arange(k) + 0.5) / k - 1)  # midpoints of k equal slices
            line = sum(line_image((path_x(u) - origin[0]) / px, (path_y(u) - origin[1]) / px, (H, W), sigma)
                       for u in sub) / k
        else:
            line = line_image(xp[i], yp[i], (H, W), sigma)
        clean = bg + A * height * line
        if math.isinf(snr):
            img = clean
        else:
            img = rng.poisson(clean).astype(float) + rng.normal(0.0, read_noise, clean.shape)
        if dtype == "uint16":
            img = np.clip(np.rint(img), 0, 65535)
        out[i] = img
    fps = float(1.0 / np.median(np.diff(t))) if t.size > 1 else math.nan
    return Movie(frames=out, t=t, x_px=xp, y_px=yp, um_per_px=um_per_px, fps=fps, snr=float(snr),
                 origin_m=origin, meta={"psf_sigma": psf_sigma, "defocus": defocus,
                                        "background": background, "read_noise": read_noise,
                                        "gradient": gradient, "amplitude": A * height,
                                        "exposure": exposure})
