"""SIGTERM and SIGHUP stop `generate` cleanly: no worker left running, resumable; a Ray
address that does not answer is an error within the connect timeout, and SIGTERM works
while connecting."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from dataset_support import SEED

import affordgrasp
from affordgrasp.dataset.reading import read_dataset
from affordgrasp.dataset.shards import plan_shards, shard_paths
from affordgrasp.errors import InputError
from affordgrasp.runtime.engines import check_ray_address

# The folder the tests import affordgrasp from (the installed package in CI, src/ in a
# checkout): a subprocess must run the same build, with the same compiled kernels.
SRC = Path(affordgrasp.__file__).resolve().parents[1]


def _start(args: list[str], **env) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "affordgrasp.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, like a shell job
        env={**os.environ, "PYTHONPATH": str(SRC), **env},
    )


def _children(pid: int) -> list[int]:
    """Every descendant of ``pid`` (from /proc, no extra dependency)."""
    parents: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parents.setdefault(int(fields[1]), []).append(int(entry))
    found, todo = [], [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.parametrize(
    "signum, to_group",
    [(signal.SIGTERM, False), (signal.SIGHUP, True)],
    ids=["SIGTERM to the process", "SIGHUP to the process group"],
)
def test_signal_stops_the_workers_and_the_run_resumes(tmp_path, box_mesh, signum, to_group):
    out = tmp_path / "ds"
    args = ["generate", str(box_mesh), "--samples", "256", "--out", str(out)]
    args += ["--seed", str(SEED), "--shard-size", "8", "--chunk-size", "8", "--workers", "2"]
    proc = _start(args)
    deadline = time.monotonic() + 120
    workers: list[int] = []
    while time.monotonic() < deadline:
        workers = [p for p in _children(proc.pid) if _alive(p)]
        if len(workers) >= 2 and shard_paths(out) if out.exists() else False:
            break
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.02)
    else:
        pytest.fail("the workers did not start in time")
    workers = _children(proc.pid)
    # Frozen while the signal is sent, so that it lands mid-run however fast the machine is.
    os.killpg(proc.pid, signal.SIGSTOP)
    assert len(shard_paths(out)) < len(plan_shards(1, 256, 8))
    if to_group:
        os.killpg(proc.pid, signum)
    else:
        os.kill(proc.pid, signum)
    os.killpg(proc.pid, signal.SIGCONT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signum, err
    assert signal.Signals(signum).name in err and "Run the same command" in err
    deadline = time.monotonic() + 10
    while any(_alive(p) for p in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not [p for p in workers if _alive(p)], "worker processes outlived generate"
    card = json.loads((out / "_card.json").read_text())
    assert card["complete"] is False
    if signum != signal.SIGTERM:
        return  # resuming is the same path whatever stopped the run: checked once

    again = _start([*args, "--json"])
    stdout, err = again.communicate(timeout=300)
    assert again.returncode == 0, err
    summary = json.loads(stdout)
    assert summary["complete"]
    assert summary["shards_skipped"] + summary["shards_written"] == len(plan_shards(1, 256, 8))
    assert read_dataset(out)["sample"].to_pylist() == list(range(256))


def test_workers_end_when_generate_is_killed(tmp_path, box_mesh):
    """kill -9 of generate: its workers (parent-death signal, or watchdog) end within 5 s."""
    out = tmp_path / "ds"
    args = ["generate", str(box_mesh), "--samples", "4096", "--out", str(out)]
    args += ["--seed", str(SEED), "--shard-size", "8", "--chunk-size", "8", "--workers", "2"]
    proc = _start(args)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if len([p for p in _children(proc.pid) if _alive(p)]) >= 2 and out.exists():
            if shard_paths(out):
                break
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.02)
    else:
        pytest.fail("the workers did not start in time")
    workers = [p for p in _children(proc.pid) if _alive(p)]
    proc.kill()  # SIGKILL: no handler runs in the parent
    proc.communicate(timeout=30)
    killed = time.monotonic()
    while any(_alive(p) for p in workers) and time.monotonic() < killed + 5:
        time.sleep(0.05)
    left = [p for p in workers if _alive(p)]
    for pid in left:  # do not leave them to the next test
        os.kill(pid, signal.SIGKILL)
    assert not left, f"{len(left)} of {len(workers)} workers outlived their parent by 5 s"


def test_die_with_parent_arms_the_parent_death_signal():
    """In a child process: the kernel's parent-death signal is set to SIGKILL."""
    code = (
        "import ctypes, os, signal\n"
        "from affordgrasp.runtime.worker_lifetime import die_with_parent\n"
        "assert die_with_parent(os.getppid())\n"
        "libc = ctypes.CDLL(None)\n"
        "sig = ctypes.c_int()\n"
        "assert libc.prctl(2, ctypes.byref(sig), 0, 0, 0) == 0\n"  # PR_GET_PDEATHSIG
        "print(sig.value)\n"
    )
    if not sys.platform.startswith("linux"):
        pytest.skip("PR_SET_PDEATHSIG is Linux only (the watchdog covers other systems)")
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(SRC)},
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert int(done.stdout) == signal.SIGKILL


