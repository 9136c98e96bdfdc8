"""Ctrl-C and SIGTERM end every command with "interrupted" and the documented exit status.

A signal that arrives inside a compiled kernel surfaces as numba's ``SystemError(...
returned a result with an exception set)`` caused by the KeyboardInterrupt; the command line
must see through it. Subprocess tests send the real signals during a long ``evaluate``.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from terminal import as_in_a_terminal

import affordgrasp
from affordgrasp import cli
from affordgrasp.errors import Interrupted
from affordgrasp.runtime.interrupts import interrupt_in

SRC = Path(affordgrasp.__file__).resolve().parents[1]


def _kernel_error(cause: BaseException) -> SystemError:
    try:
        try:
            raise cause
        except KeyboardInterrupt as exc:
            raise SystemError(
                "CPUDispatcher(<function k>) returned a result with an exception set"
            ) from exc
    except SystemError as wrapped:
        return wrapped


def test_interrupt_found_through_causes_and_contexts():
    stop = KeyboardInterrupt()
    assert interrupt_in(stop) is stop
    wrapped = _kernel_error(stop)
    assert interrupt_in(wrapped) is stop
    try:
        try:
            raise stop
        except KeyboardInterrupt:
            raise ValueError("raised while handling it")  # noqa: B904 - the context is the point
    except ValueError as exc:
        assert interrupt_in(exc) is stop
    assert interrupt_in(ValueError("plain")) is None


@pytest.mark.parametrize("command", sorted(cli.COMMANDS))
@pytest.mark.parametrize(
    "raised, code",
    [
        (lambda: _kernel_error(KeyboardInterrupt()), 130),
        (lambda: _kernel_error(Interrupted(signal.SIGTERM)), 128 + signal.SIGTERM),
        (KeyboardInterrupt, 130),
    ],
    ids=["Ctrl-C in a kernel", "SIGTERM in a kernel", "Ctrl-C"],
)
def test_every_command_says_interrupted(command, raised, code, monkeypatch, capsys):
    parser = cli.build_parser()
    module = None
    for action in parser._subparsers._group_actions:  # the registered command modules
        sub = action.choices.get(command)
        if sub is not None:
            module = sub.get_default("_module")
    if module is None:
        pytest.skip(f"{command} is not available here")

    def run(args, out):
        raise raised()

    monkeypatch.setattr(module, "run", run)
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    # Any parse that reaches run(): the required positionals and options, with dummy values.
    args = _minimal_argv(parser, command)
    assert cli.main(args) == code
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"affordgrasp {command}: interrupted"), err
    assert "internal error" not in "\n".join(err)


def _minimal_argv(parser, command: str) -> list[str]:
    sub = None
    for action in parser._subparsers._group_actions:
        sub = action.choices.get(command) or sub
    argv = [command]
    for action in sub._actions:
        value = "1" if action.type in (int, float) else "x"
        if action.choices:
            value = str(next(iter(action.choices)))
        if not action.option_strings and action.dest != "help":
            argv += [value] * (1 if action.nargs in (None, "?") else 1)
        elif action.required:
            argv += [action.option_strings[0], value]
    return argv


def _start(args: list[str]) -> subprocess.Popen:
    return subprocess.Popen(
        as_in_a_terminal([sys.executable, "-m", "affordgrasp.cli", *args]),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(SRC)},
    )


def _cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_during_evaluate_kernels(tmp_path, signum):
    out = tmp_path / "rows.parquet"
    proc = _start(["evaluate", "knife", "--samples", "1000000", "--out", str(out)])
    # Past imports and kernel loading (about 3 s of CPU): the run is in the compiled kernels.
    deadline = time.monotonic() + 60
    while _cpu_seconds(proc.pid) < 5.0 and time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    assert _cpu_seconds(proc.pid) >= 5.0, "the command did not start working within 60 s"
    proc.send_signal(signum)
    # the chunk in flight finishes first: slow on a loaded machine
    _, err = proc.communicate(timeout=90)
    expected = 130 if signum == signal.SIGINT else 128 + signum
    assert proc.returncode == expected, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines[-1].startswith("affordgrasp evaluate: interrupted"), err
    assert "internal error" not in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no output, no temporary file
