"""Frame sources: a TIFF stack, a folder of PNG or TIFF frames, an MP4 or AVI movie, or an
array, read lazily one grey-level frame at a time (float32, (H, W)), optionally cropped.

ROI: (x0, y0, x1, y1) in pixels of the full frame, columns x0 <= x < x1, rows y0 <= y < y1.
"""

from __future__ import annotations

import logging
import math
import os
import re
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from .._validate import ParameterError

__all__ = ["Frames", "open_frames", "parse_roi", "read_times", "FRAME_SUFFIXES", "MOVIE_SUFFIXES", "STACK_SUFFIXES"]

STACK_SUFFIXES = (".tif", ".tiff")
FRAME_SUFFIXES = (".png", ".tif", ".tiff")
MOVIE_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv")


def _gray(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a)
    if a.ndim == 3 and a.shape[-1] in (3, 4):
        a = a[..., :3].astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)
    elif a.ndim == 3 and a.shape[-1] == 2:  # grey and alpha: the alpha dropped, as a colour image's
        a = a[..., 0]
    if a.ndim != 2:
        raise ParameterError(f"a frame has shape {a.shape}; a grey-level (H, W) or colour (H, W, 3) image is required")
    return a.astype(np.float32, copy=False)


def _natural_key(p: Path, decimals: bool = True) -> list:
    """Sort key of a frame's file name: its numbers by value (frame_2 before frame_10), with
    ``decimals`` a number with a decimal point as one (t0.02s before t0.1s), the rest by text."""
    from decimal import Decimal  # (exact: a 17-digit timestamp is beyond a float's precision)

    rx = r"(\d+(?:\.\d+)?)" if decimals else r"(\d+)"
    return [Decimal(t) if k % 2 else t.lower() for k, t in enumerate(re.split(rx, p.name))]


def _evenly_numbered(files: list[Path], decimals: bool) -> bool:
    """Whether, in this order, the last number that changes between the names steps evenly."""
    keys = [_natural_key(f, decimals)[1::2] for f in files]
    if len({len(k) for k in keys}) != 1 or not keys or not keys[0]:
        return False
    cols = [j for j in range(len(keys[0])) if len({k[j] for k in keys}) > 1]
    if not cols:
        return False
    v = np.array([float(k[cols[-1]]) for k in keys])
    d = np.diff(v)
    return bool(np.all(d > 0) and np.ptp(d) <= 1e-6 * np.max(np.abs(v)) + 1e-9 * np.median(d))


def _frame_order(files: list[Path], where: str) -> list[Path]:
    """The frames in the order of the numbers in their names. Read as decimals (t0.02s, t0.1s)
    and as whole numbers (trial1.2, trial1.10) the numbers may order the frames differently:
    the reading that tells every name apart is taken; if both or neither do, the order is
    ambiguous and refused (it silently shuffled frames: a period 10-20 % off)."""
    orders = []
    for decimals in (True, False):
        keys = [_natural_key(f, decimals) for f in files]
        distinct = len({tuple(k) for k in keys}) == len(keys)
        orders.append((distinct, [f for _, f in sorted(zip(keys, files), key=lambda kf: kf[0])]))
    (dec_ok, by_dec), (int_ok, by_int) = orders
    if by_dec == by_int or (dec_ok and not int_ok):
        return by_dec
    if int_ok and not dec_ok:
        return by_int
    # both tell the names apart: the reading under which the numbers step evenly (a frame rate:
    # t0.1s, t0.15s, t0.2s ...; a counter: trial1.9, trial1.10 ...) when only one does
    even = [_evenly_numbered(order, decimals) for order, decimals in ((by_dec, True), (by_int, False))]
    if even[0] != even[1]:
        return by_dec if even[0] else by_int
    raise ParameterError(f"input={where!r}: the frames' names order them differently read as decimals "
                         f"({by_dec[0].name}, {by_dec[1].name}, ...) and as whole numbers ({by_int[0].name}, "
                         f"{by_int[1].name}, ...); rename them with zero-padded frame numbers, or give a TIFF stack")


