"""Safe output paths: checks before computing, atomic writes, and the store marker.

- :func:`check_output_file`: the path is not a directory, its folder exists (none is created
  for a file) and is writable, its suffix is one of those allowed. Call it before any computation.
- :func:`atomic_path`: write to a temporary name in the same folder, then ``os.replace``:
  an interrupted save leaves the old file or the new one, never a truncated one.
- :func:`check_store_path` / :func:`remove_own_store`: a store directory is replaced only if
  it carries our marker file (:data:`MARKER`); the current directory, plain directories,
  files and Zarr stores of other tools are refused.
"""

from __future__ import annotations

import collections
import contextlib
import errno
import json
import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Iterator, Sequence

from ._validate import ParameterError

__all__ = ["MARKER", "SIGNATURE", "FINGERPRINT", "is_ours", "write_netcdf", "row_signature", "save_figure_file", "figure_metadata", "mark_gif", "check_output_file", "check_output_dir", "atomic_path", "atomic_write_text",
           "check_store_path", "write_marker", "has_marker", "remove_own_store"]

#: File inside every store flutterswim creates; nothing without it is ever deleted.
MARKER = ".flutterswim-store"
#: What every file flutterswim writes carries, in a field of its format's own metadata (a NetCDF
#: file's ``source`` attribute, a figure's Software/Creator/comment, a GIF or MP4 comment, a
#: JSON file's ``generator``, a CSV's ``tracked_by`` column, an HTML report's generator tag).
SIGNATURE = b"flutterswim"
_SCAN = 64 << 20
_TAG = re.compile(rb"flutterswim[ :]")


def _scan(p: Path, pattern: re.Pattern) -> bool:
    """The pattern in the file's first or last 64 MiB."""
    size = p.stat().st_size
    with open(p, "rb") as f:
        if pattern.search(f.read(_SCAN)):
            return True
        if size > _SCAN:
            f.seek(max(_SCAN - 4096, size - _SCAN))
            return bool(pattern.search(f.read()))
    return False


#: NetCDF attribute holding the SHA-256 of the file's variables as written (:func:`write_netcdf`)
FINGERPRINT = "flutterswim_fingerprint"


