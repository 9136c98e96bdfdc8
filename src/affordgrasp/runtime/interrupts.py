"""Stopping a run: SIGTERM and SIGHUP handled as Ctrl-C, and interrupts seen through wrappers.

A signal that arrives while a compiled kernel runs is delivered when the kernel returns to
Python; numba's dispatcher then reports it as ``SystemError(... returned a result with an
exception set)`` whose cause is the KeyboardInterrupt. :func:`interrupt_in` finds it there, so
the command line says "interrupted" whatever layer the signal surfaced in.
"""

from __future__ import annotations

import contextlib
import signal
import threading

from ..errors import Interrupted

__all__ = ["STOP_SIGNALS", "interrupt_in", "stop_on_signals"]

STOP_SIGNALS = (signal.SIGTERM, signal.SIGHUP)


@contextlib.contextmanager
def stop_on_signals(signals=STOP_SIGNALS):
    """Within this block, SIGTERM and SIGHUP stop the run as Ctrl-C does (a context manager).

    The handler raises :class:`~affordgrasp.errors.Interrupted` (a KeyboardInterrupt) in
    the main thread, so the engine's ``close(cancel=True)`` stops the worker processes and
    the finished work is kept. Outside the main thread it does nothing (Python delivers
    signals to the main thread only).

    Parameters
    ----------
    signals : tuple of signal.Signals
        The signals handled; the previous handlers come back on exit.

    Yields
    ------
    None
        The block runs with the handlers in place.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise Interrupted(signum)

    previous = {s: signal.signal(s, handler) for s in signals}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def interrupt_in(exc: BaseException) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt (Ctrl-C or a stop signal) behind an exception, if any.

    Parameters
    ----------
    exc : BaseException
        What a run raised.

    Returns
    -------
    KeyboardInterrupt or None
        ``exc`` itself, or the first in its chain of causes and contexts.
    """
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        if isinstance(current, KeyboardInterrupt):
            return current
        seen.add(id(current))
        current = current.__cause__ or current.__context__
    return None
