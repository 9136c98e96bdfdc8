"""Worker processes that end with the process that started them, ``kill -9`` included.

A pool's workers are normally stopped by their parent; a parent killed with SIGKILL cannot do
that, and its workers (hundreds of MB each) would run on. :func:`die_with_parent`, called in
each worker's initializer, asks Linux to send the worker SIGKILL when its parent dies
(``prctl(PR_SET_PDEATHSIG)``) and, as a fallback where that is unavailable (other systems) or
does not apply (the parent thread that started the worker ended before the parent did),
starts a daemon thread that checks the parent's id twice a second and ends the worker when
the parent is gone.

Processes that are not ours to initialise (a local Ray's GCS, raylet and agents: Ray's agents
outlive a driver killed with SIGKILL by a minute or more, waiting on the dead GCS) are covered
by :class:`Reaper`: a small stdlib-only process that notes the parent's descendants twice a
second and, when the parent dies without saying goodbye, kills the ones it noted (Linux: it
reads ``/proc``; elsewhere it is not started).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading

__all__ = ["WATCH_INTERVAL_S", "Reaper", "die_with_parent"]

WATCH_INTERVAL_S = 0.5
_PR_SET_PDEATHSIG = 1


def _set_parent_death_signal(signum: int) -> bool:
    """``prctl(PR_SET_PDEATHSIG, signum)`` through ctypes; False where unavailable."""
    if not sys.platform.startswith("linux"):
        return False
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(signum), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch(parent_pid: int, interval: float) -> None:
    event = threading.Event()
    while not event.wait(interval):
        if os.getppid() != parent_pid:
            os._exit(128 + signal.SIGKILL)


def die_with_parent(parent_pid: int, interval: float = WATCH_INTERVAL_S) -> bool:
    """Make this (worker) process end when the process ``parent_pid`` ends.

    Parameters
    ----------
    parent_pid : int
        The parent's process id, as the parent saw it (``os.getpid()`` there).
    interval : float
        Seconds between the watchdog thread's checks.

    Returns
    -------
    bool
        Whether the kernel's parent-death signal was set (the watchdog runs either way).
    """
    armed = _set_parent_death_signal(signal.SIGKILL)
    # The parent may have died before the signal was armed: then nothing would send it.
    if os.getppid() != parent_pid:
        os._exit(128 + signal.SIGKILL)
    thread = threading.Thread(
        target=_watch, args=(parent_pid, interval), name="parent-watchdog", daemon=True
    )
    thread.start()
    return armed


# The reaper's program: stdlib only (it must start in milliseconds and import nothing of ours).
# argv: parent pid, interval. stdin: a pipe whose write end only the parent holds; a "q" on it
# means a normal goodbye, EOF without one means the parent died.
_REAPER_SOURCE = r"""
import os, select, signal, sys, time
parent, interval = int(sys.argv[1]), float(sys.argv[2])
signal.signal(signal.SIGINT, signal.SIG_IGN)
me = os.getpid()

def table():
    kids = {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open("/proc/" + name + "/stat", "rb") as f:
                fields = f.read().rsplit(b")", 1)[1].split()
        except OSError:
            continue
        kids.setdefault(int(fields[1]), []).append((int(name), fields[19]))
    return kids

def descendants(roots):
    kids, found, todo = table(), {}, list(roots)
    while todo:
        for pid, start in kids.get(todo.pop(), ()):
            if pid != me and pid not in found:
                found[pid] = start
                todo.append(pid)
    return found

def start_of(pid):
    try:
        with open("/proc/%d/stat" % pid, "rb") as f:
            return f.read().rsplit(b")", 1)[1].split()[19]
    except OSError:
        return None

noted = {}
while True:
    ready, _, _ = select.select([0], [], [], interval)
    if ready:
        if os.read(0, 1) == b"q":
            sys.exit(0)
        break
    noted.update(descendants([parent]))
    noted = {p: s for p, s in noted.items() if start_of(p) == s}
# The parent is gone: its noted descendants, and theirs, as they are now.
victims = {p: s for p, s in noted.items() if start_of(p) == s}
victims.update(descendants(list(victims)))
for pid, start in victims.items():
    if start_of(pid) == start:
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
"""


class Reaper:
    """Kill this process's descendants when it dies without :meth:`close` (``kill -9``).

    Starts a watcher process (stdlib only, its own session so that Ctrl-C in a terminal does
    not reach it) that notes this process's descendants every ``interval`` seconds from
    ``/proc``. Closing says goodbye and the watcher leaves everything alone; if this process
    dies first, the kernel closes the pipe between them, and the watcher kills every noted
    process that still runs (matched by start time, so a recycled process id is spared),
    with its own descendants. Processes started less than ``interval`` before the death may
    be missed. Linux only: elsewhere (no ``/proc``) nothing is started.

    Parameters
    ----------
    interval : float
        Seconds between the watcher's looks at the process tree.
    """

    def __init__(self, interval: float = WATCH_INTERVAL_S):
        self._write: int | None = None
        self._process: subprocess.Popen | None = None
        if not sys.platform.startswith("linux") or not os.path.isdir("/proc/self"):
            return
        read, write = os.pipe()
        try:
            self._process = subprocess.Popen(
                [sys.executable, "-S", "-c", _REAPER_SOURCE, str(os.getpid()), str(interval)],
                stdin=read,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                start_new_session=True,
                close_fds=True,
            )
        except OSError:
            os.close(write)
            return
        finally:
            os.close(read)
        os.set_inheritable(write, False)
        self._write = write

    @property
    def running(self) -> bool:
        """Whether a watcher was started and has not been closed."""
        return self._write is not None

    def close(self) -> None:
        """Say goodbye: the watcher ends and kills nothing."""
        if self._write is None:
            return
        try:
            os.write(self._write, b"q")
        except OSError:
            pass
        os.close(self._write)
        self._write = None
        if self._process is not None:
            try:
                self._process.wait(timeout=5)
            except subprocess.TimeoutExpired:  # pragma: no cover - a stuck watcher
                self._process.kill()
            self._process = None
