"""Tracking benchmarks (not a test): speed per 512 x 512 frame and per 5-cycle movie, and the
accuracy on movies rendered from the paper's settled stroke (50 fps, 14 um/px).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_tracking.py [--repeat 5] [--seeds 4] [--json out.json] [--no-periodic] [--degraded]

Speed: one core; min and median over repeats. ``scratch``: one frame tracked with no previous
frame (coarse 4x-reduced localisation, then the window around it); ``whole frame``: the
segmentation of the whole 512 x 512 frame (the fallback); ``in a movie``: per frame of a 100-frame 512 x
512 movie (after the first frame, the search window follows the body; the whole frame is
searched again whenever a frame fails in the window). Accuracy: per SNR and noise seed,
centreline RMS distance to the true curve and tip RMS error [px], frames flagged (of which
tip outliers), whether the ends' offsets were smoothed in time, whether the periodic shape
template was used (and its drift test's F statistic), and the relative error of
the descriptors of :func:`describe` against those of the simulated centrelines on the same
frames (all complete cycles). ``--degraded``: the same accuracy on degraded and longer movies
of the settled stroke (defocus, background gradient, uint16, wider PSF, other pixel sizes, a
dim background, 3 and 10 cycles; ``DEGRADED``) and nothing else.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from bench_sweep import machine  # noqa: E402  (same folder: the one description of the machine)

FPS = 50.0
KEYS = ("period_s", "advance_per_cycle_mm", "leading_lateral_p2p_mm", "trailing_lateral_p2p_mm")


def stroke(n_frames: int = 101, t_end: float = 10.0):
    """The last ``n_frames`` frames (50 fps) of the paper's swimmer simulated for ``t_end`` s."""
    import flutterswim as fs

    r = fs.simulate(fs.PAPER, t_end, n_segments=24, frame_dt=1.0 / FPS)
    sl = slice(r.t.size - n_frames, r.t.size)
    return SimpleNamespace(t=r.t[sl], x=r.x[sl], y=r.y[sl])


def speed(sim, repeat: int) -> dict:
    from importlib import import_module

    from flutterswim.tracking import render, track

    mod = import_module("flutterswim.tracking.track")
    big = render(sim, um_per_px=14.0, snr=3.0, shape=(512, 512), margin_px=60, seed=0)
    single, whole = [], []
    for _ in range(repeat):
        for f in big.frames[:20]:
            t = time.perf_counter()
            mod.track_image(f, None, 40.0)
            single.append(time.perf_counter() - t)
            t = time.perf_counter()
            mod.track_frame(f)
            whole.append(time.perf_counter() - t)
    movie512, per_frame = [], []
    for _ in range(repeat):
        t = time.perf_counter()
        tr = track(big.frames[:100], px_per_mm=big.px_per_mm, fps=FPS)
        dt = time.perf_counter() - t
        movie512.append(dt)
        per_frame.append(dt / 100)
    small = render(sim, um_per_px=14.0, snr=3.0, seed=0)
    movie = []
    for _ in range(repeat):
        t = time.perf_counter()
        tr = track(small.frames[:100], px_per_mm=small.px_per_mm, fps=FPS)
        movie.append(time.perf_counter() - t)
    stat = lambda v: {"min": min(v), "median": statistics.median(v)}  # noqa: E731
    return {"frame_512_scratch_s": stat(single), "frame_512_whole_frame_s": stat(whole),
            "frame_512_in_movie_s": stat(per_frame),
            "movie_512_100_frames_s": stat(movie512), "movie_100_frames_s": stat(movie),
            "movie_shape": list(small.frames.shape), "n_failed_512": int(tr.meta["n_failed"])}


def measure(mv, **labels) -> dict:
    """Track a rendered movie and compare with its truth: pixel errors and the descriptors'
    relative errors [%] (``labels`` are copied into the row)."""
    from flutterswim.analysis.descriptors import describe
    from flutterswim.tracking import track
    from flutterswim.tracking.evaluate import pixel_errors, truth_track

    tr = track(mv, px_per_mm=mv.px_per_mm, fps=FPS, t0=float(mv.t[0]))
    D, E, _ = pixel_errors(tr, mv)
    truth = truth_track(mv, 3.7)
    dt, dm = describe(truth, n_last=100), describe(tr, n_last=100)
    row = {**labels, "failed": int(tr.meta["n_failed"]),
           "centreline_rms_px": float(np.sqrt(np.mean(D**2))),
           "worst_frame_rms_px": float(np.sqrt(np.mean(D**2, axis=1)).max()),
           "tip_rms_px": float(np.sqrt(np.mean(E**2))), "tip_max_px": float(E.max()),
           "length_spread": tr.meta["length_spread"], "cycles": dm.n_cycles_used,
           "tip_outliers": sum(r.startswith("tip outlier") for r in tr.meta["frames"]["reason"]),
           "smoothing": tr.meta["temporal"]["smoothing"].split(",")[0],
           "periodic": tr.meta["temporal"]["periodic"].split(":")[0],
           "periodic_drift_f": tr.meta["temporal"].get("periodic_info", {}).get("drift_f")}
    for k in KEYS:
        row[k + "_rel_err_pct"] = 100 * (getattr(dm, k) - getattr(dt, k)) / getattr(dt, k)
    print(json.dumps(row), flush=True)
    return row