@dataclass
class Frames:
    """A lazy sequence of frames: ``len``, iteration and indexing give (H, W) float32 frames
    (cropped to ``roi``). fps: the container's frame rate if known (movies), else None."""

    source: str
    n_frames: int
    shape: tuple[int, int]
    fps: float | None
    _get: Callable[[int], np.ndarray]
    _iter: Callable[[], Iterator[np.ndarray]]
    roi: tuple[int, int, int, int] | None = None
    note: str = ""  # how the file was read, when it could be read another way
    sequential: bool = False  # a movie: indexing decodes every frame into memory once
    names: tuple[str, ...] = ()  # a folder's frame files, in the order read

    def __len__(self) -> int:
        return self.n_frames

    def _crop(self, a: np.ndarray) -> np.ndarray:
        if self.roi is None:
            return a
        x0, y0, x1, y1 = self.roi
        return a[y0:y1, x0:x1]

    def __getitem__(self, i: int) -> np.ndarray:
        return self._crop(_gray(self._get(int(i))))

    def __iter__(self) -> Iterator[np.ndarray]:
        for a in self._iter():
            yield self._crop(_gray(a))

    def take(self, indices: Any) -> list[np.ndarray]:
        """Frames ``indices`` (increasing): by index, or for a movie (no random access without
        decoding it all into memory) in one pass that keeps only those."""
        idx = [int(i) for i in indices]
        if not self.sequential:
            return [self[i] for i in idx]
        want, out = set(idx), {}
        for i, a in enumerate(self):
            if i in want:
                out[i] = a
                if len(out) == len(want):
                    break
        return [out[i] for i in idx]


def parse_roi(roi: Any, shape: tuple[int, int] | None) -> tuple[int, int, int, int] | None:
    """(x0, y0, x1, y1) from a tuple or the string "x0,y0,x1,y1", checked against the frame
    shape (H, W) (None: only the numbers and their order)."""
    if roi is None:
        return None
    if isinstance(roi, str):
        parts = roi.replace(" ", "").split(",")
    else:
        parts = list(roi)
    try:
        x0, y0, x1, y1 = (int(float(v)) for v in parts)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"roi={roi!r} must be four integers x0,y0,x1,y1 (pixels)") from None
    if shape is None:  # the numbers alone (the frame not read yet)
        if not (0 <= x0 < x1 and 0 <= y0 < y1) or x1 - x0 < 8 or y1 - y0 < 8:
            raise ParameterError(f"roi={roi!r} must satisfy 0 <= x0 < x1 and 0 <= y0 < y1 and span at least "
                                 "8 x 8 pixels")
        return x0, y0, x1, y1
    H, W = shape
    if not (0 <= x0 < x1 <= W and 0 <= y0 < y1 <= H) or x1 - x0 < 8 or y1 - y0 < 8:
        raise ParameterError(f"roi={roi!r} must satisfy 0 <= x0 < x1 <= {W} and 0 <= y0 < y1 <= {H} "
                             "(frame width and height) and span at least 8 x 8 pixels")
    return x0, y0, x1, y1


def _from_array(a: np.ndarray, name: str) -> Frames:
    if not (a.ndim == 3 or (a.ndim == 4 and a.shape[-1] in (3, 4))):
        raise ParameterError(f"input array has shape {a.shape}; (T, H, W) or (T, H, W, 3|4) is required")
    return Frames(name, a.shape[0], tuple(a.shape[1:3]), None, lambda i: a[i], lambda: iter(a))


@contextmanager
def _tifffile_said() -> Iterator[list[str]]:
    """tifffile's log messages during a read, kept here instead of printed to stderr."""
    said: list[str] = []

    def keep(record: logging.LogRecord) -> bool:
        if record.levelno < logging.WARNING:
            return True
        # tifffile starts its messages with repr(self), e.g. "<tifffile.TiffPages @8> ..."
        said.append(re.sub(r"^<[^>]*>\s*", "", record.getMessage()))
        return False

    log = logging.getLogger("tifffile")
    log.addFilter(keep)
    try:
        yield said
    finally:
        log.removeFilter(keep)


