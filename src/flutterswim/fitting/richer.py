"""Richer data that breaks the degeneracy of the three descriptors: a tracked shape time
series (the tangent-angle kymograph over a cycle), the growth rate and frequency at onset, and
several voltages at once (kappa_E proportional to the voltage).

Each source is a block of sigma-weighted residuals in the identifiable coordinates
x = (log eta_perp, log chi, log tau[, nuisance]); blocks stack, and the covariance of the
stacked problem gives the uncertainty (:mod:`.uncertainty`). :func:`compare_information`
reports how much each addition shrinks the 1-sigma of B, tau and kappa_E.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import ParameterError
from .voltages import voltage_residuals

__all__ = ["ShapeData", "shape_residuals", "shape_data_from_model", "onset_residuals", "compare_information", "fit_shapes",
           "voltage_residuals"]


@dataclass(frozen=True)
class ShapeData:
    """Tangent angle theta(t_j, s_k) relative to the field [rad] at times ``t`` [s] (J,), on K
    points along the body (the midpoints of K equal segments, s measured from the model's s=0
    end), with noise ``sigma`` [rad] per sample."""

    t: np.ndarray
    theta: np.ndarray
    sigma: float

    def __post_init__(self) -> None:
        if self.theta.ndim != 2 or self.theta.shape[0] != self.t.size:
            raise ParameterError(f"theta has shape {self.theta.shape}; (len(t), K) = ({self.t.size}, K) is required")
        if not self.sigma > 0:
            raise ParameterError(f"sigma={self.sigma!r} must be > 0 (noise of the tangent angle, rad)")

    @classmethod
    def from_track(cls, track, sigma: float, k: int = 24) -> "ShapeData":
        """From a :class:`~flutterswim.analysis.track.Track` (a tracked movie, or anything
        ``as_track`` takes): the tangent angle relative to the field at the midpoints of ``k``
        equal segments of each frame's centreline (by the frame's own arc length), at the
        track's times; ``sigma`` [rad]: its noise per sample. Which end is the model's s = 0,
        and the mirror image, need not be known: :func:`fit_shapes` tries all four."""
        from .._validate import positive_int
        from ..analysis.track import as_track, polyline_tangent_angle

        tr = as_track(track)
        k = positive_int("k", k, minimum=3)
        th = polyline_tangent_angle(tr.x, tr.y)  # (T, P - 1), at the segments' midpoints
        seg = np.hypot(np.diff(tr.x, axis=1), np.diff(tr.y, axis=1))
        cum = np.concatenate((np.zeros((seg.shape[0], 1)), np.cumsum(seg, axis=1)), axis=1)
        mid = 0.5 * (cum[:, 1:] + cum[:, :-1]) / cum[:, -1:]
        s_k = (np.arange(k) + 0.5) / k
        out = np.array([np.interp(s_k, m, row) for m, row in zip(mid, th)]) - np.asarray(tr.field_angle)[:, None]
        # one branch of the angle for the whole track: the frames' mean angles continuous in time
        # (a body whose s = 0 end leads has its mean near +-pi: chosen frame by frame, it jumped by
        # 2 pi twice a stroke), the track's mean within (-pi, pi]
        mean = out.mean(axis=1)
        out += (np.unwrap(mean) - mean)[:, None]
        out -= 2 * np.pi * np.round(out.mean() / (2 * np.pi))
        return cls(np.asarray(tr.t, float), out, float(sigma))

    def oriented(self, reverse: bool, mirror: bool) -> "ShapeData":
        """The same shapes with s running from the other end (the tangent turned by pi) and/or
        mirrored about the field (theta -> -theta)."""
        th = self.theta
        if reverse:
            th = th[:, ::-1] + np.pi
            th = th - 2 * np.pi * np.round(th.mean() / (2 * np.pi))
        if mirror:
            th = -th
        return ShapeData(self.t, th, self.sigma)


def _model_kymograph(model, x: np.ndarray, t: np.ndarray, t0: float, k: int) -> np.ndarray:
    """The model's tangent angle at times t (J,) on K body points, phase origin t0 [s]; for an
    extrapolating model, Richardson-extrapolated from its two resolutions as its descriptors
    are (order 2: the 24-segment shapes alone put kappa_E and tau 2 % low, ten of their
    sigmas, fitting a 48-segment stroke)."""
    eta_perp, chi, tau = np.exp(x[:3])
    orb = model.orbit(eta_perp, chi)
    fine = getattr(model, "_fine", None)
    if fine is None:
        return _orbit_kymograph(_phase_coefficients(orb, k), orb.period * tau, t, t0)
    # Richardson on a common phase: each orbit's phase origin is where its Newton solve put it
    # (0.0175 cycles apart at the paper's point, N = 24 and 48), so the fine one is turned to
    # the coarse one's by their first harmonics, and the period is extrapolated on its own
    orb_f = fine.orbit(eta_perp, chi)
    c, c_f = _phase_coefficients(orb, k), _phase_coefficients(orb_f, k)
    shift = np.angle(np.vdot(c_f[1], c[1]))  # c_f e^{i h shift} ~ c at h = 1
    c_f = c_f * np.exp(1j * shift * np.arange(c_f.shape[0]))[:, None]
    h = min(c.shape[0], c_f.shape[0])
    period = (4.0 * orb_f.period - orb.period) / 3.0 * tau
    return _orbit_kymograph((4.0 * c_f[:h] - c[:h]) / 3.0, period, t, t0)


def _phase_coefficients(orb, k: int) -> np.ndarray:
    """A dimensionless orbit's tangent angle on K body points as one-sided Fourier
    coefficients in phase (H, K)."""
    th = orb.theta  # (M, N) on the phase grid
    m, n = th.shape
    if k != n:  # resample along the body (linear in s at the segment midpoints)
        s_m, s_d = (np.arange(n) + 0.5) / n, (np.arange(k) + 0.5) / k
        th = np.array([np.interp(s_d, s_m, row) for row in th])
    c = np.fft.rfft(th, axis=0) / m  # trigonometric interpolation in phase
    if m % 2 == 0:
        c[-1] *= 0.5
    return c


def _orbit_kymograph(c: np.ndarray, period: float, t: np.ndarray, t0: float) -> np.ndarray:
    """The tangent angle at times t [s] from its phase coefficients (H, K) and period [s]."""
    phase = (t - t0) / period
    h = np.arange(c.shape[0])
    e = np.exp(2j * np.pi * np.outer(phase, h))  # (J, H)
    w = np.where(h == 0, 1.0, 2.0)
    return np.real(e @ (w[:, None] * c))


def shape_residuals(model, x: np.ndarray, data: ShapeData) -> np.ndarray:
    """(model - data) / sigma over the kymograph; x = (log eta_perp, log chi, log tau, t0)."""
    pred = _model_kymograph(model, x, data.t, x[3], data.theta.shape[1])
    return ((pred - data.theta) / data.sigma).ravel()


def shape_data_from_model(model, x: np.ndarray, t: np.ndarray, k: int, sigma: float, t0: float = 0.0,
                          rng=None) -> ShapeData:
    """Synthetic shape data: the model's kymograph at times t with Gaussian noise sigma."""
    th = _model_kymograph(model, np.r_[x[:3], t0], t, t0, k)
    if rng is not None:
        th = th + sigma * rng.standard_normal(th.shape)
    return ShapeData(np.asarray(t, float), th, float(sigma))


