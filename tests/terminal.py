"""Start a command the way a terminal does, for the Ctrl-C tests.

A command started in the background by a shell without job control inherits SIGINT ignored,
and Python keeps it so; a terminal's command has the default disposition. The tests want the
latter whatever started the test run. ``preexec_fn`` could reset it, but it runs Python in
the child between fork and exec, which can deadlock when the test process has other threads
(Ray's, a fixture's server) holding a lock at the fork: the child then hangs before it
starts. A short launcher process resets the disposition and execs the command instead.
"""

from __future__ import annotations

import sys

_LAUNCH = (
    "import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
    "os.execv(sys.argv[1], sys.argv[1:])"
)


def as_in_a_terminal(cmd: list[str]) -> list[str]:
    """``cmd`` (its first item an executable's path) run with SIGINT's default disposition."""
    return [sys.executable, "-c", _LAUNCH, *cmd]