def _tiff_stack(p: Path) -> Frames:
    import tifffile

    with _tifffile_said() as said:
        try:
            with tifffile.TiffFile(p) as tf:
                axes, shape = tf.series[0].axes, tuple(tf.series[0].shape)
                fps = _tiff_frame_rate(tf)
            try:
                arr = tifffile.memmap(p, mode="r")  # uncompressed: frames read on demand
            except (ValueError, tifffile.TiffFileError, OSError):
                arr = tifffile.imread(p)
        except (MemoryError, PermissionError):
            raise
        except Exception as exc:  # a damaged file fails in many ways inside tifffile
            why = said[0] if said else f"{type(exc).__name__}: {exc}"
            raise ParameterError(f"input={str(p)!r} cannot be read as a TIFF stack ({why})") from None
    if said:  # read, but damaged (e.g. truncated: the pages after the damage are missing)
        warnings.warn(f"input={str(p)!r}: tifffile: {said[0]}", stacklevel=3)
    arr = np.asarray(arr) if not isinstance(arr, np.memmap) else arr
    note = ""
    if len(axes) == arr.ndim and "S" in axes[:-1] and arr.shape[axes.index("S")] in (3, 4):
        arr, axes = np.moveaxis(arr, axes.index("S"), -1), axes.replace("S", "") + "S"  # planar colour
        if arr.ndim == 3:
            note = (f" (its tags say {shape} is one planar colour image, {shape[0]} samples per pixel; a grey stack "
                    "of that many frames must be saved as one, e.g. tifffile.imwrite(..., photometric='minisblack'))")
    colour = axes.endswith("S") and arr.shape[-1] in (3, 4)
    if arr.ndim == 2 + colour:
        arr = arr[None]  # one frame
    if arr.ndim != 3 + colour:
        raise ParameterError(
            f"input={str(p)!r} is a TIFF stack of shape {shape} (axes {axes!r}); a (T, H, W) stack, a colour "
            "(T, H, W, 3|4) stack or one (H, W) frame is required: for a (T, Z, H, W) or (T, C, H, W) stack, "
            "pass one Z plane or channel")
    fr = _from_array(arr, str(p))
    fr.note = note
    fr.fps = fps
    return fr


#: ImageJ's time units (its calibration's ``tunit``; "sec" when absent) in seconds
_IMAGEJ_TIME_UNITS = {"sec": 1.0, "s": 1.0, "second": 1.0, "seconds": 1.0, "ms": 1e-3, "msec": 1e-3,
                      "millisecond": 1e-3, "milliseconds": 1e-3, "us": 1e-6, "\u00b5s": 1e-6, "\u03bcs": 1e-6,
                      "usec": 1e-6, "microsecond": 1e-6, "microseconds": 1e-6, "min": 60.0, "minute": 60.0,
                      "minutes": 60.0}


def _tiff_frame_rate(tf) -> float | None:
    """The frame rate an ImageJ stack records: 1 / its frame interval ``finterval`` in its time
    unit ``tunit`` (seconds when absent), else None (an unknown unit too). Its ``fps`` is the
    animation's playback speed, not the camera's, and is not used."""
    meta = tf.imagej_metadata or {}
    try:
        v = float(meta.get("finterval", 0) or 0)
    except (TypeError, ValueError):
        return None
    unit = _IMAGEJ_TIME_UNITS.get(str(meta.get("tunit", "sec")).strip().lower())
    if unit is None or not (math.isfinite(v) and v > 0):
        return None
    return 1.0 / (v * unit)


def _read_image(p: Path) -> np.ndarray:
    try:
        if p.suffix.lower() in STACK_SUFFIXES:
            import tifffile

            return tifffile.imread(p)
        import imageio.v3 as iio

        return iio.imread(p)
    except (MemoryError, PermissionError):
        raise
    except Exception as exc:  # a damaged (e.g. truncated) frame fails in many ways inside the readers
        raise ParameterError(f"frame {str(p)!r} cannot be read as an image ({type(exc).__name__}: "
                             f"{' '.join(str(exc).split())})") from None


def _image_shape(p: Path) -> tuple[int, ...]:
    """The shape :func:`_read_image` gives, from the file's header."""
    try:
        if p.suffix.lower() in STACK_SUFFIXES:
            import tifffile

            with _tifffile_said(), tifffile.TiffFile(p) as tf:
                return tuple(tf.series[0].shape)
        import imageio.v3 as iio

        return tuple(iio.improps(p).shape)
    except (MemoryError, PermissionError):
        raise
    except Exception as exc:  # a damaged file fails in many ways inside the readers
        raise ParameterError(f"frame {str(p)!r} cannot be read as an image ({type(exc).__name__}: {exc})") from None


