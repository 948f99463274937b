"""Execution backends: a registry of named executors behind one argument.

Every backend is a context manager factory ``factory(workers=None, scheduler=None)``
returning an object with ``imap(fn, items)``: it calls ``fn(item)`` for every
``(key, item)`` pair and yields ``(key, fn(item))`` in completion order. Workers only
compute and return; the caller alone writes results.

- ``"serial"``: in this process, in order.
- ``"processes"`` (default): local worker programs, all cores unless ``workers`` (they never
  re-import the caller's main module, die with the parent, and a dead worker costs only its
  own item, yielded as :class:`WorkerLost`).
- ``"dask"``: a running dask.distributed scheduler at ``scheduler`` (``tcp://host:port``); an
  unreachable address raises :class:`SchedulerUnreachable` after ``defaults.SCHEDULER_TIMEOUT_S``.
- ``"dask-local"``: a dask.distributed LocalCluster started on demand (``workers`` processes,
  one thread each), closed at the end.

``register_backend(name, factory)`` adds one (e.g. a batch system).
"""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Any, Callable, Iterable, Iterator

from .._validate import ParameterError

__all__ = ["BACKENDS", "register_backend", "get_backend", "available_backends", "default_workers", "blas_threads",
           "WorkerLost", "SchedulerUnreachable"]

BACKENDS: dict[str, Callable[..., Any]] = {}


class SchedulerUnreachable(ParameterError):
    """No Dask scheduler answered at the given address within the timeout."""


def register_backend(name: str, factory: Callable[..., Any]) -> None:
    """Register ``factory(workers=..., scheduler=...)`` -> context manager yielding an executor."""
    BACKENDS[name] = factory


def available_backends() -> list[str]:
    return sorted(BACKENDS)


def default_workers() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def check_backend(name: str, *, workers: int | None = None, scheduler: str | None = None) -> None:
    """Check the backend arguments without starting anything (ParameterError if bad)."""
    if scheduler is not None and name in ("processes", "serial"):
        name = "dask"
    if name not in BACKENDS:
        raise ParameterError(f"backend={name!r} is unknown; choose one of {available_backends()}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, (int, float))
                                or int(workers) != workers or workers < 1):
        raise ParameterError(f"workers={workers!r} must be an integer >= 1")
    if name == "dask" and scheduler is None:
        raise ParameterError("backend='dask' needs a scheduler's address (scheduler=), e.g. 'tcp://host:8786'; "
                             "or use backend='dask-local'")
    if scheduler is not None and not isinstance(scheduler, str):
        raise ParameterError(f"scheduler={scheduler!r} must be an address such as 'tcp://host:8786'")


def get_backend(name: str, *, workers: int | None = None, scheduler: str | None = None):
    """A context manager yielding the executor of backend ``name``."""
    if scheduler is not None and name in ("processes", "serial"):
        name = "dask"
    try:
        factory = BACKENDS[name]
    except KeyError:
        raise ParameterError(f"backend={name!r} is unknown; choose one of {available_backends()}") from None
    if workers is not None and (isinstance(workers, bool) or int(workers) != workers or workers < 1):
        raise ParameterError(f"workers={workers!r} must be an integer >= 1")
    return factory(workers=workers, scheduler=scheduler)


class SerialExecutor:
    name = "serial"
    workers = 1

    def imap(self, fn: Callable, items: Iterable[tuple[Any, Any]]) -> Iterator[tuple[Any, Any]]:
        for key, item in items:
            yield key, fn(item)


@contextlib.contextmanager
def _serial(workers=None, scheduler=None):
    yield SerialExecutor()


_SET = ("scipy_openblas_set_num_threads64_", "scipy_openblas_set_num_threads", "openblas_set_num_threads64_",
        "openblas_set_num_threads")
_GET = tuple(n.replace("_set_", "_get_") for n in _SET)


_LIBS: list | None = None


