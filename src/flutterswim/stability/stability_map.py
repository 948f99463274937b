"""Stability map: omega_max over a (eta_perp, chi) grid by root following (paper's algorithm).

The leading eigenvalue is found at (max eta_perp, max |chi|) from scratch, followed in
eta_perp at that chi, then, for every eta_perp in parallel, followed in chi down to the
smallest |chi| > 0. The spectrum is invariant under chi -> -chi, so negative chi reuse |chi|.
chi = 0 is exact: omega_max = max(-1, -k_1^4/eta_perp). eta_perp <= 0 (no drag) is NaN.
Grid steps larger than ``max_step`` are subdivided internally so that no branch is jumped.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from .._validate import ParameterError, finite, positive
from ..defaults import MAX_MAP_POINTS
from . import _kernels
from .leading import FREE_FREE_K1, ROOT_RTOL, leading_eigenvalue
from .newton import _newton_numpy, follow_root, resolve_backend

__all__ = ["StabilityMap", "stability_map", "load_map"]

#: points per axis of the default check subgrid (see :func:`stability_map`)
CHECK_POINTS = 8

#: the NetCDF title of a stability map (a map replaces only these)
MAP_TITLE = "flutterswim stability map of the straight filament"


@dataclass(frozen=True)
class StabilityMap:
    """omega (n_eta, n_chi) complex leading eigenvalue, Im >= 0, units 1/tau (NaN: not computed);
    eta_perp (n_eta,), chi (n_chi,); iterations (n_eta, n_chi) Newton steps (-1: failed);
    check_points, check_max_rel_diff: size of the spectral cross-check subgrid and the largest
    relative difference found there (0 and NaN in maps saved before the check was made by default)."""

    eta_perp: np.ndarray
    chi: np.ndarray
    omega: np.ndarray
    iterations: np.ndarray
    check_points: int = 0
    check_max_rel_diff: float = math.nan

    @property
    def growth_rate(self) -> np.ndarray:
        return self.omega.real

    @property
    def angular_frequency(self) -> np.ndarray:
        return self.omega.imag

    def to_dataset(self):
        """CF-style xarray Dataset with re_omega, im_omega (dims eta_perp, chi) and iterations."""
        import xarray as xr

        from .. import __version__
        from .._cf import cf_dataset

        return cf_dataset(xr.Dataset(
            {
                "re_omega": (("eta_perp", "chi"), self.omega.real,
                             {"long_name": "growth rate Re omega_max of the leading eigenvalue", "units": "1/tau"}),
                "im_omega": (("eta_perp", "chi"), self.omega.imag,
                             {"long_name": "angular frequency Im omega_max of the leading eigenvalue",
                              "units": "1/tau"}),
                "iterations": (("eta_perp", "chi"), self.iterations.astype(np.int16),
                               {"long_name": "Newton iterations (-1: not converged)", "units": "1"}),
            },
            coords={"eta_perp": ("eta_perp", self.eta_perp,
                                 {"long_name": "normal drag group eta_perp = mu_perp l^4/(B tau)", "units": "1"}),
                    "chi": ("chi", self.chi, {"long_name": "activity group chi = kappa_E l", "units": "1"})},
            attrs={"Conventions": "CF-1.10", "title": MAP_TITLE, "source": f"flutterswim {__version__}",
                   "description": "leading eigenvalue of the straight filament (flutterswim.stability)",
                   "check_points": self.check_points, "check_points_units": "1",
                   "check_max_rel_diff": self.check_max_rel_diff, "check_max_rel_diff_units": "1"},
        ))

    def save(self, path, *, dtype: str = "float64", complevel: int = 4):
        """Write NetCDF (h5netcdf engine), zlib-compressed, atomically (temporary file in the same
        folder, then renamed). ``dtype="float32"`` halves the size (relative rounding 6e-8).
        Returns the path."""
        from .._paths import check_output_file, write_netcdf

        if dtype not in ("float64", "float32"):
            raise ParameterError(f"dtype={dtype!r} is not allowed; use 'float64' or 'float32'")
        path = check_output_file(path, (".nc", ".nc4", ".h5"), what="path", kind=MAP_TITLE)
        enc = {k: {"zlib": True, "complevel": int(complevel), "shuffle": True, "dtype": dtype}
               for k in ("re_omega", "im_omega")}
        enc["iterations"] = {"zlib": True, "complevel": int(complevel), "shuffle": True}
        return write_netcdf(self.to_dataset(), path, encoding=enc)


def load_map(path) -> StabilityMap:
    """Read a map written by :meth:`StabilityMap.save` (float32 maps come back as float64)."""
    import xarray as xr

    with xr.open_dataset(path, engine="h5netcdf") as ds:
        om = ds["re_omega"].values.astype(float) + 1j * ds["im_omega"].values.astype(float)
        return StabilityMap(ds["eta_perp"].values, ds["chi"].values, om, ds["iterations"].values.astype(np.int64),
                            int(ds.attrs.get("check_points", 0)), float(ds.attrs.get("check_max_rel_diff", math.nan)))


def _refine(values: np.ndarray, hmax: float, ratio: float = 1.25) -> tuple[np.ndarray, np.ndarray]:
    """Insert points so consecutive gaps are <= hmax and, towards 0, |a/b| <= ratio (geometric
    steps: the leading root moves like omega + 1 ~ chi near chi = 0); return (path, indices)."""
    pieces, idx, pos = [values[:1]], [0], 0
    for a, b in zip(values[:-1], values[1:]):
        k = max(1, int(np.ceil(abs(b - a) / hmax - 1e-9)))
        kg = 0
        if a * b > 0 and abs(a) > ratio * abs(b):
            kg = int(np.ceil(np.log(abs(a / b)) / np.log(ratio) - 1e-9))
        if kg > k:
            k = kg
            pieces.append(np.geomspace(a, b, k + 1)[1:])
        else:
            pieces.append(a + (b - a) * np.arange(1, k + 1) / k)
        pos += k
        idx.append(pos)
    return np.concatenate(pieces), np.array(idx)


def _uniform(lo: float, hi: float, step: float) -> np.ndarray:
    """lo + k step up to hi, rounded so that grid values such as 0 are exact."""
    v = lo + step * np.arange(int(np.floor((hi - lo) / step + 0.5)) + 1)
    v = np.round(v, 9)
    v[np.abs(v) < 1e-6 * step] = 0.0
    return v


def _grid(arg, rng, step, name):
    if arg is None:
        lo, hi = finite(f"{name}_range[0]", rng[0]), finite(f"{name}_range[1]", rng[1])
        step = positive("step", step)
        n = (hi - lo) / step + 1.5
        if n > MAX_MAP_POINTS:  # before anything is allocated
            raise ParameterError(f"step={step!r} gives {n:.3g} values of {name}; the map may have at most "
                                 f"{MAX_MAP_POINTS} points (flutterswim.defaults.MAX_MAP_POINTS)")
        v = _uniform(lo, hi, step)
    else:
        v = np.atleast_1d(np.asarray(arg, dtype=float))
    if v.ndim != 1 or v.size == 0 or not np.all(np.isfinite(v)) or np.any(np.diff(v) <= 0):
        raise ParameterError(f"{name} must be a non-empty, finite, strictly increasing 1-D array")
    return v


def _columns_numpy(etas, chis, seeds, tol, maxit):
    ne, nc = etas.size, chis.size
    out = np.empty((ne, nc), dtype=complex)
    its = np.empty((ne, nc), dtype=np.int64)
    for j in range(nc):
        if j == 0:
            guess = seeds
        elif j == 1:
            guess = out[:, 0]
        else:
            r = (chis[j] - chis[j - 1]) / (chis[j - 1] - chis[j - 2])
            guess = out[:, j - 1] + (out[:, j - 1] - out[:, j - 2]) * r
        guess = np.where(np.isfinite(guess), guess, out[:, j - 1] if j else seeds)
        w, it = _newton_numpy(guess, np.full(ne, chis[j]), etas, tol, maxit)
        w = np.where(w.imag < 0, w.conj(), w)
        out[:, j], its[:, j] = np.where(it >= 0, w, np.nan), it
    return out, its


#: the paper's map: eta_perp in [0, 350], chi in [-130, 130]
ETA_RANGE = (0.0, 350.0)
CHI_RANGE = (-130.0, 130.0)


def stability_map(*, eta_perp=None, chi=None, eta_range: tuple[float, float] = ETA_RANGE,
                  chi_range: tuple[float, float] = CHI_RANGE, step: float = 0.1,
                  max_step: float = 0.25, tol: float = 1e-10, maxit: int = 30,
                  check_stride: int | None = None, backend: str = "auto",
                  executor: str | None = None, workers: int | None = None,
                  scheduler: str | None = None, progress: bool = False) -> StabilityMap:
    """Leading eigenvalue over the grid eta_perp x chi (default: the paper's [0,350]x[-130,130]
    at ``step``; or explicit increasing 1-D arrays). Returns a :class:`StabilityMap`.

    ``executor`` spreads blocks of eta_perp rows over the sweep backends
    (:func:`flutterswim.sweep.get_backend`: "serial", "processes", "dask", "dask-local";
    ``scheduler`` is a Dask address); by default the rows run in this process (numba threads).

    The map follows one root (the paper's algorithm), the leading one in the paper's region;
    beyond it another pair can lead (at eta_perp ~ 1000 and chi < 30 the followed root is the
    second). So the map is compared with the collocation solver started from scratch
    (:func:`leading_eigenvalue`) on a subgrid, by default CHECK_POINTS x CHECK_POINTS points
    spread over it, with ``check_stride=k`` every k-th point in both directions, and a warning
    says where the followed root is not the leading one.
    ``progress``: a bar over the eta_perp rows. Grids above ``defaults.MAX_MAP_POINTS`` points
    are refused before anything is allocated.
    """
    from ..simulate import single_blas_thread

    with single_blas_thread():  # the seed and check eigen-solves are small dense problems
        return _stability_map(eta_perp, chi, eta_range, chi_range, step, max_step, tol, maxit, check_stride,
                              backend, executor, workers, scheduler, progress)


def _stability_map(eta_perp, chi, eta_range, chi_range, step, max_step, tol, maxit, check_stride, backend,
                   executor, workers, scheduler, progress) -> StabilityMap:
    backend = resolve_backend(backend)
    eta = _grid(eta_perp, eta_range, step, "eta_perp")
    chis = _grid(chi, chi_range, step, "chi")
    if eta.size * chis.size > MAX_MAP_POINTS:
        raise ParameterError(f"the map grid has {eta.size} x {chis.size} = {eta.size * chis.size} points; at "
                             f"most {MAX_MAP_POINTS} are allowed (flutterswim.defaults.MAX_MAP_POINTS)")
    if np.any(eta < 0):
        raise ParameterError(f"eta_perp={eta[eta < 0][0]!r} must be >= 0 (eta_perp = 0 gives NaN)")
    max_step = positive("max_step", max_step)
    omega = np.full((eta.size, chis.size), complex(np.nan, np.nan))  # no drag: no eigenvalue, NaN in both parts
    iters = np.full((eta.size, chis.size), -1, dtype=np.int64)
    ve = np.flatnonzero(eta > 0)
    if ve.size == 0:
        return StabilityMap(eta, chis, omega, iters)
    ev = eta[ve]
    zero = chis == 0.0
    if np.any(zero):
        w0 = np.maximum(-1.0, -(FREE_FREE_K1**4) / ev)
        omega[np.ix_(ve, np.flatnonzero(zero))] = w0[:, None]
        iters[np.ix_(ve, np.flatnonzero(zero))] = 0
    apos = np.unique(np.abs(chis[~zero]))[::-1]  # descending |chi| > 0
    if apos.size == 0:
        return StabilityMap(eta, chis, omega, iters)
    # seed at (largest eta, largest |chi|), follow eta downwards at that chi
    seed = leading_eigenvalue(float(apos[0]), float(ev[-1]), n=48).omega
    epath, eidx = _refine(ev[::-1], max_step)
    path = follow_root(seed, float(apos[0]), epath, tol=tol, maxit=maxit, backend=backend)
    seeds = np.ascontiguousarray(path.omega[eidx][::-1])
    cpath, cidx = _refine(apos, max_step)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=int(ev.size), desc="stability map", unit="row", leave=False)
    try:
        if executor is None:
            out = np.empty((ev.size, cpath.size), dtype=complex)
            its = np.empty((ev.size, cpath.size), dtype=np.int64)
            n_blocks = 1 if bar is None else min(ev.size, 50)
            for b in np.array_split(np.arange(ev.size), n_blocks):
                out[b], its[b] = _follow_block((ev[b], cpath, seeds[b], tol, maxit, backend))
                if bar is not None:
                    bar.update(b.size)
        else:
            out, its = _distributed(executor, workers, scheduler, ev, cpath, seeds, tol, maxit, backend, bar)
    finally:
        if bar is not None:
            bar.close()
    out, its = out[:, cidx], its[:, cidx]
    col = np.searchsorted(-apos, -np.abs(chis[~zero]))
    nz = np.flatnonzero(~zero)
    omega[np.ix_(ve, nz)] = out[:, col]
    iters[np.ix_(ve, nz)] = its[:, col]
    return _check(StabilityMap(eta, chis, omega, iters), check_stride)


def _follow_block(args) -> tuple[np.ndarray, np.ndarray]:
    """Follow the leading root along chi for a block of eta_perp rows (a picklable task)."""
    ev, cpath, seeds, tol, maxit, backend = args
    if backend == "numba":
        out = np.empty((ev.size, cpath.size), dtype=complex)
        its = np.empty((ev.size, cpath.size), dtype=np.int64)
        _kernels._follow_columns(np.ascontiguousarray(ev), np.ascontiguousarray(cpath),
                                 np.ascontiguousarray(seeds), tol, maxit, out, its)
        return out, its
    return _columns_numpy(ev, cpath, seeds, tol, maxit)


def _distributed(executor, workers, scheduler, ev, cpath, seeds, tol, maxit, backend, bar=None):
    from ..sweep.backends import WorkerLost, get_backend

    with get_backend(executor, workers=workers, scheduler=scheduler) as ex:
        n_blocks = max(1, min(ev.size, 4 * int(getattr(ex, "workers", 1) or 1)))
        blocks = np.array_split(np.arange(ev.size), n_blocks)
        items = ((k, (ev[b], cpath, seeds[b], tol, maxit, backend)) for k, b in enumerate(blocks))
        parts = {}
        for k, res in ex.imap(_follow_block, items):
            if isinstance(res, WorkerLost):
                raise RuntimeError(f"stability map: {res.message} (block {k} of {len(blocks)})")
            parts[k] = res
            if bar is not None:
                bar.update(blocks[k].size)
    out = np.concatenate([parts[k][0] for k in range(len(blocks))], axis=0)
    its = np.concatenate([parts[k][1] for k in range(len(blocks))], axis=0)
    return out, its


def _check(smap: StabilityMap, stride: int | None) -> StabilityMap:
    """``smap`` with its check against :func:`leading_eigenvalue` on the subgrid (every
    ``stride``-th point, or CHECK_POINTS per axis), warning where the followed root differs."""
    if stride is None:
        rows = np.unique(np.linspace(0, smap.eta_perp.size - 1, CHECK_POINTS).round().astype(int))
        cols = np.unique(np.linspace(0, smap.chi.size - 1, CHECK_POINTS).round().astype(int))
    else:
        if not isinstance(stride, (int, np.integer)) or isinstance(stride, bool) or stride < 1:
            raise ParameterError(f"check_stride={stride!r} must be an integer >= 1")
        rows, cols = range(0, smap.eta_perp.size, stride), range(0, smap.chi.size, stride)
    worst, count, off, first = 0.0, 0, 0, None
    for i in rows:
        for j in cols:
            e, c = float(smap.eta_perp[i]), float(smap.chi[j])
            if e <= 0 or c == 0:
                continue
            ref = leading_eigenvalue(c, e, n=48).omega
            d = abs(smap.omega[i, j] - ref) / max(1.0, abs(ref))
            d = d if np.isfinite(d) else math.inf
            worst = max(worst, d)
            count += 1
            if d > ROOT_RTOL:
                off += 1
                first = first or (e, c, complex(smap.omega[i, j]), complex(ref))
    if off:
        e, c, w, ref = first
        warnings.warn(
            f"stability map: at {off} of {count} checked points the followed root is not the leading eigenvalue "
            f"(first at eta_perp={e:.6g}, chi={c:.6g}: {w.real:.6g}{w.imag:+.6g}i, leading {ref.real:.6g}"
            f"{ref.imag:+.6g}i, relative difference up to {worst:.3g}): another pair leads there, which following "
            "one root (the paper's algorithm) does not see, or the root was lost between grid points; compute "
            "such points with leading_eigenvalue or bifurcation (which re-seeds), or a smaller max_step",
            RuntimeWarning, stacklevel=4)
    return StabilityMap(smap.eta_perp, smap.chi, smap.omega, smap.iterations, count, worst if count else math.nan)