def _folder(p: Path) -> Frames:
    # hidden files are not frames (macOS leaves "._frame1.png" companions beside copied files)
    files = _frame_order(sorted((f for f in p.iterdir() if f.is_file() and f.suffix.lower() in FRAME_SUFFIXES
                                 and not f.name.startswith(".")), key=lambda f: f.name), str(p))
    if not files:
        raise ParameterError(f"input={str(p)!r} is a folder without PNG or TIFF frames")
    sfx = {f.suffix.lower().replace(".tiff", ".tif") for f in files}
    if len(sfx) > 1:
        raise ParameterError(f"input={str(p)!r} mixes frame formats {sorted(sfx)}; one format per folder is required")
    first = _gray(_read_image(files[0]))
    want = _image_shape(files[0])
    for f in files[1:]:
        if (got := _image_shape(f)) != want:
            raise ParameterError(f"input={str(p)!r}: frame {f.name!r} has shape {got} but the first frame "
                                 f"{files[0].name!r} has {want}; all frames must have one size and channel count")
    return Frames(str(p), len(files), first.shape, None, lambda i: _read_image(files[i]),
                  lambda: (_read_image(f) for f in files), names=tuple(f.name for f in files))


def _ffmpeg_said(exc: BaseException) -> str:
    """A short reason from an imageio-ffmpeg error, whose text holds ffmpeg's whole log: its
    first line and the log's last line (ffmpeg's verdict), without the "[in#0 @ 0x...]" tags."""
    lines = [" ".join(re.sub(r"\[[^\]]*@ 0x[0-9a-f]+\]", "", ln).split()) for ln in str(exc).splitlines()]
    lines = [ln for ln in lines if ln and not ln.startswith("===")]
    if not lines:
        return type(exc).__name__
    said = lines[0] if len(lines) == 1 else f"{lines[0]}: {lines[-1]}"
    return said if len(said) <= 200 else said[:197] + "..."


def _avi_truncated(p: Path) -> tuple[int, int] | None:
    """(bytes the AVI's RIFF chunks declare, bytes the file has) when the file is shorter than
    its chunks say (cut), else None (complete, or not an AVI). The chunk sizes, not the frame
    count: capture software lists dropped frames as empty chunks, which decode to nothing."""
    import struct

    try:
        size = p.stat().st_size
        with open(p, "rb") as fh:
            head = fh.read(12)
            if len(head) < 12 or head[:4] != b"RIFF" or head[8:12] != b"AVI ":
                return None
            at = 0
            while at + 8 <= size:  # RIFF 'AVI ' then, in an OpenDML file, RIFF 'AVIX' chunks
                fh.seek(at)
                tag, n = struct.unpack("<4sI", fh.read(8))
                if tag != b"RIFF" or n in (0, 0xFFFFFFFF):
                    # (0 or all ones: a writer that could not seek back, to a pipe, or a crashed
                    # capture: the size says nothing)
                    return None
                at += 8 + n + (n & 1)
            return (at, size) if at > size + 1 else None  # (+1: a last odd chunk's pad byte)
    except OSError:
        return None


def _movie(p: Path) -> Frames:
    import imageio_ffmpeg

    try:
        gen = imageio_ffmpeg.read_frames(str(p), pix_fmt="gray", bpp=1)
        meta = gen.__next__()
        gen.close()
        W, H = meta["size"]
        # a stream of more than 8 bits per sample (gray16le, yuv420p10le, rgb48 ...) is read at 16:
        # at 8 a lossless 16-bit movie of a line 52 counts over its background came out as 0s and 1s
        deep = bool(re.search(r"(?:gray|yuv\w*p|gbrp|rgb|bgr)(?:9|1[0-6]|48|64)", str(meta.get("pix_fmt", ""))))
        fmt, bpp, dtype = ("gray16le", 2, np.uint16) if deep else ("gray", 1, np.uint8)
        fps = float(meta.get("fps") or 0) or None
        n, _ = imageio_ffmpeg.count_frames_and_secs(str(p))
    except (MemoryError, PermissionError):
        raise
    except Exception as exc:  # an empty, truncated or foreign file: ffmpeg's log is in the message
        raise ParameterError(f"input={str(p)!r} cannot be read as a movie ({_ffmpeg_said(exc)})") from None
    cut = _avi_truncated(p)
    if cut is not None:
        # (ffmpeg estimates a cut file's length from its size: only the chunks' sizes tell)
        import warnings

        warnings.warn(f"input={str(p)!r}: the file is truncated ({cut[1]} of the {cut[0]} bytes its chunks "
                      f"declare); the {n} frames that can be read are tracked", stacklevel=3)

    def it() -> Iterator[np.ndarray]:
        g = imageio_ffmpeg.read_frames(str(p), pix_fmt=fmt, bpp=bpp)
        try:
            g.__next__()
            for buf in g:
                yield np.frombuffer(buf, dtype).reshape(H, W)
        except (MemoryError, GeneratorExit):
            raise
        except Exception as exc:  # damaged after its header
            raise ParameterError(f"input={str(p)!r} cannot be read as a movie ({_ffmpeg_said(exc)})") from None
        finally:
            g.close()

    cache: dict[int, np.ndarray] = {}

    def get(i: int) -> np.ndarray:
        if not cache:
            for k, a in enumerate(it()):
                cache[k] = a
        return cache[i]

    return Frames(str(p), int(n), (H, W), fps, get, it, sequential=True)


