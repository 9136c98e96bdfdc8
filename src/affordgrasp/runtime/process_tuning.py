"""Settings of the processes affordgrasp owns: the allocator and numpy's BLAS threads.

Only processes that affordgrasp starts call these (the command line, the local engine's
worker processes, Ray tasks of a dataset job): a program that imports the library keeps its
own settings.

**Freed memory stays in the process** (:func:`keep_freed_memory`). A dataset job allocates
and frees the same large temporary arrays batch after batch (the grasps' poses, contacts,
wrench matrices, ray hits: hundreds of kB to tens of MB each). With glibc's defaults a freed
block of that size goes back to the system (``munmap``, or a trim of the heap's top) and the
next batch's block of the same size is faulted in again, page by page, zeroed by the kernel:
on a 4000-grasp ``generate`` of the mug, about 100,000 page faults and 0.3-0.5 s of system
time out of 4.5 s of CPU. Raising glibc's mmap threshold to its largest allowed value (32 MB
with 64-bit pointers) and its trim threshold to 256 MB lets those blocks come from the heap
and stay there between batches: 29,000 page faults (most of them start-up's), 0.1-0.2 s of
system time, and a peak resident memory 5 % higher on the mug (286 -> 301 MB), lower on the
tools (knife 327 -> 279 MB). Elsewhere than glibc (macOS, musl) nothing changes.

**One BLAS thread** (:func:`one_blas_thread`). A worker is one core (``--workers N`` runs N
of them); numpy's OpenBLAS would start a thread per core in each, and its idle threads spin
after every call: about 0.1 s of CPU at numpy's import and 0.2-0.4 s over the same
4000-grasp job, for matrix products far too small to gain from threads. The command line
sets ``OPENBLAS_NUM_THREADS=1`` before numpy is imported, unless it is already set (set it
to run numpy's BLAS on more threads); the worker processes inherit it.
"""

from __future__ import annotations

import os
import sys

__all__ = ["MMAP_THRESHOLD", "TRIM_THRESHOLD", "keep_freed_memory", "one_blas_thread"]

# glibc's mallopt parameters (malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
# glibc refuses an mmap threshold above half its largest heap: 32 MB with 64-bit pointers
MMAP_THRESHOLD = 32 * 1024 * 1024
TRIM_THRESHOLD = 256 * 1024 * 1024

_done: bool | None = None


def keep_freed_memory() -> bool:
    """Ask glibc to serve blocks below 32 MB from the heap and to keep up to 256 MB of free
    memory at its top (once per process; later calls return the first answer).

    Returns
    -------
    bool
        Whether both settings were taken (False off glibc, where nothing changes).
    """
    global _done
    if _done is None:
        _done = _set_glibc_thresholds()
    return _done


def _set_glibc_thresholds() -> bool:
    if not sys.platform.startswith("linux"):
        return False
    import ctypes

    try:
        glibc = os.confstr("CS_GNU_LIBC_VERSION")  # "glibc 2.36"; musl has none
    except (ValueError, OSError):
        return False
    if not glibc or not glibc.startswith("glibc"):
        return False
    try:
        libc = ctypes.CDLL("libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    # mallopt returns 1 on success, 0 on a refused value
    return bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(
        mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    )


def one_blas_thread() -> bool:
    """Hold numpy's OpenBLAS to one thread in this process and those it starts, unless
    ``OPENBLAS_NUM_THREADS`` is already set. Effective only before numpy is imported.

    Returns
    -------
    bool
        Whether this call set it.
    """
    if "OPENBLAS_NUM_THREADS" in os.environ:
        return False
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    return True