@pytest.fixture
def silent_server():
    """A TCP port that accepts connections and never says a word (not a Ray cluster)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    held = []

    def accept():
        while True:
            try:
                held.append(server.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    yield f"127.0.0.1:{server.getsockname()[1]}"
    server.close()
    for c in held:
        c.close()


def test_ray_address_checks():
    with pytest.raises(InputError, match="Connection refused"):
        check_ray_address("127.0.0.1:1", 5)
    with pytest.raises(InputError, match="not HOST:PORT"):
        check_ray_address("no-port-here", 5)
    check_ray_address("auto", 0.1)  # left to Ray


def test_silent_ray_address_times_out_with_a_clear_error(silent_server):
    started = time.monotonic()
    with pytest.raises(InputError, match=r"no answer within 1 s.*AFFORDGRASP_RAY_CONNECT_TIMEOUT"):
        check_ray_address(silent_server, 1)
    assert time.monotonic() - started < 5


def test_generate_on_a_silent_ray_address_exits_2_then_obeys_sigterm(
    tmp_path, box_mesh, silent_server
):
    pytest.importorskip("ray")
    args = ["generate", str(box_mesh), "--samples", "8", "--engine", "ray"]
    args += ["--address", silent_server, "--out", str(tmp_path / "ds")]
    started = time.monotonic()
    proc = _start(args, AFFORDGRASP_RAY_CONNECT_TIMEOUT="2")
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2, err
    assert "no answer within 2 s" in err and silent_server in err
    assert time.monotonic() - started < 60

    # A long timeout: SIGTERM while it waits for the cluster stops it at once, cleanly.
    out = tmp_path / "ds2"
    proc = _start([*args[:-1], str(out)], AFFORDGRASP_RAY_CONNECT_TIMEOUT="600")
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (out / "_manifest.json").exists():
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    signalled = time.monotonic()
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert "stopped by SIGTERM" in err
    assert time.monotonic() - signalled < 15


_REAPED_PARENT = (
    "import subprocess, sys, time\n"
    "from affordgrasp.runtime.worker_lifetime import Reaper\n"
    "reaper = Reaper(interval=0.1)\n"
    "assert reaper.running\n"
    # Its own session: a child that would survive its parent (and any group kill).
    "child = subprocess.Popen(['sleep', '60'], start_new_session=True)\n"
    "time.sleep(0.5)\n"  # the watcher has noted it
    "print(child.pid, flush=True)\n"
    "if sys.argv[1] == 'close':\n"
    "    reaper.close()\n"
    "    sys.exit(0)\n"
    "time.sleep(60)\n"
)


def _reaped_parent(mode: str) -> tuple[subprocess.Popen, int]:
    if not sys.platform.startswith("linux"):
        pytest.skip("the reaper reads /proc (Linux only)")
    proc = subprocess.Popen(
        [sys.executable, "-c", _REAPED_PARENT, mode],
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(SRC)},
    )
    line = proc.stdout.readline()
    assert line.strip().isdigit(), proc.communicate(timeout=30)
    return proc, int(line)


def test_reaper_kills_the_descendants_of_a_killed_parent():
    """kill -9 of a parent with a Reaper: a detached child of it ends within 5 s."""
    proc, child = _reaped_parent("wait")
    try:
        proc.kill()
        proc.communicate(timeout=30)
        killed = time.monotonic()
        while _alive(child) and time.monotonic() < killed + 5:
            time.sleep(0.05)
        assert not _alive(child), "the child outlived its killed parent by 5 s"
    finally:
        if _alive(child):
            os.kill(child, signal.SIGKILL)


def test_reaper_closed_leaves_children_alone():
    """A parent that closes its Reaper and exits: the watcher kills nothing."""
    proc, child = _reaped_parent("close")
    try:
        assert proc.wait(timeout=30) == 0
        time.sleep(0.5)
        assert _alive(child), "a closed reaper killed a child"
    finally:
        if _alive(child):
            os.kill(child, signal.SIGKILL)