def open_frames(source: Any, roi: Any = None) -> Frames:
    """Frames from a path (TIFF stack (T, H, W) or colour (T, H, W, 3|4), folder of PNG/TIFF
    frames of one shape, MP4/AVI movie), an array (T, H, W), or an object with a ``frames``
    array (a rendered :class:`Movie`). A damaged file or another shape is a ParameterError."""
    if hasattr(source, "frames") and isinstance(source.frames, np.ndarray):
        fr = _from_array(source.frames, "movie")
        fr.fps = getattr(source, "fps", None)
    elif isinstance(source, np.ndarray):
        fr = _from_array(source, "array")
    elif isinstance(source, (list, tuple)) and source and all(isinstance(a, np.ndarray) for a in source):
        shapes = {a.shape for a in source}
        if len(shapes) != 1:
            raise ParameterError(f"input: a list of {len(source)} frames of shapes {sorted(shapes)[:3]}; frames of one "
                                 "shape are required")
        fr = _from_array(np.stack(source), "list of frames")
    else:
        try:
            p = Path(os.fspath(source))
        except TypeError:
            # (not its repr: an array's contents ran to thousands of characters)
            raise ParameterError(f"input of type {type(source).__name__} is not a path, an array of frames (T, H, W) or "
                                 "a list of frames (H, W)") from None
        if not p.exists():
            raise ParameterError(f"input={str(p)!r} does not exist")
        if p.is_dir():
            fr = _folder(p)
        elif p.suffix.lower() in STACK_SUFFIXES:
            fr = _tiff_stack(p)
        elif p.suffix.lower() in MOVIE_SUFFIXES:
            fr = _movie(p)
        else:
            raise ParameterError(f"input={str(p)!r} has the suffix {p.suffix!r}; a TIFF stack (.tif), a folder "
                                 f"of PNG/TIFF frames or a movie ({', '.join(MOVIE_SUFFIXES)}) is required")
    if fr.n_frames < 2:
        raise ParameterError(f"input={fr.source!r} holds {fr.n_frames} frame(s); at least 2 are required{fr.note}")
    fr.roi = parse_roi(roi, fr.shape)
    if fr.roi is not None:
        x0, y0, x1, y1 = fr.roi
        fr.shape = (y1 - y0, x1 - x0)
    return fr


# column names of a timestamps file, and the factor to seconds
#: header names of a time column (lower case, unit removed) and the units a header may give
#: (a suffix _s, _ms, _us or a unit in brackets: "Time (ms)", "t [s]")
_TIME_NAMES = ("t", "time", "timestamp", "time stamp", "elapsed", "elapsed time", "time elapsed", "relative time",
               "frame time", "capture time", "acquisition time", "time since start")
_TIME_UNITS = {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "\u00b5s": 1e-6, "\u03bcs": 1e-6}


def _time_header(field: str) -> float | None:
    """The factor to seconds if ``field`` names a time column, else None."""
    f = field.strip().strip('"').strip("'").strip().lower()
    m = re.fullmatch(r"(.*?)\s*[\(\[]\s*([^\)\]]*?)\s*[\)\]]", f)
    unit = None
    if m:
        f, unit = m.group(1).strip(), m.group(2)
    else:
        m = re.fullmatch(r"(.*?)[ _]([a-z\u00b5\u03bc]+)", f)
        # (words joined by underscores as by spaces: elapsed_time_ms had been refused)
        if m and m.group(2) in _TIME_UNITS and re.sub(r"[_\s]+", " ", m.group(1).strip()) in _TIME_NAMES:
            f, unit = m.group(1).strip(), m.group(2)
    f = re.sub(r"[_\s]+", " ", f)
    if f not in _TIME_NAMES:
        return None
    if unit is None:
        return 1.0
    return _TIME_UNITS.get(unit)