def _openblas_libs() -> list:
    global _LIBS
    if _LIBS is None:
        _LIBS = _find_openblas()
    return _LIBS


def _find_openblas() -> list:
    import ctypes

    try:
        with open("/proc/self/maps") as f:
            paths = sorted({ln.split()[-1] for ln in f if "openblas" in ln.lower() and ln.split()[-1].startswith("/")})
    except OSError:  # pragma: no cover - not Linux
        return []
    libs = []
    for p in paths:
        try:
            libs.append(ctypes.CDLL(p))
        except OSError:  # pragma: no cover
            pass
    return libs


def blas_threads(n: int | None) -> list[int]:
    """Set the thread count of every loaded OpenBLAS (numpy's and scipy's) to ``n`` (None: leave);
    return the previous counts. The filament's matrices are small: BLAS threads only add
    overhead (~1.7x slower with 2 threads here), and the points are the parallelism."""
    old = []
    for lib in _openblas_libs():
        get = next((getattr(lib, g) for g in _GET if hasattr(lib, g)), None)
        st = next((getattr(lib, s_) for s_ in _SET if hasattr(lib, s_)), None)
        if get is None or st is None:
            continue
        old.append(int(get()))
        if n is not None:
            st(int(n))
    return old


def _limit_threads() -> None:
    # one BLAS thread per worker (the environment for processes started later, the loaded
    # libraries for this one)
    for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(k, "1")
    import numpy  # noqa: F401 - load BLAS before limiting it
    import scipy.linalg  # noqa: F401

    blas_threads(1)


@contextlib.contextmanager
def single_blas_thread():
    """In this process, for the duration: BLAS single-threaded (restored afterwards)."""
    import scipy.linalg  # noqa: F401

    libs_old = blas_threads(1)
    try:
        yield
    finally:
        for lib, n in zip(_openblas_libs(), libs_old):
            st = next((getattr(lib, s_) for s_ in _SET if hasattr(lib, s_)), None)
            if st is not None:
                st(n)


class WorkerLost:
    """Yielded by ``imap`` instead of a result when the worker computing the item died
    (killed, crashed, out of memory): only that item is lost, the others go on."""

    def __init__(self, message: str):
        self.message = message

    def __repr__(self) -> str:
        return f"WorkerLost({self.message!r})"


class _Worker:
    """One worker program and its two pipes."""

    def __init__(self, env: dict[str, str]):
        import subprocess
        from multiprocessing.connection import Connection

        r_task, w_task = os.pipe()  # parent -> worker
        r_res, w_res = os.pipe()  # worker -> parent
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "flutterswim.sweep._worker", str(os.getpid()), str(r_task), str(w_res)],
                pass_fds=(r_task, w_res), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL, env=env, close_fds=True)
        finally:
            os.close(r_task)
            os.close(w_res)
        self.send_conn = Connection(w_task, readable=False)
        self.recv_conn = Connection(r_res, writable=False)
        self.key: Any = None
        self.send_conn.send(list(sys.path))

    def submit(self, key, payload: bytes) -> None:
        self.key = key
        self.send_conn.send((key, payload))

    def death(self) -> str:
        try:
            rc = self.proc.wait(timeout=5)
        except Exception:  # noqa: BLE001
            self.proc.kill()
            rc = self.proc.wait()
        if rc is not None and rc < 0:
            import signal

            try:
                return f"killed by signal {signal.Signals(-rc).name}"
            except ValueError:
                return f"killed by signal {-rc}"
        return f"exited with status {rc}"

    def stop(self, kill: bool = False) -> None:
        for c in (self.send_conn, self.recv_conn):
            try:
                if c is self.send_conn and not kill:
                    c.send(None)
            except OSError:
                pass
        for c in (self.send_conn, self.recv_conn):
            try:
                c.close()
            except OSError:
                pass
        if kill and self.proc.poll() is None:
            self.proc.kill()
        try:
            self.proc.wait(timeout=5)
        except Exception:  # noqa: BLE001
            self.proc.kill()
            self.proc.wait()