def _h5_fingerprint(h) -> str:
    """SHA-256 of every dataset of an open HDF5 file (NetCDF-4): its name, type, shape and stored
    values, in name order. Attributes are left out (a file's title or comments are not its data)."""
    import hashlib

    import numpy as np

    items: list = []
    h.visititems(lambda name, obj: items.append((name, obj)) if hasattr(obj, "shape") else None)
    digest = hashlib.sha256()
    for name, d in sorted(items, key=lambda it: it[0]):
        digest.update(f"{name}|{d.dtype.str}|{d.shape}|".encode())
        if d.dtype.kind == "O":  # variable-length strings
            digest.update("\x1f".join(str(v) for v in np.ravel(d.asstr()[()])).encode())
        elif d.size and d.ndim == 0:
            digest.update(np.ascontiguousarray(d[()]).tobytes())
        elif d.size:  # in blocks of rows (~16 MB: a 1 GB run is not read into memory whole)
            rows = max(1, int(16e6 // max(1, d.dtype.itemsize * (d.size // d.shape[0]))))
            for i in range(0, d.shape[0], rows):
                digest.update(np.ascontiguousarray(d[i:i + rows]).tobytes())
    return digest.hexdigest()


def _netcdf_ours(p: Path) -> bool:
    """Signed by flutterswim (its ``source``) and, when it records one, with the variables it was
    written with (:data:`FINGERPRINT`): a file another tool re-wrote from ours keeps our signature
    in its copied attributes (xarray carries them), but not our data."""
    with open(p, "rb") as f:
        if f.read(8) != b"\x89HDF\r\n\x1a\n":
            return False
    import h5py

    with h5py.File(p, "r") as h:
        src = h.attrs.get("source", b"")
        src = src.decode("utf-8", "replace") if isinstance(src, bytes) else str(src)
        if not src.startswith("flutterswim "):
            return False
        fp = h.attrs.get(FINGERPRINT)
        if fp is None:  # (written before fingerprints: the signature alone)
            return True
        fp = fp.decode() if isinstance(fp, bytes) else str(fp)
        return fp == _h5_fingerprint(h)


def write_netcdf(ds, path: str | os.PathLike, **kwargs) -> Path:
    """Write the xarray Dataset ``ds`` to NetCDF-4 (h5netcdf engine) atomically, with the
    fingerprint of its variables as written (:data:`FINGERPRINT`), so that only this file, not
    one derived from it, is taken for ours. ``kwargs`` go to ``to_netcdf`` (encoding ...)."""
    import io

    import h5py

    p = Path(os.fspath(path))
    if ds.nbytes > IN_MEMORY_NETCDF_BYTES:
        # (in memory a file needs about twice its size again: +808 MB for a 400 MB run) written by
        # HDF5, after a check that it fits: HDF5 meeting a full disk crashes the interpreter
        _check_room(p, int(1.05 * ds.nbytes) + (1 << 20))
        with atomic_path(p) as tmp:
            ds.to_netcdf(tmp, engine="h5netcdf", **kwargs)
            with h5py.File(tmp, "r+") as h:
                h.attrs[FINGERPRINT] = _h5_fingerprint(h)
        return p
    # built in memory, written by Python: HDF5 writing a file onto a full disk (or past a file
    # size limit) crashed the interpreter (a segmentation fault, a notebook's kernel lost) after
    # the OSError; Python's own write raises it and the temporary file is removed
    buf = io.BytesIO(ds.to_netcdf(engine="h5netcdf", **kwargs))
    with h5py.File(buf, "r+") as h:
        h.attrs[FINGERPRINT] = _h5_fingerprint(h)
    with atomic_path(p) as tmp:
        _write_bytes(tmp, buf.getbuffer())
    return p


#: a dataset up to this size is written to NetCDF in memory first (safe on a full disk), a larger
#: one by HDF5 directly after a check that it fits
IN_MEMORY_NETCDF_BYTES = 256 << 20


def _check_room(p: Path, need: int) -> None:
    """OSError (ENOSPC / EFBIG) before writing ``need`` bytes beside ``p``, where the disk or
    the process's file size limit has no room for them."""
    import resource

    free = shutil.disk_usage(p.parent if str(p.parent) else ".").free
    if need > free:
        raise OSError(errno.ENOSPC, f"No space left on device for {str(p)!r}: about {need / 1e6:.0f} MB needed, "
                                    f"{free / 1e6:.0f} MB free")
    soft, _ = resource.getrlimit(resource.RLIMIT_FSIZE)
    if soft != resource.RLIM_INFINITY and need > soft:
        raise OSError(errno.EFBIG, f"File too large: {str(p)!r} needs about {need / 1e6:.0f} MB, over the file size "
                                   f"limit of {soft / 1e6:.0f} MB (ulimit -f)")


def _write_bytes(path: Path, data) -> None:
    with open(path, "wb") as f:
        f.write(data)


def json_kind(p: Path) -> str | None:
    """The kind of result a JSON flutterswim wrote names after its version in ``generator``
    ("fit", "steer metrics"; "" for one that names none, as before stop 47), None for a file
    that is not one of ours."""
    try:
        if not _json_ours(p):
            return None
        tag = json.loads(p.read_text(encoding="utf-8")).get("generator", "")
    except (OSError, ValueError):
        return None
    words = str(tag).split(" ", 2)
    return words[2] if len(words) > 2 else ""


def _json_ours(p: Path) -> bool:
    if p.stat().st_size > _SCAN:
        return False
    d = json.loads(p.read_text(encoding="utf-8"))
    if not isinstance(d, dict):
        return False
    tag = d.get("generator", d.get("software"))
    return isinstance(tag, str) and _TAG.match(tag.encode()) is not None


def row_signature(fields: Sequence[str]) -> str:
    """The ``tracked_by`` value of a CSV row of ours: the version and a hash of the row's other
    fields as written (an edited row is not ours)."""
    import hashlib

    from . import __version__

    return f"flutterswim {__version__} #" + hashlib.sha256("\x1f".join(fields).encode()).hexdigest()[:16]


def _csv_ours(p: Path) -> bool:
    """Exactly the columns of a CSV flutterswim writes (a column added by hand: not ours), every
    row signed in its last column, ``tracked_by``, and, where the signature holds a hash
    (:func:`row_signature`), the row as written."""
    import csv

    from .tracking.batch import CSV_COLUMNS, CSV_COLUMNS_BEFORE_SE, FAILED_COLUMNS

    with open(p, newline="", encoding="utf-8") as f:
        rows = csv.reader(f)
        head = tuple(next(rows, []))
        if head not in (CSV_COLUMNS, CSV_COLUMNS_BEFORE_SE, FAILED_COLUMNS):
            return False
        for r in rows:
            if len(r) != len(head) or not r[-1].startswith("flutterswim "):
                return False
            if " #" in r[-1] and r[-1].split(" #", 1)[1] != row_signature(r[:-1]).split(" #", 1)[1]:
                return False  # (the hash, whatever version wrote it)
    return True  # (a header alone: a batch whose trials all failed)


def _png_ours(p: Path) -> bool:
    with open(p, "rb") as f:
        if f.read(8) != b"\x89PNG\r\n\x1a\n":
            return False
        while True:
            head = f.read(8)
            if len(head) < 8:
                return False
            n, kind = int.from_bytes(head[:4], "big"), head[4:]
            if kind in (b"tEXt", b"iTXt") and n < 1 << 16:
                key, _, text = f.read(n).partition(b"\x00")
                if key == b"Software" and (text.startswith(b"flutterswim ") or b"\x00flutterswim " in text):
                    return True
                f.seek(4, 1)
            elif kind == b"IEND":
                return False
            else:
                f.seek(n + 4, 1)


def _jpeg_ours(p: Path) -> bool:
    with open(p, "rb") as f:
        if f.read(2) != b"\xff\xd8":
            return False
        while True:
            m = f.read(4)
            if len(m) < 4 or m[0] != 0xFF or m[1] in (0xD9, 0xDA):  # end of image, start of scan
                return False
            n = int.from_bytes(m[2:], "big") - 2
            if m[1] == 0xFE:
                if f.read(n).startswith(b"flutterswim "):
                    return True
            else:
                f.seek(n, 1)


# signatures inside a file's own metadata structures (what matplotlib, the GIF marker, ffmpeg's
# comment and the report template write), never a bare word in its content
_PATTERNS = {
    ".pdf": re.compile(rb"/Creator\s*\(flutterswim "),
    ".svg": re.compile(rb"<dc:creator>\s*<cc:Agent>\s*<dc:title>flutterswim "),
    ".gif": re.compile(rb"\x21\xfe" + bytes([len(b"flutterswim animation")]) + rb"flutterswim animation\x00"),
    ".mp4": re.compile(rb"\xa9cmt.{4,16}?data.{8}flutterswim animation", re.S),
    ".html": re.compile(rb'<meta name="generator" content="flutterswim '),
}
_READERS = {".nc": _netcdf_ours, ".nc4": _netcdf_ours, ".h5": _netcdf_ours, ".hdf5": _netcdf_ours,
            ".json": _json_ours, ".csv": _csv_ours, ".png": _png_ours, ".jpg": _jpeg_ours, ".jpeg": _jpeg_ours}


def is_ours(path: str | os.PathLike) -> bool:
    """True if the file carries flutterswim's signature in its format's own metadata (a NetCDF
    ``source`` attribute starting "flutterswim ", a PNG's Software text, a PDF's Creator, a
    JSON ``generator``, ...); a file that merely mentions the word, or of a kind flutterswim
    does not write, is not ours."""
    p = Path(os.fspath(path))
    sfx = p.suffix.lower()
    try:
        if sfx in _READERS:
            return bool(_READERS[sfx](p))
        if sfx in _PATTERNS:
            return _scan(p, _PATTERNS[sfx])
    except Exception:  # unreadable, malformed or truncated: not provably ours
        return False
    return False


def figure_metadata(suffix: str) -> dict:
    """``savefig`` keywords that sign a figure file (png, pdf, svg, jpg)."""
    from . import __version__

    sfx = suffix.lower().lstrip(".")
    tag = f"flutterswim {__version__}"
    if sfx == "png":
        return {"metadata": {"Software": tag}}
    if sfx in ("pdf", "svg"):
        return {"metadata": {"Creator": tag}}
    if sfx in ("jpg", "jpeg"):
        return {"pil_kwargs": {"comment": tag.encode()}}
    return {}


#: figure files flutterswim writes
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")


def save_figure_file(fig, path: str | os.PathLike, *, dpi: float = 150,
                     suffixes: Sequence[str] = FIGURE_SUFFIXES, **savefig_kw) -> Path:
    """Save a matplotlib figure to ``path`` atomically, signed, and never over a file that is not
    ours (the functions of the API that save a figure; the command line checks before computing).
    ``savefig_kw`` go to ``savefig`` (bbox_inches ...)."""
    p = check_output_file(path, suffixes, what="path")
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=dpi, format=p.suffix.lower().lstrip(".").replace("jpg", "jpeg"),
                    **figure_metadata(p.suffix), **savefig_kw)
    return p


def mark_gif(path: str | os.PathLike) -> None:
    """Insert a GIF comment extension with :data:`SIGNATURE` before the trailer byte."""
    p = Path(os.fspath(path))
    data = p.read_bytes()
    if not data.endswith(b"\x3b") or SIGNATURE in data[-64:]:
        return
    note = SIGNATURE + b" animation"
    p.write_bytes(data[:-1] + b"\x21\xfe" + bytes([len(note)]) + note + b"\x00\x3b")


def _writable_dir(folder: Path, what: str, path: Path, *, may_create: bool = False) -> None:
    """Refuse a folder that does not exist (a typo must not create folders anywhere; only an
    output folder itself, ``may_create``, is made, inside an existing one) or is not writable."""
    if not folder.exists() and not (may_create and folder.parent.is_dir()):
        missing = folder
        while not missing.parent.exists() and missing.parent != missing:
            missing = missing.parent
        raise ParameterError(f"{what}={str(path)!r}: the folder {str(missing)!r} does not exist; create it first "
                             "or give an existing folder")
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise ParameterError(f"{what}={str(path)!r}: {str(probe)!r} is not a directory, so the folder "
                             f"{str(folder)!r} cannot be created")
    # a real probe: os.access says yes to root on read-only or virtual file systems
    try:
        fd, tmp = tempfile.mkstemp(prefix=".flutterswim-probe-", dir=probe)
    except OSError as exc:
        # a virtual file system (/proc) says "No such file or directory" of the file to create
        why = "" if exc.errno == errno.ENOENT else f" ({exc.strerror or exc})"
        if probe != folder:
            raise ParameterError(f"{what}={str(path)!r}: the folder {str(folder)!r} does not exist and cannot be "
                                 f"created: {str(probe)!r} is not writable{why}") from None
        raise ParameterError(f"{what}={str(path)!r}: the folder {str(folder)!r} is not writable{why}; no file "
                             "can be created in it") from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(tmp)


def netcdf_attrs(path: str | os.PathLike) -> dict:
    """The global attributes of a NetCDF-4 file ({} if none, unreadable or not NetCDF-4)."""
    p = Path(os.fspath(path))
    try:
        with open(p, "rb") as f:
            if f.read(8) != b"\x89HDF\r\n\x1a\n":
                return {}
        import h5py

        with h5py.File(p, "r") as h:
            return dict(h.attrs)
    except Exception:  # noqa: BLE001 - unreadable: no attributes
        return {}


def netcdf_title(path: str | os.PathLike) -> str:
    """The ``title`` attribute of a NetCDF-4 file ("" if none or not NetCDF-4)."""
    title = netcdf_attrs(path).get("title", b"")
    return title.decode("utf-8", "replace") if isinstance(title, bytes) else str(title)


def check_output_file(path: str | os.PathLike, suffixes: Sequence[str], *, what: str = "out",
                      kind: str | None = None) -> Path:
    """Check an output file path before computing; return it as a Path.

    Raises ParameterError naming the path if it is a directory, an existing read-only file, a
    pipe, socket or device, has a suffix not in ``suffixes`` (lower case, with the dot), or its
    folder is not writable. A symbolic link to a file is followed: the path returned is its
    target's, so the file is replaced there and the link kept. ``kind``: the NetCDF title the
    command writes; a flutterswim NetCDF of another title (a simulated run under a track's
    name) is refused, not replaced; "<kind> in <anything>" is of the kind (a branch's title names
    its parameter). For a JSON, the kind its ``generator`` names after the version (one that
    names none is replaced)."""
    try:
        p = Path(os.fspath(path))
    except TypeError:
        raise ParameterError(f"{what}={path!r} is not a path") from None
    if str(p) in ("", "."):
        raise ParameterError(f"{what}={str(path)!r} is not a file name")
    if p.suffix.lower() not in tuple(s.lower() for s in suffixes) and not p.is_dir():
        raise ParameterError(f"{what}={str(p)!r} has the suffix {p.suffix or '(none)'!r}; use "
                             f"{' or '.join(suffixes)}")
    if p.is_symlink():
        if not p.exists():
            raise ParameterError(f"{what}={str(p)!r} is a symbolic link to {os.readlink(p)!r}, which does not exist; "
                                 "give the file's own path")
        # written through the link: the rename would replace the link, and leave its target stale
        # (the name given decides the format, the target's may be anything)
        p = Path(os.path.realpath(p))
    if p.exists() and not p.is_file() and not p.is_dir():
        raise ParameterError(f"{what}={str(p)!r} exists and is not a regular file (a pipe, socket or device); "
                             "it is never replaced. Choose another name")
    if p.is_dir():
        raise ParameterError(f"{what}={str(p)!r} is a directory; give a file name ending in "
                             f"{' or '.join(suffixes)}")
    if p.exists() and not os.access(p, os.W_OK):
        raise ParameterError(f"{what}={str(p)!r} exists and is not writable")
    if p.is_file() and p.stat().st_size > 0 and not is_ours(p):
        raise ParameterError(f"{what}={str(p)!r} exists and was not written by flutterswim; it is never "
                             "overwritten. Choose another name, or move the file away first")
    if kind is not None and p.is_file() and p.stat().st_size > 0 and p.suffix.lower() == ".json":
        # (a fit's JSON, maybe hours of profiles, was replaced by steer's metrics without a word)
        held = json_kind(p)
        if held and held != kind:
            raise ParameterError(f"{what}={str(p)!r} holds another kind of flutterswim result ({held!r}); it is "
                                 f"not replaced by {kind!r}. Choose another name, or move the file away first")
    elif kind is not None and p.is_file() and p.stat().st_size > 0:
        title = netcdf_title(p)
        if title and title != kind and not title.startswith(f"{kind} in "):  # (a branch: "... in <parameter>")
            raise ParameterError(f"{what}={str(p)!r} holds another kind of flutterswim result ({title!r}); it is "
                                 f"not replaced by a {kind!r}. Choose another name, or move the file away first")
    _writable_dir(p.parent if str(p.parent) else Path("."), what, p)
    return p


def check_output_dir(path: str | os.PathLike, *, what: str = "out") -> Path:
    """An output folder: an existing directory, or a new one whose parent exists; writable;
    not one of our own stores or folders of a kind (a sweep store, a reproduce folder: figures
    written into one made it refuse its own --overwrite later, as holding files it did not write)."""
    p = Path(os.fspath(path))
    if p.exists() and not p.is_dir():
        raise ParameterError(f"{what}={str(p)!r} exists and is not a directory; give a folder")
    # the folder or one it lies in (demo --out s.zarr/demo wrote into a sweep store)
    for q in (p, *p.resolve().parents):
        if q.is_dir() and has_marker(q):
            try:
                found = json.loads((q / MARKER).read_text()).get("kind") or "store"
            except (OSError, ValueError, AttributeError):
                found = "store"
            inside = "" if q == p else f" lies in {str(q)!r}, which"
            raise ParameterError(f"{what}={str(p)!r}{inside} is a flutterswim {found} folder; it is written only by "
                                 "its own command. Give another folder")
    _writable_dir(p, what, p, may_create=True)
    return p


def check_text_file(path: Path, what: str) -> None:
    """A CSV or other text input that is UTF-8 text (a byte-order mark allowed) without NUL
    bytes; otherwise a ParameterError naming it (a binary file reached the CSV readers as a
    UnicodeDecodeError, exit 1)."""
    data = Path(path).read_bytes()
    try:
        data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ParameterError(f"{what}={str(path)!r} is not a text (UTF-8) file: {exc.reason} at byte {exc.start}") from None
    if b"\x00" in data:
        raise ParameterError(f"{what}={str(path)!r} is not a text file: it holds NUL bytes at byte {data.index(0)}")


def check_files_in(folder: Path, names: Sequence[str], *, what: str = "out", kinds: dict | None = None) -> None:
    """:func:`check_output_file` for each file ``names`` an output folder would get (each with
    its own suffix and, from ``kinds``, its NetCDF title); a folder not made yet replaces nothing."""
    for name in names if Path(folder).is_dir() else ():
        check_output_file(Path(folder) / name, (Path(name).suffix,), what=what, kind=(kinds or {}).get(name))


#: the last files :func:`atomic_path` has put in place, with their sequence numbers (the command
#: line says which, when a command writing several is interrupted: the others are still those of
#: an earlier run); bounded, for a long-lived process writing many
WRITTEN: collections.deque = collections.deque(maxlen=256)
_n_written = 0


def write_mark() -> int:
    """The number of files put in place so far (for :func:`written_since`)."""
    return _n_written


def written_since(mark: int) -> list[Path]:
    """The files put in place since :func:`write_mark` gave ``mark`` (the last 256 at most)."""
    return [p for k, p in WRITTEN if k >= mark]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path next to ``path`` (same suffix); on success rename it onto
    ``path`` atomically, on any error remove it and leave ``path`` untouched."""
    p = Path(os.fspath(path))
    if p.is_symlink():  # a link to a file: replace the file, keep the link (check_output_file)
        p = Path(os.path.realpath(p))
    fd, tmp = tempfile.mkstemp(prefix=f".{p.stem}.", suffix=f".part{p.suffix}", dir=p.parent)
    os.close(fd)
    tmp_p = Path(tmp)
    os.chmod(tmp_p, 0o666 & ~_umask())  # mkstemp makes 0600; a saved file gets the usual mode
    try:
        yield tmp_p
        if tmp_p.is_dir():
            raise RuntimeError("atomic_path: a directory was written instead of a file")
        os.replace(tmp_p, p)
        global _n_written
        WRITTEN.append((_n_written, p))
        _n_written += 1
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_p.unlink()
        raise


def _umask() -> int:
    old = os.umask(0o022)
    os.umask(old)
    return old


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def write_marker(store: Path, kind: str, **info) -> None:
    (Path(store) / MARKER).write_text(json.dumps({"kind": kind, **info}))


def has_marker(store: Path) -> bool:
    return (Path(store) / MARKER).is_file()


def _check_kind(p: Path, kind: str | None, what: str) -> None:
    """Refuse one of our folders of another kind (a reproduce folder is no sweep store)."""
    if kind is None or not has_marker(p):
        return
    try:
        found = json.loads((p / MARKER).read_text()).get("kind")
    except (OSError, ValueError, AttributeError):
        found = None  # unreadable: as before, the marker alone decides
    if found is not None and found != kind:
        raise ParameterError(f"{what}={str(p)!r} is a flutterswim {found} folder, not a {kind} store; it is "
                             "never overwritten by another command. Give a new name")


def _is_cwd_or_parent(p: Path) -> bool:
    try:
        rp, cwd = p.resolve(), Path.cwd().resolve()
    except OSError:
        return False
    return rp == cwd or rp in cwd.parents or rp == Path(rp.anchor)


def check_store_path(path: str | os.PathLike, *, overwrite: bool, what: str = "out", kind: str | None = None) -> Path:
    """Check a store directory before computing.

    Allowed: a path that does not exist (its folder writable), an empty directory, or one of
    our stores (marker present; it is resumed, or replaced when ``overwrite``). Refused, with
    the reason: the current directory or one of its parents, a file, a non-empty directory
    without our marker (user files, or a Zarr store of another tool), and, given ``kind``, one
    of our folders whose marker names another kind."""
    p = Path(os.fspath(path))
    store = kind in (None, "sweep")  # a reproduce folder is an output folder, not a store
    new_name = "a new store name such as sweep.zarr" if store else f"the name of a new {kind} folder"
    if str(p) in ("", "."):
        raise ParameterError(f"{what}={str(path)!r} is the current directory; give {new_name}")
    if _is_cwd_or_parent(p):
        raise ParameterError(f"{what}={str(p)!r} is the current directory or one of its parents; give {new_name}")
    if p.is_symlink() and (overwrite or not p.exists()):
        # replacing or creating through a link would rename or delete the user's link itself
        raise ParameterError(f"{what}={str(p)!r} is a symbolic link (to {os.readlink(p)!r}); a store is never "
                             f"{'replaced' if p.exists() else 'created'} through a link, and the link is left as it "
                             f"is. Give the store's own path, or {new_name}")
    if p.exists() and not p.is_dir():
        raise ParameterError(f"{what}={str(p)!r} is an existing file, not "
                             f"{'a sweep store' if store else 'an output folder'}; nothing was changed. Give {new_name}")
    if p.is_dir() and not has_marker(p) and any(p.iterdir()):
        zarrish = any((p / f).exists() for f in ("zarr.json", ".zgroup", ".zattrs", ".zarray"))
        why = "a Zarr store written by another tool" if zarrish else "a directory holding other files"
        ours = "a flutterswim store" if store else f"a flutterswim {kind} folder"
        raise ParameterError(f"{what}={str(p)!r} is {why}, not {ours} (no {MARKER} marker); "
                             f"it is never overwritten. Give {new_name}")
    if p.is_dir():
        _check_kind(p, kind, what)
    if p.is_dir() and not os.access(p, os.W_OK | os.X_OK):
        raise ParameterError(f"{what}={str(p)!r} is not writable")
    if not p.exists():
        _writable_dir(p.parent if str(p.parent) else Path("."), what, p)
    return p


def set_aside_own_store(path: str | os.PathLike, kind: str | None = None, tag: str = "replaced") -> Path | None:
    """Rename a store that carries our marker (checked again here, with its ``kind`` if given)
    to a hidden name beside it, returned (None: nothing there); anything else raises."""
    p = Path(os.fspath(path))
    if p.is_symlink():
        raise ParameterError(f"{str(p)!r} is a symbolic link; a store is never deleted through a link")
    if not p.exists():
        return None
    if not (p.is_dir() and has_marker(p)) or _is_cwd_or_parent(p):
        raise ParameterError(f"{str(p)!r} is not a flutterswim store; it is never deleted")
    _check_kind(p, kind, "store")
    aside = p.parent / f".{p.name}.{tag}-{os.getpid()}"
    if aside.exists():  # a remnant of a run with this process id: removed only if it is a store of ours
        if aside.is_symlink() or not (aside.is_dir() and has_marker(aside)):
            raise ParameterError(f"{str(aside)!r} is in the way of setting {str(p)!r} aside and is not a flutterswim "
                                 "store; move it away")
        shutil.rmtree(aside)
    os.replace(p, aside)
    return aside


def remove_own_store(path: str | os.PathLike, kind: str | None = None) -> None:
    """Delete a store that carries our marker (checked again here, with its ``kind`` if
    given); anything else raises."""
    # rename first: a crash mid-delete leaves a hidden remnant, never a half store at the path
    trash = set_aside_own_store(path, kind, tag="deleting")
    if trash is not None:
        shutil.rmtree(trash)