def _delimiter(line: str) -> str:
    """The rows' field separator: a comma, a semicolon or a tab when the line holds one, else
    white space (a header's names may hold spaces: "Time (ms)")."""
    for d in (",", ";", "\t"):
        if d in line:
            return re.escape(d)
    return r"\s+"


def read_times(path: str | os.PathLike) -> np.ndarray:
    """The frames' times [s] from a text or CSV file (a camera's timestamps): one row per frame,
    fields separated by commas, semicolons, tabs or (when a row holds none of these) white space;
    blank lines and lines starting with ``#`` are skipped. A first row with a field that is not a
    number is a header naming the time column (t, time, timestamp, elapsed time, ...; any case),
    with its unit as a suffix (``time_ms``) or in brackets (``Time (ms)``, ``t [s]``): s, ms or
    us; a name without a unit is seconds. Without a header the first column holds seconds.
    Whether the times are one per frame, increasing and consistent with a movie's own frame rate
    is checked by :func:`~flutterswim.tracking.track.track`."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError(f"times={str(p)!r} cannot be read ({exc.strerror if isinstance(exc, OSError) else exc})") from None
    lines = [(n, line.strip()) for n, line in enumerate(text.splitlines(), 1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise ParameterError(f"times={str(p)!r} holds no times")
    sep = _delimiter(lines[0][1])
    if sep == r"\s+":  # a unit in brackets stays with its name: "Time [ms]"
        lines = [(n, re.sub(r"\s+([\(\[])", r"\1", line)) for n, line in lines]
    rows = [(n, [v.strip() for v in re.split(sep, line)]) for n, line in lines]

    def number(v: str) -> float | None:
        try:
            return float(v)
        except ValueError:
            return None

    col, factor = 0, 1.0
    n0, first = rows[0]
    if sep == r"\s+" and len(rows) > 1 and any(number(v) is None for v in first):
        # columns separated by white space, whose header's names may hold spaces: "Elapsed Time
        # (ms)" split into "Elapsed" (a name without its unit: seconds) and "Time(ms)"
        width = len(rows[1][1])
        if width == 1:
            first = [lines[0][1]]  # one column: the whole line names it
        elif len(first) != width or any(_time_header(a) is not None and _time_header(f"{a} {b}") not in
                                        (None, _time_header(a)) for a, b in zip(first, first[1:])):
            # (two words that name a time together with a unit, "Time Stamp(ms)", over two
            # columns: one name whose unit the other column took, or two names? the unit is in doubt)
            raise ParameterError(f"times={str(p)!r}: its header (row {n0}) names {width} columns separated by spaces "
                                 "with names that may hold spaces; separate the columns by commas or tabs")
    if any(number(v) is None for v in first):
        found = [(k, _time_header(v)) for k, v in enumerate(first)]
        named = [(k, f) for k, f in found if f is not None]
        if not named:
            bad_unit = [v for v in first if re.sub(r"\s*[\(\[].*", "", v.strip().strip('"').lower()) in _TIME_NAMES]
            if bad_unit:
                raise ParameterError(f"times={str(p)!r}: its header (row {n0}) gives the time column {bad_unit[0]!r} in "
                                     f"a unit not understood; give s, ms or us")
            raise ParameterError(f"times={str(p)!r}: its header (row {n0}) names no time column; name one "
                                 f"{', '.join(_TIME_NAMES)} (a unit as time_ms or Time (ms)), or give one time [s] per "
                                 "row without a header")
        col, factor = named[0]
        rows = rows[1:]
    out = []
    for n, fields in rows:
        v = number(fields[col]) if col < len(fields) else None
        if v is None:
            raise ParameterError(f"times={str(p)!r}, row {n}: {fields[col] if col < len(fields) else ''!r} is not a time "
                                 "(a number of seconds)")
        out.append(v * factor)
    return np.asarray(out, float)
