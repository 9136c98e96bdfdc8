"""Where a run's jobs run: this process, local worker processes or Ray.

Every engine runs the same unit of work, a job of the run's *context* (any picklable object
with a ``key`` and a ``run(job)`` method), through the same function, :func:`run_job`, and
hands what it returns back to the caller, which alone writes files. So the output does not
depend on the engine or on the number of workers; only where the computing happens changes.
The stages bring their contexts: grasp evaluation's
(:class:`affordgrasp.dataset.jobs.RunContext`: generate, optimise) and the physics replay's
get the same engines, defaults and stopping behaviour.

The context is sent once to each worker (a Ray task's context once to the object store).
Workers leave Ctrl-C and a terminal's hangup to the process that started them, which stops
them (:func:`stop_pool`), and end with it (:mod:`.worker_lifetime`), ``kill -9`` included.
:func:`process_pool` is the same pool for a stage that submits plain functions.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import threading
import time

from ..errors import InputError, bad_parameter, require
from .interrupts import STOP_SIGNALS
from .process_tuning import keep_freed_memory
from .worker_lifetime import Reaper, die_with_parent

ENGINES = ("local", "ray")

# Per process: the context of the current run (a worker's, installed once).
_CONTEXT = None


def _install_context(context) -> None:
    global _CONTEXT
    if _CONTEXT is None or _CONTEXT.key != context.key:
        _CONTEXT = context


def run_job(job, context=None):
    """Run one job in this process; the same function on every engine.

    Parameters
    ----------
    job : object
        A unit of work of the installed context.
    context : object, optional
        Installed first when given (a worker started without it, or the inline engine):
        anything with a ``key`` (str) and a ``run(job)`` method.

    Returns
    -------
    object
        ``context.run(job)``.
    """
    if context is not None:
        _install_context(context)
    return _CONTEXT.run(job)


def _detach_worker(parent_pid: int | None = None) -> None:
    # Ctrl-C and a terminal's hangup reach the whole process group; only the parent decides
    # what to do about them (it stops the workers). SIGTERM keeps its default: it is how
    # the parent stops a worker. A parent killed outright (SIGKILL) takes its workers along.
    if parent_pid is not None:
        die_with_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    keep_freed_memory()


def _worker_init(context, parent_pid: int | None = None) -> None:
    _detach_worker(parent_pid)
    _install_context(context)


def process_pool(workers: int, initializer=None, initargs: tuple = ()):
    """A pool of worker processes started with 'spawn' (safe with threads) that leave
    Ctrl-C to this process and die with it.

    Parameters
    ----------
    workers : int
        Processes.
    initializer : callable, optional
        Run in each worker with ``initargs`` (it must call ``_detach_worker``); default:
        ``_detach_worker`` with this process's pid.
    initargs : tuple

    Returns
    -------
    concurrent.futures.ProcessPoolExecutor
        Stop it with :func:`stop_pool` when its running jobs are to be thrown away.
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    if initializer is None:
        initializer, initargs = _detach_worker, (os.getpid(),)
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=initializer,
        initargs=initargs,
    )


def stop_pool(pool) -> None:
    """Stop a :func:`process_pool` now: cancel what waits, terminate what runs.

    Parameters
    ----------
    pool : concurrent.futures.ProcessPoolExecutor
    """
    # Running jobs' results would be thrown away: stop their processes now rather than
    # wait for them. The executor keeps them in a private mapping.
    processes = list(getattr(pool, "_processes", {}).values())
    with _signals_deferred():
        pool.shutdown(wait=False, cancel_futures=True)
        for p in processes:
            if p.is_alive():
                p.terminate()
        for p in processes:
            p.join(timeout=5)
            if p.is_alive():  # pragma: no cover - a worker stuck in native code
                p.kill()
                p.join(timeout=5)