def accuracy(sim, seeds: int) -> list[dict]:
    from flutterswim.tracking import render

    return [measure(render(sim, um_per_px=14.0, snr=snr, seed=seed), snr=snr, seed=seed)
            for snr in (math.inf, 10.0, 5.0, 3.0) for seed in range(1 if math.isinf(snr) else seeds)]


# degraded and longer movies of the settled stroke: (label, frames, render options)
DEGRADED = (
    ("reference, SNR 5", 101, {"snr": 5.0}),
    ("defocus 1.5 px, SNR 5", 101, {"snr": 5.0, "defocus": 1.5}),
    ("background gradient 100 %, SNR 5", 101, {"snr": 5.0, "gradient": 1.0}),
    ("uint16 frames, SNR 5", 101, {"snr": 5.0, "dtype": "uint16"}),
    ("PSF sigma 2 px, SNR 5", 101, {"snr": 5.0, "psf_sigma": 2.0}),
    ("10 um/px, SNR 5", 101, {"snr": 5.0, "um_per_px": 10.0}),
    ("20 um/px, SNR 5", 101, {"snr": 5.0, "um_per_px": 20.0}),
    ("20 um/px, SNR 3", 101, {"snr": 3.0, "um_per_px": 20.0}),
    ("dim: background 10, read noise 5, SNR 5", 101, {"snr": 5.0, "background": 10.0, "read_noise": 5.0}),
    ("3.2 cycles (60 frames), SNR 5", 60, {"snr": 5.0}),
    ("10.7 cycles (201 frames), SNR 3", 201, {"snr": 3.0}),
)


def degraded(seeds: int) -> list[dict]:
    """Every condition of DEGRADED on the stroke settled at 14 s (the last 10.7 cycles of it
    are periodic to the drift test), ``seeds`` noise draws each. ``snr_effective``: the line's
    peak over the background noise after defocus (photons conserved, the peak drops)."""
    from flutterswim.tracking import render

    full = stroke(max(n for _, n, _ in DEGRADED), t_end=14.0)  # simulated once; each movie its last n frames
    rows = []
    for label, n, opts in DEGRADED:
        sim = SimpleNamespace(t=full.t[-n:], x=full.x[-n:], y=full.y[-n:])
        for seed in range(seeds):
            mv = render(sim, seed=seed, **{"um_per_px": 14.0, **opts})
            eff = mv.meta["amplitude"] / math.sqrt(mv.meta["background"] + mv.meta["read_noise"] ** 2)
            rows.append(measure(mv, condition=label, seed=seed, snr_effective=eff))
    return rows


def failures_and_mp4(sim) -> dict:
    import imageio_ffmpeg

    from flutterswim.analysis.descriptors import describe
    from flutterswim.tracking import failures, render, track

    out = {}
    for snr in (0.5, 0.7, 0.9):
        bad = render(sim, um_per_px=14.0, snr=snr, seed=3)
        try:
            tr = track(bad.frames[:50], px_per_mm=bad.px_per_mm, fps=FPS)
            out[f"snr_{snr}_flagged"] = f"{len(failures(tr))} of 50"
        except Exception as exc:  # noqa: BLE001 - every frame failed: reported by the error
            out[f"snr_{snr}_flagged"] = f"50 of 50 ({str(exc)[:80]}...)"
    mv = render(sim, um_per_px=14.0, snr=3.0, seed=0)
    ref = describe(track(mv, px_per_mm=mv.px_per_mm, fps=FPS))
    lo, hi = np.percentile(mv.frames, [0.1, 99.99])
    f8 = np.clip((mv.frames - lo) / (hi - lo) * 255, 0, 255).astype(np.uint8)
    f8 = f8[:, : f8.shape[1] // 2 * 2, : f8.shape[2] // 2 * 2]
    path = "/tmp/bench_tracking.mp4"
    w = imageio_ffmpeg.write_frames(path, (f8.shape[2], f8.shape[1]), pix_fmt_in="gray", fps=FPS, quality=8,
                                    macro_block_size=1)
    w.send(None)
    for f in f8:
        w.send(np.ascontiguousarray(f))
    w.close()
    d = describe(track(path, px_per_mm=mv.px_per_mm))
    out["mp4_vs_lossless_rel_err_pct"] = {k: 100 * (getattr(d, k) - getattr(ref, k)) / getattr(ref, k) for k in KEYS}
    os.remove(path)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--json", default=None)
    ap.add_argument("--no-periodic", action="store_true", help="track without the periodic shape template (before/after)")
    ap.add_argument("--degraded", action="store_true", help="only the accuracy on degraded and longer movies (DEGRADED)")
    args = ap.parse_args()
    if args.no_periodic:  # the functions above import track from the package when they run
        import flutterswim.tracking as pkg

        orig = pkg.track
        pkg.track = lambda *a, **k: orig(*a, **{**k, "periodic": False})
    if args.degraded:
        res = {"machine": machine(), "degraded": degraded(args.seeds)}
        if args.json:
            with open(args.json, "w") as f:
                json.dump(res, f, indent=1)
        return
    sim = stroke()
    res = {"machine": machine(), "speed": speed(sim, args.repeat)}
    print(json.dumps(res, indent=1), flush=True)
    res["accuracy"] = accuracy(sim, args.seeds)
    res["failures_and_mp4"] = failures_and_mp4(sim)
    print(json.dumps(res["failures_and_mp4"], indent=1))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=1)


if __name__ == "__main__":
    main()