def onset_residuals(model, x: np.ndarray, growth: tuple[float, float], omega: tuple[float, float]) -> np.ndarray:
    """Growth rate [1/s] and angular frequency [rad/s] of the straight state at onset, from
    the discrete linear stability at (eta_perp, chi), against measured (value, sigma) pairs."""
    from ..orbits.linear import leading_pair

    eta_perp, chi, tau = np.exp(x[:3])
    lam = leading_pair(model.groups(eta_perp, chi), model.n_segments) / tau
    return np.array([(lam.real - growth[0]) / growth[1], (lam.imag - omega[0]) / omega[1]])


def _jac(fun, x: np.ndarray, steps) -> np.ndarray:
    cols = []
    for k, h in enumerate(steps):
        e = np.zeros_like(x)
        e[k] = h
        cols.append((fun(x + e) - fun(x - e)) / (2 * h))
    return np.stack(cols, axis=1)


def compare_information(model, x: np.ndarray, mean: np.ndarray, sem: np.ndarray, *, shapes: ShapeData | None = None,
                        onset=None, voltages=None) -> dict[str, np.ndarray]:
    """Relative 1-sigma of (B, tau, kappa_E) at x from the descriptors alone and with each
    addition (``shapes``: ShapeData with the phase origin 0; ``onset``: ((g, sg), (w, sw));
    ``voltages``: (voltages, means, sems, v_ref)). Returns {name: sigma_rel (3,)}."""
    from .fit import model_jacobian
    from .uncertainty import covariance

    y = model(x)
    jd = model_jacobian(model, x, y) / sem[:, None]
    out = {"descriptors": covariance(jd).sigma_rel}
    if onset is not None:
        jo = _jac(lambda z: onset_residuals(model, z, *onset), x, (1e-5, 1e-5, 1e-5))
        out["descriptors + onset"] = covariance(np.vstack([jd, jo])).sigma_rel
    if shapes is not None:
        xs = np.r_[x, 0.0]
        js = _jac(lambda z: shape_residuals(model, z, shapes), xs, (1e-5, 1e-5, 1e-5, 1e-5 * float(np.exp(x[2]))))
        out["shapes"] = covariance(js).sigma_rel
        out["descriptors + shapes"] = covariance(np.vstack([np.c_[jd, np.zeros(3)], js])).sigma_rel
    if voltages is not None:
        jv = _jac(lambda z: voltage_residuals(model, z, *voltages), x, (1e-5, 1e-5, 1e-5))
        out["several voltages (kappa_E ~ V)"] = covariance(jv).sigma_rel
    return out