def default_workers() -> int:
    """Every core this process may use.

    Returns
    -------
    int
        At least 1.
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


class Engine:
    """Submit jobs, wait for some to finish, collect their results, stop."""

    workers: int = 1
    name: str = ""

    def submit(self, job):
        """Start a job.

        Parameters
        ----------
        job : object
            A unit of work of the engine's context.

        Returns
        -------
        object
            A hashable handle for :meth:`wait` and :meth:`result`.
        """
        raise NotImplementedError

    def wait(self, handles: list) -> list:
        """Block until at least one of ``handles`` is done.

        Parameters
        ----------
        handles : list
            Handles of :meth:`submit`.

        Returns
        -------
        list
            The handles that are done.
        """
        raise NotImplementedError

    def result(self, handle):
        """The result of a finished job.

        Parameters
        ----------
        handle : object
            A done handle.

        Returns
        -------
        object
            What the context's ``run(job)`` returned.
        """
        raise NotImplementedError

    def close(self, cancel: bool = False) -> None:
        """Stop the engine.

        Parameters
        ----------
        cancel : bool
            Stop running jobs now (their results are lost) instead of waiting for them.
        """
        pass

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        self.close(cancel=exc_type is not None)


class InlineEngine(Engine):
    """Jobs run in this process when submitted (one worker: no process to start).

    Parameters
    ----------
    context : object
    """

    name = "local"

    def __init__(self, context):
        self.context = context
        self.workers = 1

    def submit(self, job):
        return _Done(run_job(job, self.context))

    def wait(self, handles: list) -> list:
        return list(handles)

    def result(self, handle):
        return handle.table


class _Done:
    """A finished inline job (a hashable handle like a future's)."""

    __slots__ = ("table",)

    def __init__(self, table):
        self.table = table


class LocalEngine(Engine):
    """A pool of worker processes on this machine (started with 'spawn': safe with threads).

    Parameters
    ----------
    context : object
        Sent once to each worker.
    workers : int
        Processes.
    """

    name = "local"

    def __init__(self, context, workers: int):
        self.workers = workers
        self._pool = process_pool(workers, _worker_init, (context, os.getpid()))

    def submit(self, job):
        return self._pool.submit(run_job, job)

    def wait(self, handles: list) -> list:
        from concurrent.futures import FIRST_COMPLETED, wait

        done, _ = wait(handles, return_when=FIRST_COMPLETED)
        return list(done)

    def result(self, handle):
        return handle.result()

    def close(self, cancel: bool = False) -> None:
        if cancel:
            stop_pool(self._pool)
        else:
            self._pool.shutdown(wait=True)


@contextlib.contextmanager
def _signals_deferred():
    """A second SIGTERM/SIGHUP while workers are being stopped must not cut that short."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, signal.SIG_IGN) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


# Seconds to wait for a Ray cluster at --address to answer (AFFORDGRASP_RAY_CONNECT_TIMEOUT).
RAY_CONNECT_TIMEOUT_S = 15.0

# The HTTP/2 client preface and an empty SETTINGS frame: a gRPC server (Ray's GCS and its
# client server) answers with a SETTINGS frame.
_H2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + b"\x00\x00\x00\x04\x00\x00\x00\x00\x00"


def check_ray_address(address: str | None, timeout_s: float | None = None) -> None:
    """Refuse, within ``timeout_s``, a Ray address that does not answer as a Ray cluster.

    ``ray.init`` retries an unreachable or silent address for minutes inside native code,
    where it cannot even be stopped by SIGTERM; this check is a socket exchange with a
    deadline, interruptible at any time. ``auto`` and ``local`` are left to Ray.

    Parameters
    ----------
    address : str or None
        ``HOST:PORT`` or ``ray://HOST:PORT``; None, ``auto`` or ``local``: not checked.
    timeout_s : float, optional
        Seconds to wait; default ``AFFORDGRASP_RAY_CONNECT_TIMEOUT`` or 15 s.

    Raises
    ------
    InputError
        When the address is malformed, unreachable, silent or not a gRPC server.
    """
    if address is None or address.strip().lower() in ("auto", "local", ""):
        return
    if timeout_s is None:
        timeout_s = _connect_timeout()
    text = address.strip()
    if "://" in text:
        text = text.split("://", 1)[1]
    host, sep, port = text.rstrip("/").rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port.isdigit():
        raise InputError(
            f"address {address!r} is not HOST:PORT, ray://HOST:PORT or auto; give the "
            "address 'ray start --head' printed",
            parameter="address",
        )
    where = f"the Ray cluster at {address!r}"
    deadline = time.monotonic() + timeout_s
    try:
        with socket.create_connection((host, int(port)), timeout=timeout_s) as sock:
            sock.settimeout(max(0.1, deadline - time.monotonic()))
            sock.sendall(_H2_PREFACE)
            header = b""
            while len(header) < 9:
                piece = sock.recv(9 - len(header))
                if not piece:
                    break
                header += piece
    except TimeoutError:
        raise InputError(
            f"cannot reach {where}: no answer within {timeout_s:g} s; check that the cluster "
            "is running ('ray status' on its head) and reachable from here (firewall, VPN), "
            "or set AFFORDGRASP_RAY_CONNECT_TIMEOUT to wait longer"
        ) from None
    except OSError as exc:
        raise InputError(
            f"cannot reach {where}: {exc.strerror or exc}; check the host and port "
            "('ray start --head' prints them) and that the cluster is running"
        ) from None
    if len(header) < 9 or header[3] != 0x04:
        raise InputError(
            f"{where} answered, but not as a Ray cluster (no gRPC); check the port: the head's "
            "GCS port (6379 by default) or its client port with ray:// (10001)"
        )


def _connect_timeout() -> float:
    try:
        value = float(os.environ.get("AFFORDGRASP_RAY_CONNECT_TIMEOUT", ""))
    except ValueError:
        return RAY_CONNECT_TIMEOUT_S
    return value if value > 0 else RAY_CONNECT_TIMEOUT_S


def _init_with_deadline(ray, kwargs: dict) -> None:
    """``ray.init`` on a cluster, given up after the connect timeout.

    Connecting blocks in native code, which neither a deadline nor SIGTERM can interrupt,
    so it runs in a daemon thread while this thread waits in short steps: a signal is
    handled at once and a silent cluster is reported after the timeout. The abandoned
    thread does not keep the process alive.
    """
    timeout_s = _connect_timeout()
    outcome: dict = {}

    def connect() -> None:
        try:
            ray.init(**kwargs)
            outcome["ok"] = True
        except BaseException as exc:  # noqa: BLE001 - handed to the waiting thread
            outcome["error"] = exc

    thread = threading.Thread(target=connect, name="ray-connect", daemon=True)
    thread.start()
    deadline = time.monotonic() + timeout_s
    while thread.is_alive() and time.monotonic() < deadline:
        thread.join(0.1)
    if "error" in outcome:
        raise outcome["error"]
    if not outcome.get("ok"):
        raise InputError(
            f"cannot connect to the Ray cluster at {kwargs['address']!r}: no answer within "
            f"{timeout_s:g} s; check that it is running ('ray status' on its head) and "
            "reachable from here, or set AFFORDGRASP_RAY_CONNECT_TIMEOUT to wait longer"
        )


def _ray_run_job(context, job):
    keep_freed_memory()  # a Ray worker runs our jobs one after another
    return run_job(job, context)


class RayEngine(Engine):
    """Jobs as Ray tasks, one CPU each, on a local Ray or an existing cluster (``address``).

    Parameters
    ----------
    context : object
        Put in Ray's object store once.
    workers : int or None
        CPUs of a local Ray (default: every core); a cluster's CPUs otherwise.
    address : str or None
        An existing cluster; None starts a local Ray, shut down by :meth:`close`.
    """

    name = "ray"

    def __init__(self, context, workers: int | None, address: str | None):
        ray = require("ray", "cluster")
        self._ray = ray
        self._started = False
        self._reaper: Reaper | None = None
        if not ray.is_initialized():
            check_ray_address(address)
            kwargs = {"address": address, "ignore_reinit_error": True, "log_to_driver": False}
            if address is None:
                kwargs["num_cpus"] = workers or default_workers()
                kwargs["include_dashboard"] = False
            try:
                if address is None:
                    # ray.init replaces the SIGTERM handler (with sys.exit); keep ours, which
                    # stops the run the way Ctrl-C does.
                    on_term = signal.getsignal(signal.SIGTERM)
                    # Ray's agents outlive a driver killed with SIGKILL by a minute or more.
                    self._reaper = Reaper()
                    ray.init(**kwargs)
                    if threading.current_thread() is threading.main_thread():
                        signal.signal(signal.SIGTERM, on_term)
                else:
                    _init_with_deadline(ray, kwargs)
            except ConnectionError as exc:
                raise InputError(
                    f"cannot connect to the Ray cluster at {address!r}: {exc}; give the "
                    "address 'ray start --head' printed (e.g. 'ray://host:10001' or 'host:6379')"
                ) from exc
            self._started = True
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self.workers = max(1, cpus if workers is None or address is not None else workers)
        self._context_ref = ray.put(context)
        self._remote = ray.remote(num_cpus=1, max_retries=2)(_ray_run_job)

    def submit(self, job):
        return self._remote.remote(self._context_ref, job)

    def wait(self, handles: list) -> list:
        done, _ = self._ray.wait(handles, num_returns=1)
        # Take everything already finished, not only the first.
        more, _ = self._ray.wait(handles, num_returns=len(handles), timeout=0)
        return list({h: None for h in [*done, *more]})

    def result(self, handle):
        return self._ray.get(handle)

    def close(self, cancel: bool = False) -> None:
        if self._started:
            self._ray.shutdown()
        if self._reaper is not None:
            self._reaper.close()
            self._reaper = None


def check_engine(engine: str, workers: int | None, address: str | None) -> None:
    """Refuse bad engine options before any work (or any directory) is made.

    Parameters
    ----------
    engine : str
        ``"local"`` or ``"ray"``.
    workers : int or None
        At least 1 when given.
    address : str or None
        Only with ``engine="ray"``.

    Raises
    ------
    InputError
        Naming the bad parameter, or the missing ``cluster`` extra.
    """
    if engine not in ENGINES:
        raise InputError(f"unknown engine {engine!r}; choose one of: {', '.join(ENGINES)}")
    if workers is not None and (isinstance(workers, bool) or workers < 1):
        raise bad_parameter("workers", f"must be at least 1, got {workers}")
    if address is not None and engine != "ray":
        raise InputError(
            "address is for the Ray engine; set engine='ray' (--engine ray)", parameter="address"
        )
    if engine == "ray":
        try:
            require("ray", "cluster")
        except ImportError as exc:
            raise InputError(str(exc)) from None


def make_engine(
    context, *, engine: str = "local", workers: int | None = None, address: str | None = None
) -> Engine:
    """The engine asked for: ``local`` (``workers`` processes; 1: this process) or ``ray``.

    Parameters
    ----------
    context : object
    engine : str
        ``"local"`` or ``"ray"``.
    workers : int, optional
        Processes (local) or CPUs (local Ray); default: every core.
    address : str, optional
        A Ray cluster.

    Returns
    -------
    Engine
        :class:`InlineEngine`, :class:`LocalEngine` or :class:`RayEngine`; a context
        manager that closes it (cancelling on an exception).
    """
    check_engine(engine, workers, address)
    if engine == "ray":
        return RayEngine(context, workers, address)
    workers = workers or default_workers()
    if workers == 1:
        return InlineEngine(context)
    return LocalEngine(context, workers)
