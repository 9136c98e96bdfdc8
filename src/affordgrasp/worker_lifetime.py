"""Worker processes that end with the process that started them, ``kill -9`` included.

A pool's workers are normally stopped by their parent; a parent killed with SIGKILL cannot do
that, and its workers (hundreds of MB each) would run on. :func:`die_with_parent`, called in
each worker's initializer, asks Linux to send the worker SIGKILL when its parent dies
(``prctl(PR_SET_PDEATHSIG)``) and, as a fallback where that is unavailable (other systems) or
does not apply (the parent thread that started the worker ended before the parent did),
starts a daemon thread that checks the parent's id twice a second and ends the worker when
the parent is gone.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

__all__ = ["WATCH_INTERVAL_S", "die_with_parent"]

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