def data_period(data: ShapeData) -> float:
    """The period [s] of a shape time series: the mean interval between the upward crossings
    through its mean of the tangent angle at the body point that swings most (NaN if fewer
    than two whole cycles)."""
    th = data.theta - data.theta.mean(axis=0)
    q = th[:, int(np.argmax(th.std(axis=0)))]
    # crossings of the mean with hysteresis (a quarter of the swing's std): noise does not count
    lo = -0.25 * q.std()
    ups, armed = [], False
    for j in range(1, q.size):
        if q[j] < lo:
            armed = True  # (a crossing counts once the angle has been well below its mean)
        elif armed and q[j - 1] < 0 <= q[j]:
            ups.append(data.t[j - 1] + (0 - q[j - 1]) / (q[j] - q[j - 1]) * (data.t[j] - data.t[j - 1]))
            armed = False
    if len(ups) < 3:
        return math.nan
    return float((ups[-1] - ups[0]) / (len(ups) - 1))


def fit_shapes(model, data: ShapeData, guess_x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares fit of (log eta_perp, log chi, log tau, t0) to a shape time series from
    ``guess_x`` (3,); the phase origin is first located by a scan (and the data's orientation:
    :meth:`ShapeData.oriented`). Returns (x (4,), relative
    1-sigma of (B, tau, kappa_E))."""
    from scipy.optimize import least_squares

    from .fit import Penalty
    from .model import NotSwimming, OutsideModel
    from .uncertainty import covariance

    x3 = np.asarray(guess_x, float).copy()
    eta_perp, chi, tau = np.exp(x3)
    try:
        period = model.orbit(eta_perp, chi).period * tau
    except NotSwimming as exc:
        raise OutsideModel(f"no stable stroke at the shape fit's start ({exc})") from None
    # tau from the data's own period: a start 10 % off in tau drifts the phase by 10 % a cycle,
    # and over several cycles the misfit has minima at other phases (the paper's point, 10 %
    # off, 6.6 cycles: kappa_E -30 %, before)
    measured = data_period(data)
    if math.isfinite(measured) and 0.5 < measured / period < 2.0:
        x3[2] += math.log(measured / period)
        period = measured
    starts = data.t[0] + period * np.arange(32) / 32
    # the phase origin by a scan, for each orientation of the data (which end is s = 0, and the
    # mirror image: a track does not know the model's): the best of the four is fitted
    best = (math.inf, None, None)
    for rev in (False, True):
        for mir in (False, True):
            d = data.oriented(rev, mir)
            cost = [np.sum(shape_residuals(model, np.r_[x3, s], d) ** 2) for s in starts]
            i = int(np.argmin(cost))
            if cost[i] < best[0]:
                best = (cost[i], d, starts[i])
    data = best[1]
    x0 = np.r_[x3, best[2]]
    steps = np.array([1e-5, 1e-5, 1e-5, 1e-5 * period])
    scale = np.r_[1.0, 1.0, 1.0, period]
    penalty = Penalty()  # a trial point without a stroke: worse than any with one (as in fit)
    n_res = data.theta.size

    def fun(z):
        try:
            return penalty.seen(shape_residuals(model, z, data))
        except NotSwimming:
            return penalty.failed(n_res)

    def jac(z):
        return _jac(fun, z, steps)

    # in steps from the start, as fit does: the first trust region is then one unit of
    # ``scale`` (a factor e per parameter), not the start's length in log units (about 6: a
    # first step to where the model has no stroke, which raised NotSwimming from 5 % off)
    r = least_squares(lambda d: fun(x0 + d * scale), np.zeros_like(x0), jac=lambda d: jac(x0 + d * scale) * scale,
                      method="trf", xtol=1e-12, ftol=1e-14, gtol=1e-14, max_nfev=40)
    x = x0 + r.x * scale
    return x, covariance(jac(x)).sigma_rel