class PoolExecutor:
    """Local worker programs (``python -m flutterswim.sweep._worker``), one task each at a time.

    Unlike multiprocessing pools, the workers never re-import the caller's main module, hold
    none of its open files, die with the parent (SIGKILL or SIGTERM included), and a worker
    that dies costs only the item it was computing (:class:`WorkerLost`); a replacement is
    started for the remaining items."""

    name = "processes"

    def __init__(self, workers: int):
        self.workers = workers
        env = dict(os.environ)
        for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
            env[k] = "1"
        # the workers import the same flutterswim (and point functions) as this process
        env["PYTHONPATH"] = os.pathsep.join([p for p in sys.path if p] + [env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
        self._env = env
        self._pool: list[_Worker] = []

    def close(self, kill: bool = False) -> None:
        for w in self._pool:
            w.stop(kill=kill)
        self._pool = []

    def imap(self, fn, items):
        import pickle
        from multiprocessing.connection import wait

        it = iter(items)
        idle: list[_Worker] = list(self._pool)
        busy: dict[Any, _Worker] = {}  # recv_conn -> worker
        exhausted = False
        lost_in_a_row = 0
        while True:
            while not exhausted and (idle or len(self._pool) < self.workers):
                try:
                    key, item = next(it)
                except StopIteration:
                    exhausted = True
                    break
                w = idle.pop() if idle else self._spawn()
                w.submit(key, pickle.dumps((fn, item)))
                busy[w.recv_conn] = w
            if not busy:
                return
            for conn in wait(list(busy)):
                w = busy.pop(conn)
                try:
                    key, status, value = conn.recv()
                except (EOFError, OSError):
                    key = w.key
                    why = w.death()
                    w.stop(kill=True)
                    self._pool.remove(w)
                    lost_in_a_row += 1
                    if lost_in_a_row > 2 * self.workers + 2:
                        raise RuntimeError(f"{lost_in_a_row} worker processes in a row died before finishing a "
                                           f"point (last: {why}); the workers cannot run here (memory? a point "
                                           "function that kills its process?)") from None
                    yield key, WorkerLost(f"the worker process computing this point died ({why})")
                    continue
                lost_in_a_row = 0
                idle.append(w)
                if status == "error":
                    raise RuntimeError(f"worker: {value}")
                yield key, value

    def _spawn(self) -> _Worker:
        w = _Worker(self._env)
        self._pool.append(w)
        return w


@contextlib.contextmanager
def _processes(workers=None, scheduler=None):
    n = workers or default_workers()
    ex = PoolExecutor(n)
    try:
        yield ex
    except BaseException:
        ex.close(kill=True)
        raise
    else:
        ex.close()


class DaskExecutor:
    name = "dask"

    def __init__(self, client):
        self.client = client
        try:
            self.workers = max(1, sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values()))
        except Exception:  # pragma: no cover
            self.workers = 1

    def imap(self, fn, items):
        from distributed import as_completed
        from distributed.scheduler import KilledWorker

        it = iter(items)
        futs: dict[Any, Any] = {}
        window = 2 * self.workers
        ac = None

        def fill():
            while len(futs) < window:
                try:
                    key, item = next(it)
                except StopIteration:
                    return
                f = self.client.submit(fn, item, pure=False)
                futs[f] = key
                if ac is not None:
                    ac.add(f)

        fill()
        if not futs:
            return
        ac = as_completed(list(futs), loop=self.client.loop)
        while futs:
            f = next(ac)
            key = futs.pop(f)
            try:
                res = f.result()
            except KilledWorker as exc:
                res = WorkerLost(f"the Dask worker computing this point died ({exc})")
            yield key, res
            f.release()
            fill()


@contextlib.contextmanager
def _dask(workers=None, scheduler=None):
    if scheduler is None:
        raise ParameterError("backend='dask' needs scheduler='tcp://host:port' (or use backend='dask-local')")
    from distributed import Client

    from ..defaults import SCHEDULER_TIMEOUT_S

    _reachable(scheduler, SCHEDULER_TIMEOUT_S)
    try:
        client = Client(scheduler, set_as_default=False, timeout=SCHEDULER_TIMEOUT_S)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SchedulerUnreachable(
            f"scheduler={scheduler!r}: no Dask scheduler answered within {SCHEDULER_TIMEOUT_S:g} s "
            f"({type(exc).__name__}); check the address (tcp://host:port) and that the scheduler is running"
        ) from None
    with client:
        yield DaskExecutor(client)


def _reachable(scheduler: str, timeout: float) -> None:
    """A TCP scheduler address that parses and accepts a connection, before a Client is made
    (a Client that fails to connect leaves an object whose clean-up prints a traceback 20 s
    later, after the one-line message); other schemes are left to the Client."""
    import socket

    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, loc = parse_address(str(scheduler))
        if scheme not in ("tcp", "tls"):
            return
        host, port = parse_host_port(loc)
    except (ValueError, TypeError) as exc:
        raise SchedulerUnreachable(f"scheduler={scheduler!r} is not a scheduler address ({exc}); give "
                                   "tcp://host:port") from None
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except OSError as exc:
        # (a refused connection fails at once: "within 10 s" said of it misled)
        how = f"no Dask scheduler answered within {timeout:g} s" if isinstance(exc, TimeoutError) else \
            "no Dask scheduler there: the connection failed"
        raise SchedulerUnreachable(
            f"scheduler={scheduler!r}: {how} ({type(exc).__name__}: "
            f"{exc}); check the address (tcp://host:port) and that the scheduler is running") from None
    if scheme != "tcp":  # (TLS needs the Client's security settings to ask: left to the Client)
        return
    # something listens there: it must answer Dask's "identity" as a scheduler, within the time
    # (an HTTP server or a silent socket on the port hung the Client for minutes; one answering
    # garbage made it allocate exabytes and fail as "out of memory")
    try:
        who = _identity(str(scheduler), timeout)
    except Exception as exc:  # noqa: BLE001 - anything but an answer: not a scheduler
        raise SchedulerUnreachable(
            f"scheduler={scheduler!r} accepts connections but did not answer as a Dask scheduler within {timeout:g} s "
            f"({type(exc).__name__}); check the address and port (the scheduler's, not its dashboard's)") from None
    if not (isinstance(who, dict) and who.get("type") == "Scheduler"):
        kind = who.get("type") if isinstance(who, dict) else type(who).__name__
        raise SchedulerUnreachable(f"scheduler={scheduler!r} answers as {kind!r}, not as a Dask scheduler; give the "
                                   "scheduler's address")


def _identity(address: str, timeout: float):
    """Dask's "identity" of the server at ``address``, within ``timeout`` seconds in all."""
    import asyncio

    from distributed.comm import connect

    async def ask():
        comm = await connect(address, timeout=timeout)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    from concurrent.futures import ThreadPoolExecutor

    # in a thread of its own: its own event loop, also where one runs already (a notebook)
    with ThreadPoolExecutor(1) as pool:
        return pool.submit(asyncio.run, asyncio.wait_for(ask(), timeout)).result(timeout + 5.0)


@contextlib.contextmanager
def _dask_local(workers=None, scheduler=None):
    from distributed import Client, LocalCluster

    n = workers or default_workers()
    keys = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
    saved = {k: os.environ.get(k) for k in keys}
    os.environ.update({k: "1" for k in keys})  # inherited by the worker processes only
    try:
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address=None)
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    with cluster, Client(cluster, set_as_default=False) as client:
        client.wait_for_workers(n)
        yield DaskExecutor(client)


register_backend("serial", _serial)
register_backend("processes", _processes)
register_backend("dask", _dask)
register_backend("dask-local", _dask_local)
